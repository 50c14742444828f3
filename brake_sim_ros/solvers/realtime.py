"""Can the streaming stepper keep up with the wall clock? Measurement and budget check.

Pure logic plus a short calibration run; no ROS. A real-time run publishes one chunk of
``chunk_samples`` samples every ``chunk_samples * sample_period_s / real_time_factor``
seconds of wall time (the chunk's wall period); the stepper takes its substeps inside.
The stepper may spend at most :data:`STEPPER_SHARE` of that period on a chunk: the rest is
for converting and publishing the chunk, the executor, and timer jitter.

The check is stated in terms of (stepper cost, sample period, chunk samples, real-time
factor), so a caller that chooses among solver presets can name the preset in the message
through ``label``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from brake_sim_ros.solvers.fixed_step import MIN_PHYSICS_STEP_S, FixedStepStepper

# Share of a chunk's wall period the stepper may use. Publishing a 256-sample chunk and
# its state messages costs the same order as stepping it in rclpy, so half the period is
# left for that, the executor and scheduling jitter.
STEPPER_SHARE = 0.5
# Wall time the start-up calibration may spend stepping, s (a few ms, not seconds).
CALIBRATION_WALL_S = 0.005
MIN_CALIBRATION_CHUNKS = 5


@dataclass(frozen=True)
class CostStats:
    """Distribution of the wall cost of one chunk, s."""

    n_chunks: int
    median_s: float
    p99_s: float
    p999_s: float
    max_s: float

    @classmethod
    def of(cls, costs_s: np.ndarray) -> CostStats:
        c = np.asarray(costs_s, dtype=float)
        if c.size == 0:
            raise ValueError("no chunk costs to summarise")
        return cls(
            n_chunks=int(c.size),
            median_s=float(np.median(c)),
            p99_s=float(np.quantile(c, 0.99)),
            p999_s=float(np.quantile(c, 0.999)),
            max_s=float(c.max()),
        )


@dataclass(frozen=True)
class RealtimeVerdict:
    """Outcome of :func:`check_realtime`.

    Attributes:
        ok: the stepper fits its share of the chunk period.
        chunk_cost_s: the measured (or estimated) wall cost of one chunk, s.
        chunk_period_s: wall time one chunk spans at the requested factor, s.
        budget_s: ``STEPPER_SHARE x chunk_period_s``, s.
        max_real_time_factor: the largest factor this cost keeps within the share.
        message: one line for the user: measured cost, budget, and what to change.
    """

    ok: bool
    chunk_cost_s: float
    chunk_period_s: float
    budget_s: float
    max_real_time_factor: float
    message: str


def check_realtime(
    chunk_cost_s: float,
    *,
    sample_period_s: float,
    chunk_samples: int,
    real_time_factor: float,
    label: str = "",
    share: float = STEPPER_SHARE,
) -> RealtimeVerdict:
    """Whether a stepper costing ``chunk_cost_s`` per chunk keeps ``real_time_factor``.

    Args:
        chunk_cost_s: wall cost of stepping one chunk, s (> 0).
        sample_period_s: time between samples, s.
        chunk_samples: samples per chunk (>= 1).
        real_time_factor: simulated seconds per wall second; 0 (as fast as possible)
            always passes.
        label: what is being run (scenario, solver preset), named in the message.
        share: share of the chunk period the stepper may use (0 < share <= 1).
    """
    if not (math.isfinite(chunk_cost_s) and chunk_cost_s > 0):
        raise ValueError(f"chunk_cost_s={chunk_cost_s!r}: allowed a finite cost > 0 s")
    if not (math.isfinite(sample_period_s) and sample_period_s > 0) or chunk_samples < 1:
        raise ValueError(
            f"sample_period_s={sample_period_s!r}, chunk_samples={chunk_samples!r}: allowed"
            " > 0 and >= 1"
        )
    if not (math.isfinite(real_time_factor) and real_time_factor >= 0):
        raise ValueError(f"real_time_factor={real_time_factor!r}: allowed a finite factor >= 0")
    if not 0 < share <= 1:
        raise ValueError(f"share={share!r}: allowed 0 < share <= 1")
    sim_s = chunk_samples * sample_period_s
    max_factor = share * sim_s / chunk_cost_s
    what = f" for {label}" if label else ""
    if real_time_factor == 0:
        return RealtimeVerdict(True, chunk_cost_s, math.inf, math.inf, max_factor, "")
    period = sim_s / real_time_factor
    budget = share * period
    ok = chunk_cost_s <= budget
    message = (
        f"one chunk of {chunk_samples} samples of {sample_period_s:g} s{what} costs"
        f" {1e6 * chunk_cost_s:.0f} us"
        f" of wall time on this machine; at real_time_factor {real_time_factor:g} a chunk spans"
        f" {1e6 * period:.0f} us and the stepper may use {100 * share:.0f} % of it"
        f" ({1e6 * budget:.0f} us)"
    )
    if ok:
        message += f": fits (up to real_time_factor {max_factor:.3g})"
    else:
        message += (
            f": too slow. Lower real_time_factor to at most {max_factor:.3g}, or use a faster"
            " solver preset or a lower sample rate, or a less loaded machine"
        )
    return RealtimeVerdict(ok, chunk_cost_s, period, budget, max_factor, message)


def measure_chunk_costs(
    stepper: FixedStepStepper,
    chunk_samples: int,
    *,
    max_chunks: int,
    wall_budget_s: float = math.inf,
    min_chunks: int = 1,
    actuation_n: tuple[float, float] | None = None,
    clock: Callable[[], float] = time.perf_counter,
) -> np.ndarray:
    """Wall cost of successive ``stepper.advance(chunk_samples)`` calls, s.

    Stops after ``max_chunks`` chunks, or once ``wall_budget_s`` is spent and at least
    ``min_chunks`` were taken. The stepper is advanced: pass one made for the purpose.
    """
    costs = []
    start = clock()
    while len(costs) < max_chunks:
        t0 = clock()
        stepper.advance(chunk_samples, actuation_n=actuation_n)
        costs.append(clock() - t0)
        if len(costs) >= min_chunks and clock() - start >= wall_budget_s:
            break
    return np.asarray(costs)


def probe_forces(stepper: FixedStepStepper, force_n: float) -> tuple[float, float] | None:
    """The actuation a cost probe steps ``stepper`` with: ``force_n`` on both shoes, or
    None (its own history) for a run with a drive cycle, which commands the brake itself
    and refuses other forces."""
    return None if stepper.setup.cycle is not None else (force_n, force_n)


def calibrate_chunk_cost(
    stepper: FixedStepStepper,
    chunk_samples: int,
    *,
    force_n: float,
    wall_budget_s: float = CALIBRATION_WALL_S,
) -> CostStats:
    """Short calibration: the per-chunk cost of ``stepper`` (a throwaway one, at t = 0,
    e.g. ``node_stepper.fresh()``) on this machine.

    The shoes are driven by ``force_n`` from t = 0, so the calibration steps through the
    contact code (impacts, then contact), the costlier branch of the model, at the substeps
    that force needs; a run with a drive cycle (``[cycle]``) is calibrated on its cycle.
    Takes about ``wall_budget_s`` of wall time (at least MIN_CALIBRATION_CHUNKS chunks).
    """
    force = probe_forces(stepper, force_n)
    stepper.advance(1, actuation_n=force)  # kernel loaded, substeps picked, outside the timing
    costs = measure_chunk_costs(
        stepper,
        chunk_samples,
        max_chunks=10_000,
        wall_budget_s=wall_budget_s,
        min_chunks=MIN_CALIBRATION_CHUNKS,
        actuation_n=force,
    )
    return CostStats.of(costs)


# -- the whole pipeline: stepping and publishing ------------------------------------------------
# Share of a chunk's wall period stepping and publishing together may use; the rest is the
# executor's (timer ticks, services) and scheduling jitter.
PIPELINE_SHARE = 0.7
# Work bounds of one chunk, whatever the pacing: a chunk is stepped in one go inside one
# executor callback, so it must stay short and small.
MAX_CHUNK_SAMPLES = 65_536  # a SampleBlock of this many samples is about 20 MB
MAX_PHYSICS_STEPS_PER_CHUNK = 200_000  # about 0.3 s at 1.3 us per step (rk4-located, here)
MAX_CHUNK_WALL_S = 0.1  # measured cost of stepping one chunk, s


@dataclass(frozen=True)
class PipelineCosts:
    """Measured wall costs of what one chunk causes, s.

    Attributes:
        step_per_sample_s: stepping, per sample (calibration median / chunk samples).
        chunk_fixed_s: converting and publishing one PivotForceChunk and one Clock, the
            part independent of the chunk's length.
        chunk_per_sample_s: the same, per sample of the chunk.
        state_row_s: converting and publishing one BrakeState and one JointState.
    """

    step_per_sample_s: float
    chunk_fixed_s: float = 0.0
    chunk_per_sample_s: float = 0.0
    state_row_s: float = 0.0

    def publish_s(self, chunk_samples: int, state_stride: int) -> float:
        """Publishing cost of one chunk with a state row every ``state_stride`` samples."""
        rows = math.ceil(chunk_samples / max(1, state_stride))
        return (
            self.chunk_fixed_s + self.chunk_per_sample_s * chunk_samples + self.state_row_s * rows
        )

    def per_sample_s(self, chunk_samples: int, state_stride: int) -> float:
        """Stepping and publishing, per sample, at these settings."""
        return self.step_per_sample_s + self.publish_s(chunk_samples, state_stride) / max(
            1, chunk_samples
        )


def check_chunk_work(substeps: int, chunk_samples: int, physics_step_s: float) -> str | None:
    """Why one chunk of ``chunk_samples`` samples of ``substeps`` physics steps each is too
    much work for one executor callback, or None when it is not."""
    if not physics_step_s >= MIN_PHYSICS_STEP_S:
        return (
            f"a physics step of {physics_step_s:.3g} s: allowed at least {MIN_PHYSICS_STEP_S:g} s"
            " (solver max_step_s of the scenario)"
        )
    if chunk_samples > MAX_CHUNK_SAMPLES:
        return (
            f"{chunk_samples} samples per chunk: allowed at most {MAX_CHUNK_SAMPLES} (raise"
            " chunk_rate_hz, or use a lower sample rate)"
        )
    steps = substeps * chunk_samples
    if steps > MAX_PHYSICS_STEPS_PER_CHUNK:
        return (
            f"{chunk_samples} samples x {substeps} physics steps = {steps} steps per chunk:"
            f" allowed at most {MAX_PHYSICS_STEPS_PER_CHUNK} (a larger solver max_step_s, a"
            " lower sample rate or a higher chunk_rate_hz)"
        )
    return None


def check_pipeline(
    costs: PipelineCosts,
    *,
    sample_period_s: float,
    chunk_samples: int,
    state_stride: int,
    real_time_factor: float,
    label: str = "",
) -> RealtimeVerdict:
    """Whether stepping and publishing one chunk fit its wall period at ``real_time_factor``.

    Two budgets: stepping alone within :data:`STEPPER_SHARE` of the period (as
    :func:`check_realtime`), and stepping plus publishing within :data:`PIPELINE_SHARE`.
    The message gives every figure.
    """
    step_s = costs.step_per_sample_s * chunk_samples
    publish_s = costs.publish_s(chunk_samples, state_stride)
    stepping = check_realtime(
        step_s,
        sample_period_s=sample_period_s,
        chunk_samples=chunk_samples,
        real_time_factor=real_time_factor,
        label=label,
    )
    sim_s = chunk_samples * sample_period_s
    total = step_s + publish_s
    max_factor = min(stepping.max_real_time_factor, PIPELINE_SHARE * sim_s / total)
    if real_time_factor == 0:
        return RealtimeVerdict(True, total, math.inf, math.inf, max_factor, "")
    period = sim_s / real_time_factor
    budget = PIPELINE_SHARE * period
    ok = stepping.ok and total <= budget
    rows = math.ceil(chunk_samples / max(1, state_stride))
    what = f" for {label}" if label else ""
    message = (
        f"one chunk of {chunk_samples} samples of {sample_period_s:g} s{what} costs"
        f" {1e6 * step_s:.0f} us stepping + {1e6 * publish_s:.0f} us publishing ({rows} state"
        f" rows of {1e6 * costs.state_row_s:.0f} us, the chunk"
        f" {1e6 * (costs.chunk_fixed_s + costs.chunk_per_sample_s * chunk_samples):.0f} us)"
        f" on this machine; at real_time_factor {real_time_factor:g} a chunk spans"
        f" {1e6 * period:.0f} us, of which stepping may use {100 * STEPPER_SHARE:.0f} % and"
        f" both {100 * PIPELINE_SHARE:.0f} % ({1e6 * budget:.0f} us)"
    )
    if ok:
        message += f": fits (up to real_time_factor {max_factor:.3g})"
    else:
        message += (
            f": too slow. Lower real_time_factor to at most {max_factor:.3g}, or lower"
            " state_rate_hz or chunk_rate_hz, or use a faster solver preset"
        )
    return RealtimeVerdict(ok, total, period, budget, max_factor, message)
