"""The pose-rule study's search of the calibration's space (:mod:`.pose_rules`): random
geometries drawn from :data:`.calibration.FREE`, kept when the symmetric first impact and
case 5 are in their bands, and case 1 judged under each pose rule there.

Run it with ``python -m brake_sim_ros.studies.pose_rule_study --sample N``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.studies.calibration import (
    CALIBRATION_CASES,
    FREE,
    contact_figures,
    impact_figures,
    parameters_from,
    vector_of,
)
from brake_sim_ros.studies.pose_rules import (
    RULES,
    geometry,
    impact,
    nominal_pose,
    packed,
    packed_as,
    pct_change,
    shape,
)
from brake_sim_ros.studies.validation_checks import (
    BANDS,
    PUBLISHED_CASES,
    PUBLISHED_FIRST_IMPACT_ACTUATION_N,
    PUBLISHED_STOP_TIME_S,
)


@dataclass(frozen=True)
class GridPoint:
    """One geometry of the grid and its figures under one rule (misses in band units)."""

    rule: str
    pin_deg: float
    clearance_mm: float
    gyration_mm: float
    crown_mm: float
    admissible: str  # "" or why not
    misses: dict[str, float]
    case2_peak_pct: float = math.nan  # case 2's first-impact peak change, %
    params: BrakeParameters | None = None

    @property
    def inside(self) -> int:
        return sum(abs(m) <= 1.0 for m in self.misses.values())

    @property
    def case1_miss(self) -> float:
        return sum(m * m for k, m in self.misses.items() if k.startswith("1."))


def reference_misses(params: BrakeParameters) -> tuple[tuple[float, float, float], dict]:
    """The symmetric first impact (Fe N, peak N, T s) and the misses (band units) of the
    symmetric first impact and case 5; no pose rule changes them (no pin moves)."""
    sym = impact(packed(params, nominal_pose(params)), {})
    tilt = {"initial_angle_deg": -2.0}
    c5 = impact(packed(params, nominal_pose(params), **tilt), tilt)
    pub5, pts = PUBLISHED_CASES["5"], BANDS["change_points"]
    return sym, {
        "sym.Fe": (sym[0] / PUBLISHED_FIRST_IMPACT_ACTUATION_N - 1)
        / BANDS["first_impact_actuation_rel"],
        "5.peak": (pct_change(c5[1], sym[1]) - pub5["peak_fr_change_pct"]) / pts,
        "5.T": (pct_change(c5[2], sym[2]) - pub5["period_change_pct"]) / pts,
    }


def grid_point(
    params: BrakeParameters,
    name: str,
    crown_mm: float,
    labels: tuple[float, float, float],
    reference: tuple[tuple[float, float, float], dict] | None = None,
) -> GridPoint:
    """Case 1 (and case 2, the sweep's other end) under rule ``name``, with the misses of
    :func:`reference_misses`; ``labels``: (pin deg, clearance mm, gyration mm). Case 2's
    peak is recorded as ``2.peak`` (its change, %): no published figure, the shape only."""
    rule, _held = RULES[name]
    why = []
    figs = {}
    for pct in (-3.0, 3.0):
        p = packed(params, rule(params, pct), crown_mm, pivot_radius_change_pct=pct)
        geo = geometry(p)
        if not geo.rest_gap_mm > 0.0:
            why.append(f"{pct:+g} %: lining {-geo.rest_gap_mm:.2f} mm inside the drum at rest")
            continue
        if not geo.self_locking_mu > params.friction.coefficient:
            why.append(f"{pct:+g} %: self-locks (d/h {geo.self_locking_mu:.2f})")
        figs[pct] = impact(p, {"pivot_radius_change_pct": pct})
    sym, ref = reference if reference is not None else reference_misses(params)
    misses = dict(ref)
    pub1, pts = PUBLISHED_CASES["1"], BANDS["change_points"]
    if 3.0 in figs:
        fe, pk, t = figs[3.0]
        misses |= {
            "1.peak": (pct_change(pk, sym[1]) - pub1["peak_fr_change_pct"]) / pts,
            "1.T": (pct_change(t, sym[2]) - pub1["period_change_pct"]) / pts,
            "1.Fe": (fe / pub1["first_impact_actuation_n"] - 1)
            / BANDS["first_impact_actuation_rel"],
        }
    case2 = pct_change(figs[-3.0][1], sym[1]) if -3.0 in figs else math.nan
    return GridPoint(name, *labels, crown_mm, "; ".join(why), misses, case2, params)


# held at its value in force: the friction coefficient (with the clearance and inertia it
# sets the stop time and case 7's contact regime, which no pose rule changes)
SAMPLE_HOLD = ("coefficient",)


@dataclass(frozen=True)
class Sample:
    """A random sample of the calibration's space under one rule."""

    rule: str
    points: list[GridPoint]

    def calibrated(self) -> list[GridPoint]:
        """Admissible points whose symmetric first impact and case 5 are in their bands."""
        keys = ("sym.Fe", "5.peak", "5.T")
        return [
            p
            for p in self.points
            if not p.admissible and all(abs(p.misses[k]) <= 1.0 for k in keys)
        ]

    def case1_inside(self) -> list[GridPoint]:
        keys = ("1.peak", "1.T", "1.Fe")
        return [p for p in self.calibrated() if all(abs(p.misses.get(k, 9)) <= 1 for k in keys)]


def sample_geometries(
    params: BrakeParameters, count: int, seed: int = 28
) -> list[tuple[BrakeParameters, tuple, tuple]]:
    """``count`` geometries drawn uniformly from :data:`.calibration.FREE` (seeded; the
    friction coefficient held), kept when the symmetric first impact and case 5 are in
    their bands: (parameters, labels, :func:`reference_misses`)."""
    rng = np.random.default_rng(seed)
    x0 = vector_of(params)
    out = []
    for _ in range(count):
        x = np.array(
            [
                x0[i] if f.name in SAMPLE_HOLD else rng.uniform(f.lower, f.upper)
                for i, f in enumerate(FREE)
            ]
        )
        try:
            p = parameters_from(x, params)
            ref = reference_misses(p)
        except ValueError:
            continue
        if all(abs(m) <= 1.0 for m in ref[1].values()):
            out.append((p, (x[1], 1e3 * x[4], 1e3 * x[8]), ref))
    return out


def sample_rule(name: str, geometries: list) -> Sample:
    """Case 1 under rule ``name`` for each of :func:`sample_geometries`."""
    return Sample(name, [grid_point(p, name, 0.0, labels, ref) for p, labels, ref in geometries])


def print_sample(sample: Sample) -> None:
    ok = [p for p in sample.points if not p.admissible]
    cal = sample.calibrated()
    inside = sample.case1_inside()
    print(
        f"== {sample.rule}: {len(sample.points)} calibrated geometries, {len(ok)} admissible"
        f" ({len(cal)}), {len(inside)} with case 1's three figures in their bands"
    )
    if not ok:
        print(f"   e.g. {sample.points[0].admissible}")
    rises = [p.case2_peak_pct for p in cal if math.isfinite(p.case2_peak_pct)]
    if rises:
        print(f"   case 2 peak change: {min(rises):+.1f} to {max(rises):+.1f} %")
    for key in ("1.peak", "1.T", "1.Fe"):
        cells = [p.misses[key] for p in cal if key in p.misses]
        if cells:
            print(f"   {key} miss over those: {min(cells):+.2f} to {max(cells):+.2f} bands")
    for p in sorted(cal, key=lambda p: p.case1_miss)[:2]:
        cells = "  ".join(f"{k} {m:+.2f}" for k, m in p.misses.items())
        cells += f"  case 2 peak {p.case2_peak_pct:+.1f} %"
        print(
            f"   closest: pin {p.pin_deg:.0f} deg, clearance {p.clearance_mm:.2f} mm,"
            f" gyration {p.gyration_mm:.0f} mm: {cells}"
        )


def verify(point: GridPoint) -> list[str]:
    """The rest of the validation's calibration figures for a geometry whose case 1 is in
    its bands: stop time, leading above trailing, case 7 (contact regime and first impact;
    no pin moves in them, so no pose rule changes them), and the left shoe's pivot sweep
    under the point's rule (admissible at every step? its shape)."""
    params = point.params
    rule, _held = RULES[point.rule]
    stop, lead, trail = contact_figures(params, CALIBRATION_CASES["symmetric"])
    _, lead7, _ = contact_figures(params, CALIBRATION_CASES["7"])
    sym = impact_figures(params, CALIBRATION_CASES["symmetric"])
    c7 = impact_figures(params, CALIBRATION_CASES["7"])
    g = params.shoe
    lines = [
        f"pin {1e3 * g.pivot_radius_m:.1f} mm at {g.pivot_polar_angle_deg:.1f} deg, tip"
        f" ({1e3 * g.tip_x_m:.1f}, {1e3 * g.tip_y_m:.1f}) mm, clearance"
        f" {1e3 * g.running_clearance_m:.2f} mm, mass {g.mass_kg:.2f} kg, inertia"
        f" {g.inertia_about_pivot_kg_m2:.4f} kg m^2, lining {g.lining_start_deg:g}-"
        f"{g.lining_end_deg:g} deg, contact damping {params.contact.damping_n_s_per_m:.0f} N s/m",
        f"  stop {stop:.3f} s ({100 * (stop / PUBLISHED_STOP_TIME_S - 1):+.1f} %), leading"
        f" {lead:.0f} N vs trailing {trail:.0f} N, case 7 contact {pct_change(lead7, lead):+.1f} %,"
        f" case 7 first-impact peak {pct_change(c7.peak_n, sym.peak_n):+.1f} %",
    ]
    pcts = [-3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0]
    values, gaps = [], []
    for pct in pcts:
        p = packed(params, rule(params, pct), pivot_radius_change_pct=pct)
        gaps.append(geometry(p).rest_gap_mm)
        values.append(impact(p, {"pivot_radius_change_pct": pct}))
    lines.append("  rest gap over the sweep: " + " ".join(f"{x:+.2f}" for x in gaps) + " mm")
    for i, label in enumerate(("Fe", "peak", "T")):
        col = [v[i] for v in values]
        changes = " ".join(f"{pct_change(v, col[3]):+.1f}" for v in col)
        lines.append(f"  sweep {label} %: {changes} ({shape(col, pcts)})")
    return lines


# The built-in scenarios of the cases a found geometry's check runs, with the left shoe's defect.
SCENARIO_CASES = (
    ("case1_left_pivot_out", {"pivot_radius_change_pct": 3.0}),
    ("case2_left_pivot_in", {"pivot_radius_change_pct": -3.0}),
    ("case5_left_tilted", {"initial_angle_deg": -2.0}),
)


def scenario_check(params: BrakeParameters, name: str) -> list[str]:
    """Cases 1, 2 and 5 and the symmetric brake run as the validation runs them (each
    built-in scenario's own solver, 0.6 s), with ``params`` and the left shoe placed by
    rule ``name``: the left shoe's first impact against the symmetric brake's."""
    import dataclasses

    from brake_sim_ros.scenarios import load_scenario
    from brake_sim_ros.stream.run import run_scenario

    rule, _held = RULES[name]

    def left(scenario_name: str, defect: dict):
        sc = load_scenario(scenario_name)
        sc = dataclasses.replace(sc, setup=dataclasses.replace(sc.setup, params=params))
        pct = defect.get("pivot_radius_change_pct", 0.0)
        with packed_as(packed(params, rule(params, pct), **defect)):
            return run_scenario(sc, duration_s=0.6).metrics.left

    sym = left("symmetric", {})
    lines = [f"  scenarios: symmetric {sym.first_impact_actuation_n:.2f} N"]
    for scenario_name, defect in SCENARIO_CASES:
        m = left(scenario_name, defect)
        lines.append(
            f"  scenarios: {scenario_name} {m.first_impact_actuation_n:.2f} N, peak"
            f" {pct_change(m.first_impact_peak_n, sym.first_impact_peak_n):+.1f} %, T"
            f" {pct_change(m.period_s, sym.period_s):+.1f} %"
        )
    return lines
