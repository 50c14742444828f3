"""Calibration study: the free parameters, chosen once for the symmetric brake and cases
1, 5 and 7 together (MODEL.md "How to validate honestly").

Run it with ``python -m brake_sim_ros.studies.calibration`` (a few minutes on one core).
It prints the figures of the parameters in force, then searches the free parameters
within their plausibility bounds (:data:`FREE`) for the smallest misfit to the published
targets, each measured in units of its validation band, and prints the best set and its
figures. Nothing in the library imports this module; what it found is written, with the
reasons, in :mod:`brake_sim_ros.model.parameters`.

The figures are computed as the validation report computes them (the same impact and
contact-regime metrics), with two shortcuts that the report does not take: the impacting
regime is integrated only to 0.34 s (the first two impacts of every case) with
``rk4-located`` at 20 us, and the stop time and contact-regime forces come from the
contact-regime model (quasi-static shoes, the same balance the full model settles to).
The chosen set is then checked by the full report, ``brake-sim validate``.

How the values in force were found: the search started from the parameters before issue 10
(pin at 150 mm and 261 deg, tip at (-30, 140) mm, clearance 3.73 mm) and moved the pin and
the tip to the edge of :data:`FREE` (245 deg, 150 mm high), where a pin shift turns the shoe
most; case 1 stayed outside its bands (the validation report's notes say why). The values
were then rounded, and the shoe's mass set so that its radius of gyration is that of a
uniform arc (1.6 kg, 98 mm about the mass centre) at the same inertia about the pin: the
objective moved by less than 1 %.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from brake_sim_ros.analysis.impacts import contact_regime_force, shoe_metrics
from brake_sim_ros.command_line import Parser
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.solvers.contact_regime import run_contact_regime
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.studies.validation_checks import (
    BANDS,
    PUBLISHED_CASES,
    PUBLISHED_FIRST_IMPACT_ACTUATION_N,
    PUBLISHED_STOP_TIME_S,
)

IMPACT_SPAN_S = 0.34
IMPACT_STEP_S = 2e-5
EVENT_S = 7.5

CALIBRATION_CASES: dict[str, Defects] = {
    "symmetric": Defects(),
    "1": Defects(left=ShoeDefect(pivot_radius_change_pct=3.0)),
    "5": Defects(left=ShoeDefect(initial_angle_deg=-2.0)),
    "7": Defects(left=ShoeDefect(actuation_share=0.55), right=ShoeDefect(actuation_share=0.45)),
}


@dataclass(frozen=True)
class Free:
    """One free parameter: ``group.name`` searched within ``[lower, upper]``."""

    group: str
    name: str
    lower: float
    upper: float
    why: str


# The search space: what a car's leading-trailing drum brake of 360 mm allows. The pins sit
# on an anchor at the bottom and the tips at a wheel cylinder at the top; the bounds keep
# both within what one anchor and one cylinder can carry.
FREE: tuple[Free, ...] = (
    Free("shoe", "pivot_radius_m", 0.120, 0.160, "anchor pins above the hub flange"),
    Free("shoe", "pivot_polar_angle_deg", 245.0, 265.0, "pins within 65 mm of the axis"),
    Free("shoe", "tip_x_m", -0.045, -0.020, "one wheel cylinder, 40-90 mm long"),
    Free("shoe", "tip_y_m", 0.110, 0.150, "cylinder below the drum's rim"),
    Free("shoe", "running_clearance_m", 0.3e-3, 4.5e-3, "new to worn"),
    Free("shoe", "mass_kg", 0.8, 2.0, "car shoe with lining"),
    Free("shoe", "mass_centre_offset_x_m", -0.015, 0.015, "from the shoe arc's centroid"),
    Free("shoe", "mass_centre_offset_y_m", -0.015, 0.015, "from the shoe arc's centroid"),
    Free("shoe", "radius_of_gyration_m", 0.080, 0.130, "about the mass centre"),
    Free("friction", "coefficient", 0.25, 0.45, "organic lining on cast iron"),
    Free("contact", "damping_n_s_per_m", 300.0, 6000.0, "restitution 0.3-0.95"),
)


# Radius of the shoe's web-and-table arc (its material midline), m: 30 mm inside the drum
# for a 5 mm lining on a T-section table and web.
SHOE_ARC_INSET_M = 0.030


def shoe_arc_centroid(
    drum_radius_m: float, pivot_polar_deg: float, tip_x_m: float, tip_y_m: float
) -> tuple[float, float]:
    """Centroid (m) of a uniform arc at ``drum radius - SHOE_ARC_INSET_M`` from the pin's
    polar angle to the tip's: where a shoe's mass centre sits, give or take its ends."""
    tip_deg = math.degrees(math.atan2(tip_y_m, tip_x_m)) % 360.0
    half = math.radians(0.5 * (pivot_polar_deg - tip_deg))
    mid = math.radians(0.5 * (pivot_polar_deg + tip_deg))
    r = (drum_radius_m - SHOE_ARC_INSET_M) * math.sin(half) / half
    return r * math.cos(mid), r * math.sin(mid)


def parameters_from(x: np.ndarray, base: BrakeParameters) -> BrakeParameters:
    """Parameters for the search vector ``x`` (one value per :data:`FREE` entry, in its
    units). The mass centre is the shoe arc's centroid (:func:`shoe_arc_centroid`) plus an
    offset; the radius of gyration about it is turned into the inertia about the pin
    (parallel-axis theorem); the lining spans from 15 deg past the tip's polar angle to
    50 deg short of the pin's, so that the point where the shoe first touches (90 deg short
    of the pin) stays well inside it."""
    values = {f.name: float(v) for f, v in zip(FREE, x, strict=True)}
    shoe = {k: v for k, v in values.items() if k in base.shoe.__dataclass_fields__}
    a = math.radians(values["pivot_polar_angle_deg"])
    px, py = values["pivot_radius_m"] * math.cos(a), values["pivot_radius_m"] * math.sin(a)
    gx, gy = shoe_arc_centroid(
        base.shoe.drum_radius_m,
        values["pivot_polar_angle_deg"],
        values["tip_x_m"],
        values["tip_y_m"],
    )
    shoe["mass_centre_x_m"] = values["mass_centre_x_m"] = gx + values["mass_centre_offset_x_m"]
    shoe["mass_centre_y_m"] = values["mass_centre_y_m"] = gy + values["mass_centre_offset_y_m"]
    arm2 = (values["mass_centre_x_m"] - px) ** 2 + (values["mass_centre_y_m"] - py) ** 2
    shoe["inertia_about_pivot_kg_m2"] = values["mass_kg"] * (
        arm2 + values["radius_of_gyration_m"] ** 2
    )
    tip_deg = math.degrees(math.atan2(values["tip_y_m"], values["tip_x_m"]))
    shoe["lining_start_deg"] = round(tip_deg + 15.0, 1)
    shoe["lining_end_deg"] = round(values["pivot_polar_angle_deg"] - 50.0, 1)
    return base.with_overrides(
        {
            "shoe": shoe,
            "friction": {"coefficient": values["coefficient"]},
            "contact": {"damping_n_s_per_m": values["damping_n_s_per_m"]},
        }
    )


def vector_of(params: BrakeParameters) -> np.ndarray:
    """The search vector of ``params`` (inverse of :func:`parameters_from` where it can be)."""
    g = params.shoe
    px, py = g.pivot_xy_m
    arm2 = (g.mass_centre_x_m - px) ** 2 + (g.mass_centre_y_m - py) ** 2
    gyration = math.sqrt(max(g.inertia_about_pivot_kg_m2 / max(g.mass_kg, 1e-9) - arm2, 0.0))
    gx, gy = shoe_arc_centroid(g.drum_radius_m, g.pivot_polar_angle_deg, g.tip_x_m, g.tip_y_m)
    known = {
        "mass_centre_offset_x_m": g.mass_centre_x_m - gx,
        "mass_centre_offset_y_m": g.mass_centre_y_m - gy,
        "radius_of_gyration_m": gyration,
        "coefficient": params.friction.coefficient,
        "damping_n_s_per_m": params.contact.damping_n_s_per_m,
    }
    return np.array([known.get(f.name, getattr(g, f.name, math.nan)) for f in FREE])


@dataclass(frozen=True)
class ImpactFigures:
    """First-impact figures of one shoe: actuation (N), peak |F_pivot| (N), period (s)."""

    actuation_n: float
    peak_n: float
    period_s: float


def impact_figures(params: BrakeParameters, defects: Defects, side: str = "left") -> ImpactFigures:
    """The first two impacts of ``side`` in the published ramp, by ``rk4-located``."""
    stepper = FixedStepStepper(
        BrakeSetup(params=params, defects=defects), IMPACT_STEP_S, check_step=False
    )
    m = shoe_metrics(stepper.run(IMPACT_SPAN_S), side, stop_time_s=None)
    return ImpactFigures(m.first_impact_actuation_n, m.first_impact_peak_n, m.period_s)


def contact_figures(params: BrakeParameters, defects: Defects) -> tuple[float, float, float]:
    """(stop time s, left and right contact-regime |F_pivot| N) of the contact-regime model."""
    run = run_contact_regime(BrakeSetup(params=params, defects=defects), EVENT_S)
    if run.stop_time_s is None:
        raise BrakeSimError("the drum did not stop")
    forces = [
        contact_regime_force(
            run.samples.time_s, run.samples.pivot_force_magnitude(s), stop_time_s=run.stop_time_s
        )
        for s in SIDES
    ]
    return run.stop_time_s, forces[0], forces[1]


def _pct(value: float, base: float) -> float:
    return 100.0 * (value / base - 1.0)


def calibration_figures(params: BrakeParameters) -> dict[str, float]:
    """Every calibration target's model figure for ``params`` (the report's definitions)."""
    sym = impact_figures(params, CALIBRATION_CASES["symmetric"])
    stop, lead, trail = contact_figures(params, CALIBRATION_CASES["symmetric"])
    c1 = impact_figures(params, CALIBRATION_CASES["1"])
    c5 = impact_figures(params, CALIBRATION_CASES["5"])
    c7 = impact_figures(params, CALIBRATION_CASES["7"])
    _, lead7, _ = contact_figures(params, CALIBRATION_CASES["7"])
    return {
        "stop_time_s": stop,
        "first_impact_actuation_n": sym.actuation_n,
        "lead_minus_trail_n": lead - trail,
        "1.peak_fr_change_pct": _pct(c1.peak_n, sym.peak_n),
        "1.period_change_pct": _pct(c1.period_s, sym.period_s),
        "1.first_impact_actuation_n": c1.actuation_n,
        "5.peak_fr_change_pct": _pct(c5.peak_n, sym.peak_n),
        "5.period_change_pct": _pct(c5.period_s, sym.period_s),
        "7.peak_fr_change_pct": _pct(c7.peak_n, sym.peak_n),
        "7.contact_fr_change_pct": _pct(lead7, lead),
    }


def misfits(fig: dict[str, float]) -> dict[str, float]:
    """Each target's miss in units of its validation band (|miss| <= 1: inside the band)."""
    pub = PUBLISHED_CASES
    band_pts = BANDS["change_points"]
    out = {
        "stop_time_s": (fig["stop_time_s"] / PUBLISHED_STOP_TIME_S - 1) / BANDS["stop_time_rel"],
        "first_impact_actuation_n": (
            fig["first_impact_actuation_n"] / PUBLISHED_FIRST_IMPACT_ACTUATION_N - 1
        )
        / BANDS["first_impact_actuation_rel"],
        "1.first_impact_actuation_n": (
            fig["1.first_impact_actuation_n"] / pub["1"]["first_impact_actuation_n"] - 1
        )
        / BANDS["first_impact_actuation_rel"],
        "7.contact_fr_change_pct": (fig["7.contact_fr_change_pct"] - pub["7"]["peak_fr_change_pct"])
        / BANDS["case7_contact_points"],
        # the leading shoe must carry more: a miss only when it does not (in units of 100 N)
        "lead_minus_trail_n": min(fig["lead_minus_trail_n"], 0.0) / 100.0,
    }
    for case in ("1", "5"):
        for key in ("peak_fr_change_pct", "period_change_pct"):
            out[f"{case}.{key}"] = (fig[f"{case}.{key}"] - pub[case][key]) / band_pts
    return out


# Case 1's figures are limited by the geometry (see the validation report's notes): a
# 3 % radial pin shift closes only part of the angular gap. They are weighted in band
# units like the rest, but every target the model can reach is held to a quarter of its
# band around the published value, so that the search cannot buy case 1 by moving the
# symmetric brake (its reference) or case 5 to the edge of their bands.
GEOMETRY_LIMITED = ("1.peak_fr_change_pct", "1.period_change_pct", "1.first_impact_actuation_n")
REACHABLE_SCALE = 0.25


def objective_value(miss: dict[str, float]) -> float:
    total = 0.0
    for key, m in miss.items():
        scaled = m if key in GEOMETRY_LIMITED else m / REACHABLE_SCALE
        total += scaled * scaled
    return total


def search(
    start: BrakeParameters,
    *,
    max_evaluations: int = 400,
    hold: tuple[str, ...] = (),
    log: Callable[[str], None] | None = print,
) -> tuple[BrakeParameters, float]:
    """Nelder-Mead on the free parameters scaled to their bounds, from ``start``; the
    parameters named in ``hold`` keep their values in ``start``."""
    lo = np.array([f.lower for f in FREE])
    hi = np.array([f.upper for f in FREE])
    x0 = vector_of(start)
    moving = np.array([f.name not in hold for f in FREE])
    best: dict = {"value": math.inf, "x": None}

    def cost(v: np.ndarray) -> float:
        u = np.clip((x0 - lo) / (hi - lo), 0.0, 1.0)
        u[moving] = v
        x = np.where(moving, lo + (hi - lo) * np.clip(u, 0.0, 1.0), x0)
        penalty = 1e3 * float(np.sum(np.clip(-u, 0, None) + np.clip(u - 1, 0, None)))
        try:
            value = objective_value(misfits(calibration_figures(parameters_from(x, start))))
        except (BrakeSimError, ValueError, ZeroDivisionError):
            return 1e6 + penalty
        if not math.isfinite(value):
            return 1e6 + penalty
        value += penalty
        if value < best["value"]:
            best.update(value=value, x=x.copy())
            if log:
                log(f"{value:10.4f}  " + "  ".join(f"{v:.5g}" for v in x))
        return value

    u0 = np.clip((x0 - lo) / (hi - lo), 0.0, 1.0)[moving]
    minimize(
        cost,
        u0,
        method="Nelder-Mead",
        options={"maxfev": max_evaluations, "xatol": 1e-3, "fatol": 1e-3},
    )
    return parameters_from(best["x"], start), best["value"]


def describe(params: BrakeParameters) -> str:
    fig = calibration_figures(params)
    miss = misfits(fig)
    lines = [f"{'target':34s} {'model':>10s} {'miss/band':>10s}"]
    for key, value in fig.items():
        m = miss.get(key)
        lines.append(f"{key:34s} {value:10.4g} " + (f"{m:+10.2f}" if m is not None else ""))
    lines.append(f"objective {objective_value(miss):.4f}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = Parser(description=__doc__.splitlines()[0])
    parser.add_argument("--evaluations", type=int, default=400)
    parser.add_argument("--describe-only", action="store_true")
    parser.add_argument(
        "--hold", nargs="*", default=[], help="free parameters to keep at their present values"
    )
    args = parser.parse_args(argv)
    params = BrakeParameters()
    print(describe(params))
    if args.describe_only:
        return 0
    best, _value = search(params, max_evaluations=args.evaluations, hold=tuple(args.hold))
    print(best)
    print(describe(best))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
