"""Run a scenario to the end at the fidelity level its needs call for; one result type.

The method comes from the solver registry (:data:`~brake_sim_ros.solvers.methods.METHODS`);
the fixed-step schemes build their stepper the way :func:`.build.stepper_for` does.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from brake_sim_ros.analysis.impacts import EventMetrics, contact_only_metrics, shoe_metrics
from brake_sim_ros.errors import FidelityError
from brake_sim_ros.model.assembly import SIDES, ModelOptions
from brake_sim_ros.model.fidelity import Plan, plan
from brake_sim_ros.model.run_setup import BrakeSetup, SampleBlock
from brake_sim_ros.scenarios.types import Scenario
from brake_sim_ros.solvers.methods import METHODS, MethodOptions

_IMPACT_COLUMNS = ("indentation_m", "pivot_fx_n", "pivot_fy_n", "actuation_force_n")


@dataclass(frozen=True)
class RunResult:
    """A finished run.

    Attributes:
        samples: the recorded time history (only the columns the plan keeps).
        metrics: impacts, periods, peak and contact-regime forces, stop time; what the
            level does not deliver is empty or nan (stop time None).
        cpu_s: process CPU time spent integrating, s.
        n_steps: the method's unit of work (``METHODS[method].counts``).
        method: the name in :data:`~brake_sim_ros.solvers.methods.METHODS`.
        plan: the fidelity level and signals chosen for the scenario's needs.
        model_stop_time_s: the instant the model locked, s, even where the level does not
            deliver the stop time (for the fidelity study).
        step_note: fixed-step schemes: the sample rate, physics step, substeps and the
            step limit that chose them (one line); empty otherwise.

    A run that fails raises (SimulationError, StepSizeError) instead of returning.
    """

    samples: SampleBlock
    metrics: EventMetrics
    cpu_s: float
    n_steps: int
    method: str
    plan: Plan
    model_stop_time_s: float | None = None
    step_note: str = ""

    @property
    def stop_time_s(self) -> float | None:
        return self.metrics.stop_time_s

    @property
    def memory_bytes(self) -> int:
        """Bytes held by the recorded samples."""
        return int(self.samples.data.nbytes)


def planned_setup(setup: BrakeSetup, chosen: Plan) -> BrakeSetup:
    """``setup`` with the plan's coupling and shoes (a scenario's own rigid coupling kept)."""
    options = ModelOptions(
        rigid_coupling=setup.options.rigid_coupling or chosen.level.rigid_coupling,
        shoes=chosen.shoes,
    )
    return dataclasses.replace(setup, options=options)


def with_braking_torque(block: SampleBlock) -> SampleBlock:
    """Append ``braking_torque_n_m``: friction torque on the drum, N m (positive when it
    decelerates a counter-clockwise drum), sum of each friction force times its arm."""
    torque = np.zeros(len(block))
    for side in SIDES:
        arm = np.hypot(block[f"{side}_contact_x_m"], block[f"{side}_contact_y_m"])
        torque += block[f"{side}_friction_force_n"] * arm
    data = np.column_stack([block.data, torque])
    return SampleBlock(
        data, block.first_index, block.sample_period_s, (*block.columns, "braking_torque_n_m")
    )


def _keep(block: SampleBlock, columns: tuple[str, ...]) -> SampleBlock:
    if columns == block.columns:
        return block
    if "braking_torque_n_m" in columns and not block.has("braking_torque_n_m"):
        block = with_braking_torque(block)
    return block.select(columns)


def _metrics(
    block: SampleBlock, stop: float | None, chosen: Plan, model_shoes: tuple[str, ...]
) -> EventMetrics:
    """Metrics of what the level delivers: impact metrics only from an impact level, the
    stop time only from a level that delivers it with every shoe of the brake modelled."""
    per_side = {}
    for side in SIDES:
        impact_cols = [f"{side}_{c}" for c in _IMPACT_COLUMNS]
        if not chosen.level.quasi_static_shoes and block.has(*impact_cols):
            per_side[side] = shoe_metrics(block, side, stop_time_s=stop)
        else:
            per_side[side] = contact_only_metrics(block, side, stop_time_s=stop)
    delivers_stop = "stop_time" in chosen.level.outputs and chosen.shoes == model_shoes
    return EventMetrics(per_side["left"], per_side["right"], stop if delivers_stop else None)


def run_scenario(
    scenario: Scenario,
    *,
    duration_s: float | None = None,
    method: str | None = None,
    progress: Callable[[float], None] | None = None,
) -> RunResult:
    """Integrate ``scenario`` over its duration (or ``duration_s``) at the level its needs
    call for (see :func:`brake_sim_ros.model.fidelity.plan`), and analyse it.

    ``method`` overrides the scenario's solver method (its largest step stays). Every
    impact-model method samples the scenario's sample rate: the fixed-step schemes
    (:func:`stepper_for`) and the reference alike, so their samples compare one to one.
    The contact-regime levels sample their macro step."""
    duration = scenario.duration_s if duration_s is None else duration_s
    chosen = plan(scenario.needs, model_shoes=scenario.setup.options.shoes)
    setup = planned_setup(scenario.setup, chosen)
    if chosen.level.quasi_static_shoes:
        if method == "reference":
            raise FidelityError(
                f"method 'reference' integrates the impact model; the scenario's needs chose"
                f" the level {chosen.level.name!r} (no impact dynamics): drop --method or force"
                " an impact level in [needs]"
            )
        method = "contact_regime"
    else:
        scenario = scenario.with_solver(method=method)
        method = scenario.solver.method
    options = MethodOptions(
        sample_period_s=scenario.sample_period_s,
        max_step_s=scenario.solver.max_step_s,
        rtol=scenario.solver.rtol,
        accuracy=chosen.accuracy,
        keep=lambda block: _keep(block, chosen.columns),
        progress=progress,
    )
    start = time.process_time()
    run = METHODS[method].integrate(setup, duration, options)
    cpu = time.process_time() - start
    samples, stop = run.samples, run.stop_time_s
    return RunResult(
        samples=samples,
        metrics=_metrics(samples, stop, chosen, scenario.setup.options.shoes),
        cpu_s=cpu,
        n_steps=run.n_steps,
        method=method,
        plan=chosen,
        model_stop_time_s=stop,
        step_note=run.note,
    )
