"""The validation's checks for a brake whose shoes sit by another pose rule
(:mod:`.pose_rules`): every case and the pivot sweep of ``brake-sim validate`` run as it
runs them (each built-in scenario with its own solver and duration), with the parameters
given and each shoe with a pin defect placed by the rule; then the validation's own
figures and checks (:mod:`.validation_checks`). The measured-acceleration part is left out.

Run it with ``python -m brake_sim_ros.studies.pose_rule_study --validate RULE ...`` (at the
parameters in force); about 10 s of CPU a rule.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from brake_sim_ros.analysis.impacts import EventMetrics
from brake_sim_ros.errors import BrakeSimError, ParameterError
from brake_sim_ros.model import growth
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import indentation_at, pack
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.scenarios.types import Scenario
from brake_sim_ros.stream.run import RunResult, run_scenario
from brake_sim_ros.studies.pose_rules import RULES, Pose, packed_as
from brake_sim_ros.studies.validation_checks import (
    CASES,
    SWEEP_DURATION_S,
    SWEEP_PCT,
    SYMMETRIC,
    CaseRun,
    Check,
    checks,
    figures,
    free_travel,
)


def packed_by_rule(
    params: BrakeParameters, defects: Defects, rule: Callable[[BrakeParameters, float], Pose]
) -> np.ndarray:
    """``pack(params, defects)`` with each shoe whose pin moved placed by ``rule`` (the
    right shoe as the mirror image of the left one, as the model places it)."""
    p = pack(params, defects)
    for i, side in enumerate(SIDES):
        pct = getattr(defects, side).pivot_radius_change_pct
        if pct == 0.0:
            continue
        pose = rule(params, pct)
        m = -1.0 if side == "right" else 1.0
        mid = pose.lining_mid_rad if m > 0 else math.pi - pose.lining_mid_rad
        b = L.P_SHOE_BASE + i * L.SHOE_STRIDE
        growth.write_placement.py_func(
            p,
            b,
            m * pose.pivot[0],
            pose.pivot[1],
            m * pose.lining_centre[0],
            pose.lining_centre[1],
            mid,
            m * pose.mass_centre[0],
            pose.mass_centre[1],
            pose.inertia_kg_m2,
            m * pose.tip[0],
            pose.tip[1],
        )
        if indentation_at(p, b, 0.0) >= 0.0:
            raise ParameterError(
                f"{side} pivot radius change {pct:+g} % under this pose puts the lining"
                f" {1e3 * indentation_at(p, b, 0.0):.2f} mm inside the drum at rest:"
                " allowed only a shoe clear of the drum (another geometry)"
            )
    return p


def _run(
    scenario: Scenario, params: BrakeParameters, rule, duration_s: float | None = None
) -> RunResult:
    sc = dataclasses.replace(scenario, setup=dataclasses.replace(scenario.setup, params=params))
    with packed_as(packed_by_rule(params, sc.setup.defects, rule)):
        return run_scenario(sc, duration_s=duration_s)


def validation_checks(
    params: BrakeParameters, rule_name: str, progress: Callable[[str], None] | None = None
) -> list[Check]:
    """The validation's checks for ``params`` with pins placed by rule ``rule_name``."""
    rule, _held = RULES[rule_name]
    if progress:
        progress(SYMMETRIC)
    base = _run(load_scenario(SYMMETRIC), params, rule)
    runs = []
    for case, (name, shoe) in CASES.items():
        if progress:
            progress(name)
        runs.append(CaseRun(case, name, shoe, _run(load_scenario(name), params, rule)))
    sweep: dict[str, dict[float, EventMetrics]] = {}
    travel: dict[str, dict[float, float]] = {}
    symmetric = load_scenario(SYMMETRIC)
    for side in SIDES:
        sweep[side] = {0.0: base.metrics}
        travel[side] = {0.0: free_travel(packed_by_rule(params, Defects(), rule), side)}
        for pct in SWEEP_PCT:
            if progress:
                progress(f"pivot sweep: {side} {pct:+g} %")
            defects = Defects(**{side: ShoeDefect(pivot_radius_change_pct=pct)})
            sc = dataclasses.replace(
                symmetric, setup=dataclasses.replace(symmetric.setup, defects=defects)
            )
            sweep[side][pct] = _run(sc, params, rule, SWEEP_DURATION_S).metrics
            travel[side][pct] = free_travel(packed_by_rule(params, defects, rule), side)
    return checks(figures(base.metrics, runs, sweep, travel=travel))


def print_validation(params: BrakeParameters, rule_name: str) -> None:
    """Print :func:`validation_checks` as ``brake-sim validate`` prints its checks, or the
    one line why the rule cannot place the shoes of ``params``."""
    import sys

    print(f"== {rule_name}")
    try:
        check_list = validation_checks(
            params, rule_name, progress=lambda name: print(f"running {name}", file=sys.stderr)
        )
    except BrakeSimError as exc:
        print(f"   not admissible: {exc}")
        return
    for c in check_list:
        print(
            f"{'ok  ' if c.passed else 'MISS'} {c.what}: published {c.published},"
            f" model {c.model} ({c.difference})"
        )
    print(f"{sum(c.passed for c in check_list)}/{len(check_list)} checks within their bands")
