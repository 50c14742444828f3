"""Driver of the contact-regime model (quasi-static shoes, see :mod:`model.quasi_static`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from brake_sim_ros.errors import FidelityError, SimulationError
from brake_sim_ros.model import layout as L
from brake_sim_ros.model import quasi_static as Q
from brake_sim_ros.model.assembly import indentation_at, pack
from brake_sim_ros.model.catalogue import KIND_BY_NAME
from brake_sim_ros.model.fidelity import GROWTH_LEVELS, defect_levels, levels_representing
from brake_sim_ros.model.run_setup import BrakeSetup, SampleBlock
from brake_sim_ros.solvers.kernel_parts import ensure_compiled, register

SAMPLE_COLUMNS: tuple[str, ...] = (*L.COLUMNS, "braking_torque_n_m")
# Macro step of the contact-regime model. With the torsional coupling: this many steps per
# period of the torsional mode (RK4 phase error per period about (w h)^4 / 120, below 1e-5
# at 32 steps). Rigid: the rotor has no mode; the step only follows the actuation history.
STEPS_PER_TORSIONAL_PERIOD = {"fast": 16, "balanced": 32, "accurate": 64}
RIGID_STEP_S = {"fast": 8e-3, "balanced": 4e-3, "accurate": 1e-3}
SOLVER_MESSAGES = {
    Q.STATUS_SELF_LOCKING: (
        "a shoe is self-locking (its friction moment beats the contact moment): no"
        " quasi-static equilibrium exists; run this scenario with an impact level"
    ),
    Q.STATUS_NO_CONVERGENCE: "the shoe balance did not converge",
    Q.STATUS_NON_FINITE: "non-finite rotor state",
}


@dataclass(frozen=True)
class ContactRegimeResult:
    """A contact-regime run.

    Attributes:
        samples: rows of :data:`SAMPLE_COLUMNS`, one per macro step.
        stop_time_s: lock instant, s (None if the drum did not stop).
        n_steps: macro steps; n_substeps: RK4 steps actually taken (more near standstill).
        step_s: macro step, s.
    """

    samples: SampleBlock
    stop_time_s: float | None
    n_steps: int
    n_substeps: int
    step_s: float


def macro_step(setup: BrakeSetup, accuracy: str | None = None) -> float:
    """Macro step of the contact-regime model for ``setup``, s."""
    preset = accuracy or "balanced"
    if setup.options.rigid_coupling:
        return RIGID_STEP_S[preset]
    d = setup.params.driveline
    i_red = d.flywheel_inertia_kg_m2 * d.drum_inertia_kg_m2
    i_red /= d.flywheel_inertia_kg_m2 + d.drum_inertia_kg_m2
    period = 2.0 * math.pi / math.sqrt(d.coupling_stiffness_n_m_per_rad / i_red)
    return period / STEPS_PER_TORSIONAL_PERIOD[preset]


def touch_angle(p: np.ndarray, base: int, start_rad: float) -> float:
    """Shoe angle (rad) at which the lining first touches the drum, turning out from start."""
    hi = max(start_rad, 0.0) + 1e-3
    while indentation_at(p, base, hi) <= 0.0:
        hi += 2.0 * (hi - start_rad)
        if hi > 1.0:
            raise SimulationError("the lining never reaches the drum within 1 rad of travel")
    return float(brentq(lambda th: indentation_at(p, base, th), start_rad, hi, xtol=1e-15))


def run_contact_regime(
    setup: BrakeSetup, duration_s: float, *, accuracy: str | None = None
) -> ContactRegimeResult:
    """Integrate the contact-regime model of ``setup`` over ``[0, duration_s)``.

    Raises:
        FidelityError: ``setup`` has a defect the contact-regime levels cannot represent
            (an out-of-round drum: :attr:`brake_sim_ros.model.catalogue.DefectKind.levels`).
    """
    for defect in setup.defects.kinds:
        if "contact_regime" not in defect_levels(defect):
            raise FidelityError(
                f"the contact-regime model cannot represent the defect {defect!r}"
                f" ({KIND_BY_NAME[defect].description}): allowed levels for it:"
                f" {levels_representing(defect)}"
            )
    if not setup.defects.is_static:
        raise FidelityError(
            f"the contact-regime model cannot represent the defect"
            f" {setup.defects.growing_kinds[0]!r} changing during the run (an onset after"
            f" 0 s or a growth law): allowed levels for it: {sorted(GROWTH_LEVELS)}"
        )
    ensure_compiled(parts=("contact-regime",))  # compiled at first use, saying how far
    p = pack(setup.params, setup.defects, setup.options)
    h = macro_step(setup, accuracy)
    n = max(1, round(duration_s / h))
    starts = (
        math.radians(setup.defects.left.initial_angle_deg),
        math.radians(setup.defects.right.initial_angle_deg),
    )
    bases = (L.P_SHOE_BASE, L.P_SHOE_BASE + L.SHOE_STRIDE)
    touch = np.array([touch_angle(p, b, s) for b, s in zip(bases, starts, strict=True)])
    shoes = np.array([starts[0], starts[1], 0.0, 0.0])  # angles, then slopes (none yet)
    y = np.zeros(Q.N_ROTOR)
    y[Q.R_FLY_SPEED] = y[Q.R_DRUM_SPEED] = setup.params.driveline.initial_speed_rad_s
    kstate = np.zeros(4, np.int64)  # stuck, status, substeps, breakaways
    fstate = np.zeros(L.N_FSTATE)
    fstate[L.F_STOP_TIME] = -1.0
    fstate[L.F_WHEEL_LOCK_TIME] = -1.0
    out = np.empty((n, Q.N_SAMPLE_COLUMNS))
    tl, fl, tr, fr = setup.actuation.as_arrays()
    cache = np.zeros((2, Q.N_CACHE))
    rows = Q.advance(y, 0, h, n, p, tl, fl, tr, fr, touch, shoes, cache, kstate, fstate, out)
    if kstate[1] != Q.STATUS_OK:
        raise SimulationError(
            f"contact-regime model failed at t = {(rows - 1) * h:.4f} s:"
            f" {SOLVER_MESSAGES[int(kstate[1])]}"
        )
    return ContactRegimeResult(
        samples=SampleBlock(out, 0, h, SAMPLE_COLUMNS),
        stop_time_s=float(fstate[L.F_STOP_TIME]) if fstate[L.F_STOP_TIME] >= 0.0 else None,
        n_steps=n,
        n_substeps=int(kstate[2]),
        step_s=h,
    )


def _compile_part() -> None:
    """The contact-regime levels' quasi-static shoes, compiled on a tiny event
    (:mod:`brake_sim_ros.solvers.warmup`)."""
    run_contact_regime(BrakeSetup(), 0.01)


# compiled at first use, not at set-up (its ensure_compiled call above)
register("contact-regime", "contact-regime levels", _compile_part)
