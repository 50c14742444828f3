"""Pose-rule study: how a shoe sits when its pin is moved radially, and what each rule does
to case 1 (left pin 3 % outward) and the pivot sweep (issue 28, "Also: case 1 ...").

Run it with ``python -m brake_sim_ros.studies.pose_rule_study`` (seconds): every rule at the
parameters in force for the left pin moved -3 and +3 % (``--pcts -3 -2 -1 1 2 3`` for the
sweep, ``--crown-mm`` for a crowned lining). ``--sample N`` draws ``N`` geometries from the
calibration's space (:mod:`.pose_rule_sample`; 1500: about 4 minutes of CPU), keeps those
whose symmetric first impact and case 5 are in their bands, judges case 1 under each rule
there, and for every geometry that brings case 1 into its bands prints the rest of the
calibration's figures and the left shoe's sweep. Nothing in the library imports it.

A rigid shoe in the plane has three degrees of freedom; at rest three contacts hold it, so
a pose rule is a statement of which three. Each rule places the LEFT shoe for a pin moved
radially by ``pct`` % of its distance from the drum centre (the right shoe is its mirror
image, as in the model):

* ``tip-abutment`` (a model's rule, ``ShoeGeometry.pose``, the service brake's; the study
  brake's until issue 28; :func:`.placement.place_shoe`): the tip held both ways
  by the piston and the slot in its end, the heel in a seat open along the tip-pin line:
  the body turns about the tip.
* ``carried``: the heel in a closed eye on the pin (two contacts), the turn held by a stop
  that a radial pin shift slides along (an adjuster cam bearing radially on the web
  90 deg from the pin): the whole shoe moves with its pin; the piston follows the tip
  (a hydraulic piston is not a stop: the return spring holds the tip on it).
* ``eye-piston`` (the other of the model's rules, the study brake's): the heel in an eye on
  the pin, the tip on a piston held on its stop
  along its axis (the tip slides across it in the slot): the shoe turns about the moved
  pin until its tip is back on the piston.
* ``eye-adjuster@A``: the heel in an eye on the pin, the web on an adjuster (a cam or
  stop fixed to the backing plate) bearing radially at polar angle ``A`` deg: the shoe
  moves with its pin and turns about it until the web is back on the adjuster.
  ``eye-adjuster@155`` (the stop 90 deg from the pin) is ``carried``.

A lining may also be ``crowned``: ground to a radius ``crown_mm`` smaller than the drum's
less the clearance, centred so that it still first touches in the middle of its arc with
the running clearance (a cam-ground, "centre-contact" lining). ``crown_mm = 0`` is the
model's concentric lining.

The figures are computed as :mod:`.calibration` computes them (first two impacts by
``rk4-located`` at 20 us, the same metrics as the validation report).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from unittest import mock

import numpy as np
from scipy.optimize import brentq

from brake_sim_ros.analysis.impacts import shoe_metrics
from brake_sim_ros.model import growth
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import contact_arms, indentation_at, pack
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.placement import lining_mid_rad
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.solvers import fixed_step
from brake_sim_ros.studies.calibration import IMPACT_SPAN_S, IMPACT_STEP_S
from brake_sim_ros.studies.validation_checks import BANDS, PUBLISHED_CASES


@dataclass(frozen=True)
class Pose:
    """The left shoe's assembled geometry (backing-plate frame, m, rad, kg m^2)."""

    pivot: tuple[float, float]
    lining_centre: tuple[float, float]
    lining_mid_rad: float
    mass_centre: tuple[float, float]
    inertia_kg_m2: float
    tip: tuple[float, float]


def _rotate(point: tuple[float, float], about: tuple[float, float], turn: float):
    c, s = math.cos(turn), math.sin(turn)
    dx, dy = point[0] - about[0], point[1] - about[1]
    return about[0] + c * dx - s * dy, about[1] + s * dx + c * dy


def nominal_pose(params: BrakeParameters) -> Pose:
    """The left shoe as the parameters assemble it, no pin moved."""
    g = params.shoe
    return Pose(
        g.pivot_xy_m,
        (0.0, 0.0),
        lining_mid_rad(params),
        (g.mass_centre_x_m, g.mass_centre_y_m),
        g.inertia_about_pivot_kg_m2,
        (g.tip_x_m, g.tip_y_m),
    )


def _moved(pose: Pose, params: BrakeParameters, shift: tuple[float, float], turn: float) -> Pose:
    """``pose`` translated by ``shift`` (m), then turned by ``turn`` (rad, outward positive
    for the left shoe: counter-clockwise) about its translated pin."""
    q = (pose.pivot[0] + shift[0], pose.pivot[1] + shift[1])

    def place(pt: tuple[float, float]) -> tuple[float, float]:
        return _rotate((pt[0] + shift[0], pt[1] + shift[1]), q, turn)

    g = params.shoe
    mc = place(pose.mass_centre)
    arm0 = (pose.mass_centre[0] - pose.pivot[0]) ** 2 + (pose.mass_centre[1] - pose.pivot[1]) ** 2
    arm1 = (mc[0] - q[0]) ** 2 + (mc[1] - q[1]) ** 2
    return Pose(
        q,
        place(pose.lining_centre),
        pose.lining_mid_rad + turn,
        mc,
        pose.inertia_kg_m2 + g.mass_kg * (arm1 - arm0),
        place(pose.tip),
    )


def _model_rule(params: BrakeParameters, pct: float, pose: int) -> Pose:
    """The model's placement (:func:`.placement.place_shoe`) by its rule ``pose``
    (``layout.POSE_*``), whatever ``params``' own pose."""
    g = params.shoe
    px, py = g.pivot_xy_m
    qx, qy, cx, cy, mid, mx, my, inertia, tx, ty, _turn, _seat = growth.shoe_placement.py_func(
        pct / 100.0,
        1.0,
        pose,
        px,
        py,
        g.tip_x_m,
        g.tip_y_m,
        g.mass_centre_x_m,
        g.mass_centre_y_m,
        g.inertia_about_pivot_kg_m2,
        g.mass_kg,
        lining_mid_rad(params),
    )
    return Pose((qx, qy), (cx, cy), mid, (mx, my), inertia, (tx, ty))


def tip_abutment(params: BrakeParameters, pct: float) -> Pose:
    """The model's tip abutment."""
    return _model_rule(params, pct, L.POSE_TIP_ABUTMENT)


def _pin_shift(params: BrakeParameters, pct: float) -> tuple[float, float]:
    px, py = params.shoe.pivot_xy_m
    return px * pct / 100.0, py * pct / 100.0


def held_by_stop(
    params: BrakeParameters, pct: float, point: tuple[float, float], normal: tuple[float, float]
) -> Pose:
    """Heel in an eye on the moved pin; the shoe turned about it until the body point that
    rested at ``point`` is back on a stop whose face has the unit ``normal`` (m, 1)."""
    nominal = nominal_pose(params)
    shift = _pin_shift(params, pct)
    q = (nominal.pivot[0] + shift[0], nominal.pivot[1] + shift[1])
    moved = (point[0] + shift[0], point[1] + shift[1])
    target = point[0] * normal[0] + point[1] * normal[1]

    def miss(turn: float) -> float:
        x, y = _rotate(moved, q, turn)
        return x * normal[0] + y * normal[1] - target

    turn = 0.0 if miss(0.0) == 0.0 else brentq(miss, -0.3, 0.3, xtol=1e-15)
    return _moved(nominal, params, shift, turn)


def carried(params: BrakeParameters, pct: float) -> Pose:
    """The whole shoe moves with its pin."""
    return _moved(nominal_pose(params), params, _pin_shift(params, pct), 0.0)


def eye_piston(params: BrakeParameters, pct: float) -> Pose:
    """The model's heel in an eye, tip back on the piston's axis position (its stop):
    :func:`held_by_stop` with the tip on a stop facing -x, in closed form."""
    return _model_rule(params, pct, L.POSE_EYE_PISTON)


def eye_adjuster(angle_deg: float) -> Callable[[BrakeParameters, float], Pose]:
    """Heel in an eye, web on an adjuster bearing radially at polar angle ``angle_deg``."""
    a = math.radians(angle_deg)

    def rule(params: BrakeParameters, pct: float) -> Pose:
        r = params.shoe.drum_radius_m - 0.030  # on the web; the radius does not matter
        return held_by_stop(
            params, pct, (r * math.cos(a), r * math.sin(a)), (math.cos(a), math.sin(a))
        )

    return rule


RULES: dict[str, tuple[Callable[[BrakeParameters, float], Pose], str]] = {
    "tip-abutment": (tip_abutment, "tip on the piston both ways, heel sliding in its seat"),
    "carried": (carried, "heel eye on the pin, adjuster 90 deg from the pin (slides)"),
    "eye-piston": (eye_piston, "heel eye on the pin, tip on the piston's stop along its axis"),
    "eye-adjuster@125": (eye_adjuster(125.0), "heel eye, adjuster on the web at 125 deg"),
    "eye-adjuster@135": (eye_adjuster(135.0), "heel eye, adjuster on the web at 135 deg"),
    "eye-adjuster@175": (eye_adjuster(175.0), "heel eye, adjuster on the web at 175 deg"),
}


def packed(params: BrakeParameters, pose: Pose, crown_mm: float = 0.0, **defect) -> np.ndarray:
    """The packed parameters of the brake with the left shoe at ``pose`` (``defect``: the
    left shoe's other defects), its lining crowned by ``crown_mm``."""
    p = pack(params, Defects(left=ShoeDefect(**defect)))
    b = L.P_SHOE_BASE
    cx, cy = pose.lining_centre
    if crown_mm:
        # the crowned arc's centre sits toward the middle of the lining by the crown, so that
        # the middle keeps the clearance
        k = crown_mm * 1e-3
        cx += k * math.cos(pose.lining_mid_rad)
        cy += k * math.sin(pose.lining_mid_rad)
        for side in range(2):
            p[L.P_SHOE_BASE + side * L.SHOE_STRIDE + L.S_LINING_RADIUS] -= k
        right = L.P_SHOE_BASE + L.SHOE_STRIDE
        p[right + L.S_LINING_CENTRE_X] -= k * math.cos(lining_mid_rad(params))
        p[right + L.S_LINING_CENTRE_Y] += k * math.sin(lining_mid_rad(params))
    growth.write_placement.py_func(
        p,
        b,
        *pose.pivot,
        cx,
        cy,
        pose.lining_mid_rad,
        *pose.mass_centre,
        pose.inertia_kg_m2,
        *pose.tip,
    )
    return p


@dataclass(frozen=True)
class Geometry:
    """Where the left shoe first touches, and whether it may be assembled so."""

    gap_angle_rad: float  # shoe angle at first contact
    contact_deg: float  # polar angle of the first contact
    rest_gap_mm: float  # smallest lining-drum gap at rest (negative: inside the drum)
    self_locking_mu: float  # d / h at the first contact


def geometry(p: np.ndarray) -> Geometry:
    b = L.P_SHOE_BASE
    rest = -indentation_at(p, b, 0.0) * 1e3
    arms = contact_arms(p, b, 0.0)
    if arms is None:
        return Geometry(math.nan, math.nan, rest, math.nan)
    from brake_sim_ros.model import kernel

    out = kernel.shoe_eval(p, b, arms.onset_angle_rad, 0.0, 0.0, 0.0, L.CONTACT_ON)
    return Geometry(
        arms.onset_angle_rad,
        math.degrees(math.atan2(out[8], out[7])) % 360.0,
        rest,
        arms.self_locking_coefficient,
    )


@contextmanager
def packed_as(p: np.ndarray) -> Iterator[None]:
    """Within it, every fixed-step stepper built runs on ``p`` instead of its setup's
    own packing (the study's placement; nothing else of the setup changes)."""
    # the fixed-step stepper packs its setup itself; the study hands it the shoe placed by
    # another rule (the step limit is computed on this vector as well)
    with mock.patch.object(fixed_step, "_packed", lambda setup: p.copy()):
        yield


def impact(p: np.ndarray, defect: dict) -> tuple[float, float, float]:
    """(actuation at first impact N, peak |F_pivot| N, period s) of the left shoe."""
    setup = BrakeSetup(defects=Defects(left=ShoeDefect(**defect)))
    with packed_as(p):
        stepper = fixed_step.FixedStepStepper(setup, IMPACT_STEP_S, check_step=False)
    m = shoe_metrics(stepper.run(IMPACT_SPAN_S), "left", stop_time_s=None)
    return m.first_impact_actuation_n, m.first_impact_peak_n, m.period_s


def pct_change(v: float, base: float) -> float:
    """Change of ``v`` against ``base``, %."""
    return 100.0 * (v / base - 1.0)


def shape(values: list[float], pcts: list[float]) -> str:
    """'monotone', 'both ends the same way' (the largest shifts either way move the figure
    the same way: an even, kinked response) or 'not monotone'; with
    the antisymmetry ``|c(+x) + c(-x)| / (|c(+x)| + |c(-x)|)`` at the largest shift."""
    steps = np.diff(values)
    zero = pcts.index(0.0)
    left, right = values[zero] - values[0], values[-1] - values[zero]
    c_hi, c_lo = values[-1] - values[zero], values[0] - values[zero]
    asym = abs(c_hi + c_lo) / max(abs(c_hi) + abs(c_lo), 1e-300)
    if np.all(steps > 0) or np.all(steps < 0):
        kind = "monotone"
    elif left * right < 0:
        kind = "both ends the same way"
    else:
        kind = "not monotone"
    return f"{kind}, asymmetry {asym:.2f}"


def report_rule(params: BrakeParameters, name: str, crown_mm: float, pcts: list[float]) -> None:
    rule, held = RULES[name]
    print(f"\n== {name} (crown {crown_mm:g} mm): {held}")
    base_p = packed(params, rule(params, 0.0), crown_mm)
    base_geo = geometry(base_p)
    base = impact(base_p, {})
    print(
        f"   symmetric: gap {math.degrees(base_geo.gap_angle_rad):.3f} deg, first contact"
        f" {base_geo.contact_deg:.1f} deg, Fe {base[0]:.1f} N, peak {base[1]:.0f} N,"
        f" T {1e3 * base[2]:.2f} ms"
    )
    rows = {}
    for pct in pcts:
        p = packed(params, rule(params, pct), crown_mm, pivot_radius_change_pct=pct)
        geo = geometry(p)
        fig = impact(p, {"pivot_radius_change_pct": pct})
        rows[pct] = fig
        print(
            f"   pin {pct:+.0f} %: rest gap {geo.rest_gap_mm:+.3f} mm, gap ratio"
            f" {geo.gap_angle_rad / base_geo.gap_angle_rad:.3f}, contact {geo.contact_deg:.1f}"
            f" deg, d/h {geo.self_locking_mu:.2f}; Fe {fig[0]:.1f} N, peak"
            f" {pct_change(fig[1], base[1]):+.1f} %, T {pct_change(fig[2], base[2]):+.1f} %"
        )
    if 3.0 in rows:
        pub = PUBLISHED_CASES["1"]
        fe, pk, t = rows[3.0]
        inside = (
            abs(pct_change(pk, base[1]) - pub["peak_fr_change_pct"]) <= BANDS["change_points"],
            abs(pct_change(t, base[2]) - pub["period_change_pct"]) <= BANDS["change_points"],
            abs(fe / pub["first_impact_actuation_n"] - 1) <= BANDS["first_impact_actuation_rel"],
        )
        print(f"   case 1 in band (peak, period, Fe): {inside}")
    full = sorted({0.0, *rows})
    if len(full) >= 3:
        vals = {0.0: base, **rows}
        for i, label in enumerate(("Fe", "peak", "T")):
            print(f"   sweep {label}: {shape([vals[x][i] for x in full], full)}")


@dataclass(frozen=True)
class RuleFigures:
    """One pose rule for the left pin moved 3 % out (case 1) and 3 % in (case 2).

    Attributes:
        rule, held_by: the rule's name and what holds the shoe at rest under it.
        rest_gap_mm: smallest lining-drum gap at rest, pin +3 % and -3 %, mm (negative:
            the lining would sit inside the drum, not admissible).
        contact_deg: polar angle of the first contact, pin +3 % and -3 %, deg.
        case1, case2: actuation at first impact (N), peak and period changes against the
            symmetric brake (%); None when the shoe cannot be assembled so.
    """

    rule: str
    held_by: str
    rest_gap_mm: tuple[float, float]
    contact_deg: tuple[float, float]
    case1: tuple[float, float, float] | None
    case2: tuple[float, float, float] | None


def rule_figures(params: BrakeParameters, names: tuple[str, ...] = tuple(RULES)):
    """Each rule of ``names`` (:data:`RULES`) for the left pin moved by +3 and -3 %."""
    sym = impact(packed(params, nominal_pose(params)), {})
    out = []
    for name in names:
        rule, held = RULES[name]
        gaps, contacts, cases = [], [], []
        for pct in (3.0, -3.0):
            p = packed(params, rule(params, pct), pivot_radius_change_pct=pct)
            geo = geometry(p)
            gaps.append(geo.rest_gap_mm)
            contacts.append(geo.contact_deg)
            fig = None
            if geo.rest_gap_mm > 0.0:
                fe, peak, period = impact(p, {"pivot_radius_change_pct": pct})
                fig = (fe, pct_change(peak, sym[1]), pct_change(period, sym[2]))
            cases.append(fig)
        out.append(RuleFigures(name, held, tuple(gaps), tuple(contacts), *cases))
    return out


def reference_figures(params: BrakeParameters) -> tuple[float, float, float]:
    """The symmetric brake's actuation at first impact (N) and case 5's peak and period
    changes (%): no pin moves in them, so every rule gives these."""
    sym = impact(packed(params, nominal_pose(params)), {})
    tilt = {"initial_angle_deg": -2.0}
    c5 = impact(packed(params, nominal_pose(params), **tilt), tilt)
    return sym[0], pct_change(c5[1], sym[1]), pct_change(c5[2], sym[2])
