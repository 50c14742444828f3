"""Run a scenario to the end with its chosen solver; one result type for both solvers."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

from brake_sim_ros.analysis.impacts import EventMetrics, event_metrics
from brake_sim_ros.model.trajectory import SampleBlock
from brake_sim_ros.scenarios.loader import Scenario
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.solvers.reference import run_reference


@dataclass(frozen=True)
class RunResult:
    """A finished run.

    Attributes:
        samples: the recorded time history.
        metrics: impacts, periods, peak and contact-regime forces, stop time.
        cpu_s: process CPU time spent integrating, s.
        n_steps: fixed steps taken (fixed-step schemes) or right-hand-side evaluations
            (reference).
        method: the fixed-step scheme or "reference".

    A run that fails raises (SimulationError, StepSizeError) instead of returning.
    """

    samples: SampleBlock
    metrics: EventMetrics
    cpu_s: float
    n_steps: int
    method: str

    @property
    def stop_time_s(self) -> float | None:
        return self.metrics.stop_time_s


def run_scenario(
    scenario: Scenario,
    *,
    duration_s: float | None = None,
    method: str | None = None,
    dt_s: float | None = None,
    progress: Callable[[float], None] | None = None,
) -> RunResult:
    """Integrate ``scenario`` over its duration (or ``duration_s``) and analyse it."""
    duration = scenario.duration_s if duration_s is None else duration_s
    method = method or scenario.solver.method
    start = time.process_time()
    if method == "reference":
        ref = run_reference(scenario.setup, duration, rtol=scenario.solver.rtol)
        cpu = time.process_time() - start
        samples, stop, n = ref.samples, ref.stop_time_s, ref.n_rhs
    else:
        stepper = FixedStepStepper(scenario.setup, dt_s or scenario.solver.dt_s, scheme=method)
        samples = stepper.run(duration, progress=progress)
        cpu = time.process_time() - start
        stop, n = stepper.stop_time_s, stepper.step_index
    return RunResult(
        samples=samples,
        metrics=event_metrics(samples, stop_time_s=stop),
        cpu_s=cpu,
        n_steps=n,
        method=method,
    )
