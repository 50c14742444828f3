"""Print what the step limit's resolution rule buys: the located RK4's errors at the
substeps a rule of 16 steps per period of the fastest oscillation gives and at those a rule
of 10 would give, against 16 times finer steps (``docs/model.md``, "Step limit").

The runs are the published event (``symmetric``, 7.5 s) on the service brake with the
lining over its arc at 25.6 kHz, where the rule binds (from about 100 N to 2 kN; above,
the friction's stability limit does). It never binds the point contact at the balanced
preset: its fastest oscillation (650-750 Hz) allows 8.4e-5 s and more, above the preset's
largest step of 6e-5 s. The substeps are forced (``check_step=False``), so the script
measures either rule whatever the stepper's own.
Usage (a minute once the kernels are compiled)::

    PYTHONPATH=. .venv/bin/python scripts/step_rule_errors.py
"""

from __future__ import annotations

import math

from brake_sim_ros.analysis.comparison import metric_errors
from brake_sim_ros.analysis.impacts import event_metrics
from brake_sim_ros.scenarios import Scenario, load_scenario, parse_scenario
from brake_sim_ros.scenarios.loader import parse_toml
from brake_sim_ros.scenarios.toml_text import dumps
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.solvers.stability import STABILITY_MARGIN, STEPS_PER_PERIOD

RULES = (STEPS_PER_PERIOD, 10)
FINER = 16  # the reference's substeps over the finer rule's


def _variant(force_n: float, rate_hz: float, lined: bool) -> Scenario:
    base = load_scenario("symmetric")
    data = parse_toml(base.text, base.source)
    data["brake"] = "service"
    data.setdefault("actuation", {})["peak_force_n"] = force_n
    data["sample_rate_hz"] = rate_hz
    if lined:
        data.setdefault("parameters", {}).setdefault("service", {})["distributed_lining"] = True
    return parse_scenario(dumps(data), f"symmetric, service brake, {force_n:g} N")


def _substeps(scenario: Scenario, steps_per_period: int) -> int:
    """Substeps a sample at the scenario's step limit with ``steps_per_period``."""
    limit = FixedStepStepper(scenario.setup, scenario.sample_period_s).limit  # at its peak
    resolution = limit.resolution_step_s * STEPS_PER_PERIOD / steps_per_period
    largest = min(STABILITY_MARGIN * limit.stability_step_s, resolution, scenario.solver.max_step_s)
    return math.ceil(scenario.sample_period_s / largest * (1.0 - 1e-12))


def _metrics(scenario: Scenario, substeps: int):
    period = scenario.sample_period_s
    stepper = FixedStepStepper(
        scenario.setup, period, max_step_s=period / substeps * (1.0 + 1e-9), check_step=False
    )
    block = stepper.advance(round(scenario.duration_s / period))
    assert stepper.substeps == substeps
    return event_metrics(block, stop_time_s=stepper.stop_time_s)


def main() -> None:
    cases = (
        ("lining over its arc, 855 N (the urban cycle's peak)", _variant(855.0, 25600.0, True)),
        ("lining over its arc, 1300 N (the published force)", _variant(1300.0, 25600.0, True)),
    )
    print("errors of the first-impact peak, its period and the stop time (worse shoe)")
    for label, scenario in cases:
        subs = {rule: _substeps(scenario, rule) for rule in RULES}
        finest = FINER * max(subs.values())
        reference = _metrics(scenario, finest)
        print(f"{label} (reference: {finest} substeps a sample)")
        for rule, sub in subs.items():
            e = metric_errors(_metrics(scenario, sub), reference)
            print(
                f"  {rule} steps a period: {sub} substep(s): first peak {100 * e.first_peak:.4f} %,"
                f" period {100 * e.period:.4f} %, stop {100 * e.stop_time:.1e} %, impacts"
                f" missed or added {e.impact_count_diff}"
            )


if __name__ == "__main__":
    main()
