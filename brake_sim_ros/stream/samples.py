"""What the simulator publishes, as a transport-free stream of ``(topic, message, time)``.

The node publishes this stream over DDS; recorders (MCAP), viewers (Rerun) and the
offline simulator consume the very same sequence, so a run recorded live and the same
run produced offline hold the same messages. Nothing here talks to rclpy's transport.

Topics, their types and QoS are those of :mod:`brake_sim_ros.stream.topics`. Times are
simulated, integer nanoseconds.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from typing import Any, Protocol

from brake_sim_ros.analysis.contact_events import ContactEventDetector
from brake_sim_ros.model.sensors import SensorBank
from brake_sim_ros.model.trajectory import SampleBlock
from brake_sim_ros.stream import conversion
from brake_sim_ros.stream.topics import (
    CLOCK,
    CONTACT_EVENTS,
    JOINT_STATES,
    MEASURED,
    PIVOT_FORCES,
    STATE,
    Topic,
)


def samples_per(rate_hz: float, sample_period_s: float) -> int:
    """Samples per period of ``rate_hz`` (chunks, state messages), at least 1: how the
    node and the offline stream both cut the sample stream."""
    return max(1, round(conversion.sample_rate_hz(sample_period_s) / rate_hz))


def deliver(messages: Iterable[tuple[Topic, Any, int]], sinks: Sequence[MessageSink]) -> None:
    """Write every ``(topic, message, time_ns)`` to every sink, in order (offline runs).

    A sink that raises stops the delivery; closing the sinks is the caller's (it knows
    how each must be finished)."""
    for topic, msg, ns in messages:
        for sink in sinks:
            sink.write(topic, msg, ns)


class MessageSink(Protocol):
    """Receives every message the simulator publishes or accepts, in order.

    ``write`` gets the resolved topic name, the message object (an instance of the
    topic's ROS message class) and the simulated time in ns at which it was produced.
    A sink that fails raises; its owner reports the failure, drops the sink and goes on.
    """

    def write(self, topic: Topic, msg: Any, time_ns: int) -> None: ...

    def close(self) -> None: ...


def block_messages(
    block: SampleBlock,
    state_stride: int,
    *,
    with_clock: bool,
    contact_events: ContactEventDetector,
    run_id: str,
    sensors: SensorBank | None = None,
) -> Iterator[tuple[Topic, Any, int]]:
    """The messages one published block produces, in publishing order.

    A PivotForceChunk (stamped with its first sample), with ``sensors`` a MeasuredChunk of
    the same samples (the bank is fed the block and carries its state to the next one:
    filters, noise generators, faults' holds), the ContactEvents whose sample lies
    in the block (from ``contact_events``, which is fed the block and carries open contact
    episodes to the next one; each stamped with its own sample), one BrakeState and one
    JointState per sample index that is a multiple of ``state_stride``, and with
    ``with_clock`` a Clock at the time just after the block's last sample (the next
    sample's time). ``run_id`` goes into every ContactEvent (the run's id, as in its
    DefectState).

    The bank and the detector are fed when the generator reaches their messages, so
    consume the whole generator once per block, in order.
    """
    dt = block.sample_period_s
    yield (
        PIVOT_FORCES,
        conversion.pivot_force_chunk(block),
        conversion.stamp_ns(block.first_index, dt),
    )
    if sensors is not None:
        frame = sensors.advance(block)
        yield (
            MEASURED,
            conversion.measured_chunk(block, frame, sensors),
            conversion.stamp_ns(block.first_index, dt),
        )
    for event in contact_events.feed(block):
        msg = conversion.contact_event(event, dt, run_id=run_id)
        yield CONTACT_EVENTS, msg, conversion.stamp_ns(event.sample_index, dt)
    for row in conversion.state_rows(block, state_stride):
        ns = conversion.stamp_ns(block.first_index + row, dt)
        yield STATE, conversion.brake_state(block, row), ns
        yield JOINT_STATES, conversion.joint_state(block, row), ns
    if with_clock:
        ns = conversion.stamp_ns(block.first_index + len(block), dt)
        yield CLOCK, conversion.clock(ns), ns
