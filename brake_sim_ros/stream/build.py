"""The one place a fixed-step stepper is built from a scenario.

The ROS node, the offline stream (MCAP, Rerun), ``brake-sim simulate``, :func:`run_scenario`
and the benchmarks all call :func:`stepper_for`, so they run the same scheme at the same
sample rate with the same substeps, and give the same numbers for the same scenario.
"""

from __future__ import annotations

from brake_sim_ros.errors import FidelityError
from brake_sim_ros.model.fidelity import levels_serving, plan
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.scenarios.types import Scenario
from brake_sim_ros.sensing.sensors import SensorBank
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.solvers.methods import METHODS


def stepper_for(scenario: Scenario, *, setup: BrakeSetup | None = None) -> FixedStepStepper:
    """The stepper for ``scenario``: its sample rate, its solver's fixed-step scheme and
    largest step (preset, or explicit ``method`` / ``max_step_s``), and the step limit of
    its setup at its actuation profile's peak force.

    Args:
        scenario: the scenario (apply command-line overrides first, with
            :meth:`Scenario.with_solver`).
        setup: the setup to step instead of the scenario's own (the node's, with ROS
            parameter overrides; a fidelity level's reduced model).

    Raises:
        StepSizeError: the step limit of the setup is pathological (below
            :data:`~brake_sim_ros.solvers.fixed_step.MIN_PHYSICS_STEP_S`).
    """
    return METHODS[scenario.solver.fixed_step_scheme].stepper(
        scenario.setup if setup is None else setup,
        scenario.sample_period_s,
        scenario.solver.max_step_s,
    )


def measures(scenario: Scenario) -> bool:
    """Whether ``scenario``'s fidelity plan builds its sensors (:attr:`Plan.sensors
    <brake_sim_ros.model.fidelity.Plan>`): without ``[needs]``, or when they ask
    ``measured_signals``."""
    return plan(scenario.needs, model_shoes=scenario.setup.options.shoes).sensors


def measured_refusal(scenario: Scenario) -> str | None:
    """Why ``scenario`` cannot measure (one line), or None when its plan builds sensors.

    For callers that were asked for measured signals explicitly (the node's and the
    offline stream's ``publish_measured``): they refuse rather than publish nothing."""
    if measures(scenario):
        return None
    return (
        f"scenario '{scenario.name}' states [needs] without 'measured_signals', so its plan"
        " builds no sensors (no structure, no measured channels): add 'measured_signals' to"
        f" [needs] outputs (levels that deliver it: {levels_serving('measured_signals')})"
        " or leave publish_measured off"
    )


def require_measured(scenario: Scenario, what: str) -> None:
    """Raise FidelityError ``"<what>: <reason>"`` unless ``scenario``'s plan has sensors."""
    reason = measured_refusal(scenario)
    if reason is not None:
        raise FidelityError(f"{what}: {reason}")


def sensor_bank_for(scenario: Scenario, *, seed: int | None = None) -> SensorBank | None:
    """The scenario's sensors (``scenario.sensors``) at its sample rate, their noise seeded
    from ``seed`` (default: the scenario's); None when its fidelity plan has no sensors
    (``[needs]`` without ``measured_signals``: no structure, no channels, no cost). The
    node, the offline stream and the Parquet writer build their bank here, at start and at
    each reset, so they measure the same bits."""
    if not measures(scenario):
        return None
    return SensorBank(
        scenario.sensors, scenario.sample_rate_hz, scenario.seed if seed is None else seed
    )
