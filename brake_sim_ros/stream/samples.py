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
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.sensing.sensors import SensorBank
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


class MeasuredStream:
    """The sensors' part of the stream: sample blocks in, MeasuredChunks out, fewer and
    longer than the pivot-force chunks.

    Blocks are held until at least ``chunk_samples`` samples are pending; then the bank
    runs over all of them at once and one MeasuredChunk carries them (with the node's
    default rates, ten pivot-force chunks of 10 ms make one measured chunk of 100 ms). One
    call over many samples costs the sensors a fraction of ten calls over few (their state
    and tables stay in cache), and the values are the same bits either way: the bank
    carries its state from call to call. :meth:`flush` publishes what is pending; the
    node calls it wherever the stream stops (end of the run, pause, each ~/step, reset,
    failure, shutdown), so no measured sample waits for a stream that will not come.

    Attributes:
        bank: the scenario's sensors, carrying their state from chunk to chunk.
        chunk_samples: samples that make a measured chunk due, >= 1.
    """

    def __init__(self, bank: SensorBank, chunk_samples: int) -> None:
        if chunk_samples < 1:
            raise ValueError(f"chunk_samples={chunk_samples}: allowed >= 1")
        self.bank = bank
        self.chunk_samples = int(chunk_samples)
        self._pending: list[SampleBlock] = []
        self._count = 0

    @property
    def pending_samples(self) -> int:
        """Samples fed and not yet in a published chunk."""
        return self._count

    def feed(self, block: SampleBlock) -> Iterator[tuple[Topic, Any, int]]:
        """Hold ``block``; the MeasuredChunk of everything pending once it is due."""
        if len(block):
            self._pending.append(block)
            self._count += len(block)
        if self._count >= self.chunk_samples:
            yield from self.flush()

    def flush(self) -> Iterator[tuple[Topic, Any, int]]:
        """The MeasuredChunk of every pending sample (stamped with the first), if any."""
        if not self._pending:
            return
        blocks, self._pending, self._count = self._pending, [], 0
        block = blocks[0] if len(blocks) == 1 else SampleBlock.concatenate(blocks)
        frame = self.bank.advance(block)
        yield (
            MEASURED,
            conversion.measured_chunk(block, frame, self.bank),
            conversion.stamp_ns(block.first_index, block.sample_period_s),
        )


def block_messages(
    block: SampleBlock,
    state_stride: int,
    *,
    with_clock: bool,
    contact_events: ContactEventDetector,
    run_id: str,
    measured: MeasuredStream | None = None,
) -> Iterator[tuple[Topic, Any, int]]:
    """The messages one published block produces, in publishing order.

    A PivotForceChunk (stamped with its first sample), with ``measured`` the MeasuredChunk
    that this block makes due (:class:`MeasuredStream`: the sensors' state is carried to
    the next block), the ContactEvents whose sample lies
    in the block (from ``contact_events``, which is fed the block and carries open contact
    episodes to the next one; each stamped with its own sample), one BrakeState and one
    JointState per sample index that is a multiple of ``state_stride``, and with
    ``with_clock`` a Clock at the time just after the block's last sample (the next
    sample's time). ``run_id`` goes into every ContactEvent (the run's id, as in its
    DefectState).

    The measured stream and the detector are fed when the generator reaches their
    messages, so consume the whole generator once per block, in order.
    """
    dt = block.sample_period_s
    yield (
        PIVOT_FORCES,
        conversion.pivot_force_chunk(block),
        conversion.stamp_ns(block.first_index, dt),
    )
    if measured is not None:
        yield from measured.feed(block)
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
