"""The validation's figures and checks (``brake-sim validate``, :mod:`.validation`): the
published study's figures and the project's acceptance bands, the cases, the report's
figures in their JSON shape from the runs, and each check against its band.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from brake_sim_ros.analysis import measured_features as mf
from brake_sim_ros.analysis.impacts import EventMetrics
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import contact_arms
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.stream.run import RunResult

SYMMETRIC = "symmetric"
CASES: dict[str, tuple[str, str]] = {  # case number: (built-in scenario, shoe with the defect)
    "1": ("case1_left_pivot_out", "left"),
    "2": ("case2_left_pivot_in", "left"),
    "3": ("case3_right_pivot_out", "right"),
    "4": ("case4_right_pivot_in", "right"),
    "5": ("case5_left_tilted", "left"),
    "6": ("case6_right_tilted", "right"),
    "7": ("case7_left_actuation", "left"),
    "8": ("case8_right_actuation", "right"),
}

# Published figures (the study), and the band within which the model must land.
PUBLISHED_STOP_TIME_S = 6.6
PUBLISHED_FIRST_IMPACT_ACTUATION_N = 56.0
PUBLISHED_CASES: dict[str, dict[str, float]] = {
    "1": {
        "peak_fr_change_pct": -43.0,
        "period_change_pct": -23.6,
        "first_impact_actuation_n": 42.0,
    },
    "5": {"peak_fr_change_pct": 79.7, "period_change_pct": 39.3},
    "7": {"peak_fr_change_pct": 11.1, "period_change_pct": 0.0},
}
BANDS = {
    "stop_time_rel": 0.03,
    "first_impact_actuation_rel": 0.10,
    "change_points": 10.0,  # cases 1 and 5, percentage points
    "case7_contact_points": 5.0,  # case 7 contact-regime change vs the published +11.1 %
    "other_shoe_pct": 1.0,
}


# Pivot-location sweep: radius changes of one shoe's pin, %, around the symmetric brake.
# Its actuation at first impact must follow the free travel's cube root within this, %.
# The hand calculation holds for a shoe that nothing but the ramp moves before it
# touches, on the actuation's arm at first contact (contact_arms: it turns by the gap, so
# the arm changes by about 0.3 % on the way, 0.1 % in F_e); what is left is that, where the
# onset falls between two physics steps and the Hertzian contact's first micrometres
# (measured 2026-11-28: 0.06 % with the eye, 0.01 % with the tip abutment).
FREE_TRAVEL_BAND_PCT = 0.5
SWEEP_PCT = (-3.0, -2.0, -1.0, 1.0, 2.0, 3.0)
# Each sweep run covers the impacting regime only: the first two impacts of every step
# happen before 0.3 s (first impacts between 45 and 70 N of the ramp, about 0.22 s).
SWEEP_DURATION_S = 0.6
SWEEP_QUANTITIES = {  # figures key: what the report calls it
    "first_impact_peak_fr_n": "first-impact peak F_r",
    "period_s": "impact period T",
    "first_impact_actuation_n": "actuation at first impact",
}


def _pct(value: float, base: float) -> float:
    return 100.0 * (value / base - 1.0)


@dataclass(frozen=True)
class CaseRun:
    case: str
    scenario: str
    shoe: str
    result: RunResult


def strictly_monotone(values: list[float]) -> bool:
    """True when every step changes ``values`` in the same direction (none stays put)."""
    steps = [b - a for a, b in itertools.pairwise(values)]
    return bool(steps) and (all(d > 0 for d in steps) or all(d < 0 for d in steps))


def free_travel(p: np.ndarray, side: str) -> float:
    """What the first impact's actuation follows, by hand calculation: ``I gap / a``
    (kg m^2 rad / m) of ``side``'s shoe packed in ``p``. A shoe at rest turned by the
    ramp ``F = r t`` on the arm ``a`` about its pin (nothing else acts on the study
    brake's shoe before it touches) turns by ``theta = a r t^3 / (6 I)``: it reaches the
    angular gap ``gap`` at ``F_e = (6 r^2 I gap / a)^(1/3)``, so ``F_e`` goes with the
    cube root of ``I gap / a`` whatever moved the pin or how the shoe sits."""
    base = L.P_SHOE_BASE + SIDES.index(side) * L.SHOE_STRIDE
    arms = contact_arms(p, base, 0.0)
    if arms is None:
        return math.nan
    return p[base + L.S_INERTIA] * arms.onset_angle_rad / arms.actuation_arm_m


def sweep_figures(
    sweep: dict[str, dict[float, EventMetrics]], travel: dict[str, dict[float, float]]
) -> dict:
    """The sweep's figures: per side, the changes in ascending order, each quantity's values
    and changes against 0 %, whether each moves monotonically, and the actuation at first
    impact the free travel (``travel``, :func:`free_travel`) predicts from the healthy
    shoe's, with the largest miss of the model's from it, %."""
    out = {}
    for side, by_pct in sweep.items():
        pcts = sorted(by_pct)
        shoe = [by_pct[p].shoe(side) for p in pcts]
        values = {
            "first_impact_peak_fr_n": [m.first_impact_peak_n for m in shoe],
            "period_s": [m.period_s for m in shoe],
            "first_impact_actuation_n": [m.first_impact_actuation_n for m in shoe],
        }
        zero = pcts.index(0.0)
        fe0, t0 = values["first_impact_actuation_n"][zero], travel[side][0.0]
        predicted = [fe0 * (travel[side][p] / t0) ** (1.0 / 3.0) for p in pcts]
        misses = [
            abs(_pct(v, f))
            for v, f in zip(values["first_impact_actuation_n"], predicted, strict=True)
        ]
        out[side] = {
            "pivot_radius_change_pct": pcts,
            **values,
            "change_pct": {k: [_pct(v, vals[zero]) for v in vals] for k, vals in values.items()},
            "monotone": {k: strictly_monotone(vals) for k, vals in values.items()},
            "free_travel": [travel[side][p] for p in pcts],
            "free_travel_actuation_n": predicted,
            "free_travel_miss_pct": max(misses),
        }
    return out


def figures(
    base: EventMetrics,
    runs: list[CaseRun],
    sweep: dict[str, dict[float, EventMetrics]] | None = None,
    measured: mf.CaseSeparation | None = None,
    travel: dict[str, dict[float, float]] | None = None,
) -> dict:
    """The report's figures in the documented JSON shape (``travel``: each sweep run's
    :func:`free_travel`, with ``sweep``)."""
    out = {
        "symmetric": {
            "stop_time_s": base.stop_time_s,
            "first_impact_actuation_n": base.left.first_impact_actuation_n,
            "first_impact_peak_fr_n": {s: base.shoe(s).first_impact_peak_n for s in SIDES},
            "period_s": {s: base.shoe(s).period_s for s in SIDES},
            "contact_fr_n": {s: base.shoe(s).contact_regime_force_n for s in SIDES},
        },
        "cases": {},
    }
    for run in runs:
        m = run.result.metrics
        shoe, other = run.shoe, ("right" if run.shoe == "left" else "left")
        out["cases"][run.case] = {
            "scenario": run.scenario,
            "shoe": shoe,
            "stop_time_s": m.stop_time_s,
            "first_impact_actuation_n": m.shoe(shoe).first_impact_actuation_n,
            "peak_fr_change_pct": _pct(
                m.shoe(shoe).first_impact_peak_n, base.shoe(shoe).first_impact_peak_n
            ),
            "period_change_pct": _pct(m.shoe(shoe).period_s, base.shoe(shoe).period_s),
            "contact_fr_change_pct": _pct(
                m.shoe(shoe).contact_regime_force_n, base.shoe(shoe).contact_regime_force_n
            ),
            "other_shoe_peak_fr_change_pct": _pct(
                m.shoe(other).first_impact_peak_n, base.shoe(other).first_impact_peak_n
            ),
            "other_shoe_period_change_pct": _pct(m.shoe(other).period_s, base.shoe(other).period_s),
        }
    if sweep is not None:
        if travel is None:
            raise ValueError("the pivot sweep's figures need each run's free travel")
        out["pivot_sweep"] = sweep_figures(sweep, travel)
    if measured is not None:
        out["measured"] = measured_figures(measured, base, runs)
    return out


def measured_figures(measured: mf.CaseSeparation, base: EventMetrics, runs: list[CaseRun]) -> dict:
    """Per case number: each feature's mean and std over seeds, the symmetric mean, the
    relative difference and whether it separates (None: not judged); and the separating
    features. Also each run's first contact per shoe (ms), which the first-impact feature
    hears the earlier of."""
    out: dict = {
        "duration_s": measured.duration_s,
        "seeds": list(measured.seeds),
        "noise_rms_m_s2": measured.quiet_rms,
        "first_contact_ms": {SYMMETRIC: _first_contact_ms(base)}
        | {run.case: _first_contact_ms(run.result.metrics) for run in runs},
        "cases": {},
    }
    for run in runs:
        row = measured.comparisons[run.scenario]
        out["cases"][run.case] = {
            "features": {
                k: {
                    "mean": c.mean,
                    "std": c.std,
                    "symmetric_mean": c.base_mean,
                    "symmetric_std": c.base_std,
                    "relative": c.relative,
                    "separates": c.separates,
                }
                for k, c in row.items()
            },
            "separated_by": measured.separating(run.scenario),
        }
    return out


@dataclass(frozen=True)
class Check:
    """One check of the report. ``model_limit`` is non-empty for a miss the notes explain
    as beyond this model's reach with a physically plausible parameter set."""

    what: str
    published: str
    model: str
    difference: str
    passed: bool
    model_limit: str = ""


# Published figures this model cannot reach with a physically plausible parameter set,
# each with the reason the report's notes analyse: (case, figure key) -> reason. They keep
# their bands and show as misses. None since the study brake's shoe sits with its heel in
# an eye (issue 28): with the tip abutment, case 1's three figures were here.
MODEL_LIMITS: dict[tuple[str, str], str] = {}


def checks(fig: dict) -> list[Check]:
    """Every calibration target with its published figure, model figure and verdict."""
    sym = fig["symmetric"]
    out = []
    stop = sym["stop_time_s"] or math.nan
    out.append(
        Check(
            "symmetric: drum stop time",
            f"{PUBLISHED_STOP_TIME_S:.2f} s",
            f"{stop:.3f} s",
            f"{_pct(stop, PUBLISHED_STOP_TIME_S):+.2f} %",
            abs(stop / PUBLISHED_STOP_TIME_S - 1) <= BANDS["stop_time_rel"],
        )
    )
    fe = sym["first_impact_actuation_n"]
    out.append(
        Check(
            "symmetric: actuation force at first impact",
            f"{PUBLISHED_FIRST_IMPACT_ACTUATION_N:.0f} N",
            f"{fe:.1f} N",
            f"{_pct(fe, PUBLISHED_FIRST_IMPACT_ACTUATION_N):+.1f} %",
            abs(fe / PUBLISHED_FIRST_IMPACT_ACTUATION_N - 1) <= BANDS["first_impact_actuation_rel"],
        )
    )
    lead, trail = sym["contact_fr_n"]["left"], sym["contact_fr_n"]["right"]
    out.append(
        Check(
            "symmetric: leading pivot force above trailing while the drum turns",
            "left > right",
            f"{lead:.0f} N > {trail:.0f} N",
            f"{lead - trail:+.0f} N",
            lead > trail,
        )
    )
    for case, pub in PUBLISHED_CASES.items():
        c = fig["cases"][case]
        if case in ("1", "5"):
            for key, label in (
                ("peak_fr_change_pct", "peak F_r change"),
                ("period_change_pct", "impact period change"),
            ):
                ok = (
                    math.copysign(1, c[key]) == math.copysign(1, pub[key])
                    and abs(c[key] - pub[key]) <= BANDS["change_points"]
                )
                out.append(
                    Check(
                        f"case {case}: {label}",
                        f"{pub[key]:+.1f} %",
                        f"{c[key]:+.1f} %",
                        f"{c[key] - pub[key]:+.1f} points",
                        ok,
                        "" if ok else MODEL_LIMITS.get((case, key), ""),
                    )
                )
        if "first_impact_actuation_n" in pub:
            v, p = c["first_impact_actuation_n"], pub["first_impact_actuation_n"]
            ok = abs(v / p - 1) <= BANDS["first_impact_actuation_rel"]
            out.append(
                Check(
                    f"case {case}: actuation force at first impact",
                    f"{p:.0f} N",
                    f"{v:.1f} N",
                    f"{_pct(v, p):+.1f} %",
                    ok,
                    "" if ok else MODEL_LIMITS.get((case, "first_impact_actuation_n"), ""),
                )
            )
        if case == "7":
            v = c["contact_fr_change_pct"]
            p = pub["peak_fr_change_pct"]
            out.append(
                Check(
                    "case 7: contact-regime pivot force change (vs published +11.1 %)",
                    f"{p:+.1f} %",
                    f"{v:+.1f} %",
                    f"{v - p:+.1f} points",
                    abs(v - p) <= BANDS["case7_contact_points"],
                )
            )
    out += sign_checks(fig)
    for case in ("1", "2", "3", "4", "5", "6"):
        c = fig["cases"][case]
        worst = max(abs(c["other_shoe_peak_fr_change_pct"]), abs(c["other_shoe_period_change_pct"]))
        out.append(
            Check(
                f"case {case}: other shoe unchanged (first-impact peak and period)",
                "0 %",
                f"{worst:.2f} % (largest)",
                f"{worst:.2f} points",
                worst <= BANDS["other_shoe_pct"],
            )
        )
    out += sweep_checks(fig)
    return out


def sign_checks(fig: dict) -> list[Check]:
    """Every published non-zero change keeps its sign in the model (case 7's published
    +11.1 % is checked on the first impact and in the contact regime)."""
    out = []
    labels = {
        "peak_fr_change_pct": "first-impact peak F_r change",
        "period_change_pct": "impact period change",
    }
    for case, pub in PUBLISHED_CASES.items():
        c = fig["cases"][case]
        pairs = [(labels[k], pub[k], c[k]) for k in labels if pub.get(k)]
        if case == "7":
            pairs.append(
                ("contact-regime F_r change", pub["peak_fr_change_pct"], c["contact_fr_change_pct"])
            )
        for label, published, model in pairs:
            same = math.copysign(1, model) == math.copysign(1, published) and model != 0
            out.append(
                Check(
                    f"case {case}: sign of the {label}",
                    f"{published:+.1f} %",
                    f"{model:+.1f} %",
                    "same sign" if same else "opposite sign",
                    same,
                )
            )
    return out


def sweep_checks(fig: dict) -> list[Check]:
    """The pivot sweep's actuation at first impact follows each shoe's free travel to the
    drum (:func:`free_travel`, a hand calculation) within :data:`FREE_TRAVEL_BAND_PCT`:
    the project's criterion (the study publishes no sweep). The peak and the period depend
    on where the shoe first touches as well, which a pin moved past the clearance changes
    (the report's notes on case 1): their shapes are reported, not checked."""
    out = []
    for side, sw in fig.get("pivot_sweep", {}).items():
        miss = sw["free_travel_miss_pct"]
        out.append(
            Check(
                f"pivot sweep {SWEEP_PCT[0]:+g} to {SWEEP_PCT[-1]:+g} %, {side} shoe: actuation at"
                " first impact from the free travel (cube root of I gap / a)",
                f"none (project criterion: within {FREE_TRAVEL_BAND_PCT:g} %)",
                f"{sw['first_impact_actuation_n'][0]:.1f} N to"
                f" {sw['first_impact_actuation_n'][-1]:.1f} N",
                f"largest miss {miss:.2f} %",
                miss <= FREE_TRAVEL_BAND_PCT,
            )
        )
    return out


def _first_contact_ms(metrics: EventMetrics) -> dict[str, float]:
    """Each shoe's first contact onset, ms (inf without one)."""
    out = {}
    for side in SIDES:
        onsets = metrics.shoe(side).onsets_s
        out[side] = 1e3 * float(onsets[0]) if onsets.size else math.inf
    return out
