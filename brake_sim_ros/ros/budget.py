"""Measure what a chunk costs on this machine: stepping, and converting plus publishing.

The node measures at start (and steps a new scenario's calibration at each ``~/reset``)
and refuses settings it cannot hold (:func:`~brake_sim_ros.solvers.realtime.check_pipeline`).
Publishing is timed on hidden publishers (``~/_budget/...``, same types and QoS as the
real topics) with no subscriber: what it measures is the Python conversion and rclpy
serialisation, the bulk of the cost; delivery to many subscribers costs more and is not
included.
"""

from __future__ import annotations

import dataclasses
import math
import statistics
import time

from brake_sim_ros import stream
from brake_sim_ros.analysis.contact_events import ContactEventDetector
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.ros import qos
from brake_sim_ros.ros.messages import message_class
from brake_sim_ros.sensing.sensors import SensorBank
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.solvers.realtime import (
    MAX_CHUNK_WALL_S,
    PipelineCosts,
    calibrate_chunk_cost,
    check_chunk_work,
    probe_forces,
)
from brake_sim_ros.stream import conversion

_REPEATS = 5
_PROBE_SAMPLES = 5  # one-sample timings before any whole chunk is stepped
_STATE_ROWS = 16
_BUDGET_RUN_ID = "0" * 32  # the messages priced are never seen: any id of the right size


def measure_stepping(
    stepper: FixedStepStepper, chunk_samples: int, *, force_n: float
) -> tuple[float, SampleBlock]:
    """Stepping cost per sample, s, and a block of ``chunk_samples`` samples to publish.

    ``stepper`` is a throwaway (``fresh()``). A probe of one sample first: work bounds
    (:func:`check_chunk_work`, at the substeps the force needs) and an estimate of the
    chunk's cost are checked before any whole chunk is stepped.

    Raises:
        BrakeSimError: one chunk would be more work than one executor callback may do.
    """
    force = probe_forces(stepper, force_n)
    stepper.advance(1, actuation_n=force)  # kernel loaded, substeps picked for the force
    reason = check_chunk_work(stepper.substeps, chunk_samples, stepper.physics_step_s)
    if reason:
        raise BrakeSimError(reason)
    # the fastest of a few one-sample timings: a single one is at the mercy of one
    # preemption by another process (milliseconds, which times a chunk becomes seconds)
    fastest = math.inf
    for _ in range(_PROBE_SAMPLES):
        t0 = time.perf_counter()
        stepper.advance(1, actuation_n=force)
        fastest = min(fastest, time.perf_counter() - t0)
    estimate = fastest * chunk_samples
    if estimate > 2 * MAX_CHUNK_WALL_S:  # one sample's timing is noisy: a wide margin
        raise BrakeSimError(
            f"one chunk of {chunk_samples} samples would take about {estimate:.2g} s of wall"
            f" time to step: allowed at most {MAX_CHUNK_WALL_S:g} s"
        )
    cost = calibrate_chunk_cost(stepper, chunk_samples, force_n=force_n)
    if cost.median_s > MAX_CHUNK_WALL_S:
        raise BrakeSimError(
            f"one chunk of {chunk_samples} samples takes {cost.median_s:.2g} s of wall time to"
            f" step: allowed at most {MAX_CHUNK_WALL_S:g} s"
        )
    block = stepper.advance(chunk_samples, actuation_n=force)
    return cost.median_s / chunk_samples, block


def _median_cost(action, repeats: int = _REPEATS) -> float:
    costs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        action()
        costs.append(time.perf_counter() - t0)
    return statistics.median(costs)


def measure_publishing(
    node, block: SampleBlock, step_per_sample_s: float, sensors: SensorBank | None = None
) -> PipelineCosts:
    """Publishing costs measured on hidden publishers of ``node``, with ``block``.

    The whole per-chunk pipeline (:func:`~brake_sim_ros.stream.block_messages`: the chunk,
    with ``sensors`` (a bank used for this only) a measured chunk of the same samples (the
    node's are longer, so this prices the sensors on the high side), the contact events
    the block holds, one state row, the clock) is timed on ``block``;
    a state row (BrakeState + JointState) and a one-sample chunk separately, so that the
    cost can be scaled to other chunk sizes and state rates.
    """
    topics = (
        stream.PIVOT_FORCES,
        stream.MEASURED,
        stream.CONTACT_EVENTS,
        stream.STATE,
        stream.JOINT_STATES,
        stream.CLOCK,
    )
    pubs = {
        t: node.create_publisher(
            message_class(t.type_name), f"~/_budget/{t.name.rsplit('/', 1)[-1]}", qos.for_topic(t)
        )
        for t in topics
    }
    try:
        n = len(block)

        def pipeline(b: SampleBlock) -> None:
            detector = ContactEventDetector()
            for topic, msg, _ns in stream.block_messages(
                b,
                len(b),
                with_clock=True,
                contact_events=detector,
                run_id=_BUDGET_RUN_ID,
                measured=None if sensors is None else stream.MeasuredStream(sensors, 1),
            ):
                pubs[topic].publish(msg)

        rows = min(_STATE_ROWS, n)

        def states() -> None:
            for row in range(rows):
                pubs[stream.STATE].publish(conversion.brake_state(block, row))
                pubs[stream.JOINT_STATES].publish(conversion.joint_state(block, row))

        state_row = _median_cost(states) / rows
        full = _median_cost(lambda: pipeline(block))
        one = _median_cost(lambda: pipeline(dataclasses.replace(block, data=block.data[:1])))
    finally:
        for pub in pubs.values():
            node.destroy_publisher(pub)
    per_sample = max(0.0, (full - one) / max(1, n - 1))
    fixed = max(0.0, full - per_sample * n - state_row)  # the one state row is priced apart
    return PipelineCosts(
        step_per_sample_s=step_per_sample_s,
        chunk_fixed_s=fixed,
        chunk_per_sample_s=per_sample,
        state_row_s=state_row,
    )


def step_costs(
    node,
    stepper: FixedStepStepper,
    *,
    label: str,
    chunk_samples: int,
    force_n: float,
    sensors: SensorBank | None,
    publishing: PipelineCosts | None = None,
) -> PipelineCosts:
    """Calibrate ``stepper`` (a fresh copy, at ``force_n`` N); publishing measured on
    ``node`` too (with ``sensors``) unless ``publishing`` is given, whose figures are kept.

    Raises:
        BrakeSimError: chunks too large for one callback, named with ``label``.
    """
    try:
        per_sample, block = measure_stepping(stepper.fresh(), chunk_samples, force_n=force_n)
    except BrakeSimError as exc:
        raise BrakeSimError(f"{label}: {exc}") from None
    if publishing is None:
        return measure_publishing(node, block, per_sample, sensors)
    return dataclasses.replace(publishing, step_per_sample_s=per_sample)


class Budget:
    """A node's wall-clock budget: the costs measured at start (or a scenario switch) and
    what whole chunks have cost since (moving average), for the real-time checks and the
    size of a ``~/step`` call.

    Args:
        costs: the measured costs (:func:`step_costs`).
        step_call_wall_s: wall time one ~/step call may hold the executor, s.
        max_step_request_s: simulated time one ~/step call may advance, s.
    """

    def __init__(
        self, costs: PipelineCosts, *, step_call_wall_s: float, max_step_request_s: float
    ) -> None:
        self.costs = costs
        self.observed_sample_cost_s = 0.0  # moving average over whole chunks, s
        self.step_call_wall_s = step_call_wall_s
        self.max_step_request_s = max_step_request_s

    def observe(self, cost_per_sample_s: float) -> None:
        """A whole chunk cost this much per sample (wall s), stepped and published."""
        previous = self.observed_sample_cost_s or cost_per_sample_s
        self.observed_sample_cost_s = 0.8 * previous + 0.2 * cost_per_sample_s

    def sample_cost_s(self, chunk_samples: int, state_stride: int) -> float:
        """Wall cost of one sample, stepped and published: the larger of the start-up
        estimate (no subscriber) and what whole chunks have cost so far (with the real
        subscribers, contact events and sinks)."""
        estimate = self.costs.per_sample_s(chunk_samples, state_stride)
        return max(estimate, self.observed_sample_cost_s)

    def max_step_samples(self, chunk_samples: int, state_stride: int, period_s: float) -> int:
        """Most samples one ~/step call may advance: ``step_call_wall_s`` of measured
        work (at least one chunk), at most ``max_step_request_s`` of simulated time."""
        per_sample = self.sample_cost_s(chunk_samples, state_stride)
        by_wall = max(chunk_samples, int(self.step_call_wall_s / per_sample))
        return min(by_wall, math.floor(self.max_step_request_s / period_s))
