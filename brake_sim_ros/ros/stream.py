"""What the simulator publishes, as a transport-free stream of ``(topic, message, time)``.

The node publishes this stream over DDS; recorders (MCAP), viewers (Rerun) and the
offline simulator consume the very same sequence, so a run recorded live and the same
run produced offline hold the same messages. Nothing here talks to rclpy's transport.

Topic names are the resolved ones of a node named ``brake_sim`` (the node itself uses
``~/...`` names, so a renamed node publishes under its own name; sinks attached to a node
receive the names it actually resolved). Times are simulated, integer nanoseconds.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any, Protocol

from brake_sim_ros.analysis.contact_events import ContactEventDetector
from brake_sim_ros.model.trajectory import SampleBlock
from brake_sim_ros.ros import conversion


@dataclass(frozen=True)
class Topic:
    """One published or subscribed topic: resolved name and ROS type (``pkg/msg/Name``)."""

    name: str
    type_name: str


PIVOT_FORCES = Topic("/brake_sim/pivot_forces", "brake_sim_msgs/msg/PivotForceChunk")
STATE = Topic("/brake_sim/state", "brake_sim_msgs/msg/BrakeState")
JOINT_STATES = Topic("/brake_sim/joint_states", "sensor_msgs/msg/JointState")
DEFECTS = Topic("/brake_sim/defects", "brake_sim_msgs/msg/DefectState")
CLOCK = Topic("/clock", "rosgraph_msgs/msg/Clock")
DIAGNOSTICS = Topic("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray")
ACTUATION = Topic("/brake_sim/actuation", "brake_sim_msgs/msg/ActuationCommand")
CONTACT_EVENTS = Topic("/brake_sim/contact_events", "brake_sim_msgs/msg/ContactEvent")

TOPICS = (
    PIVOT_FORCES,
    STATE,
    JOINT_STATES,
    DEFECTS,
    CLOCK,
    DIAGNOSTICS,
    ACTUATION,
    CONTACT_EVENTS,
)


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
) -> Iterator[tuple[Topic, Any, int]]:
    """The messages one published block produces, in publishing order.

    A PivotForceChunk (stamped with its first sample), the ContactEvents whose sample lies
    in the block (from ``contact_events``, which is fed the block and carries open contact
    episodes to the next one; each stamped with its own sample), one BrakeState and one
    JointState per sample index that is a multiple of ``state_stride``, and with
    ``with_clock`` a Clock at the time just after the block's last sample (the next
    sample's time).

    The detector is fed when the generator reaches the events, so consume the whole
    generator once per block, in order.
    """
    dt = block.sample_period_s
    yield (
        PIVOT_FORCES,
        conversion.pivot_force_chunk(block),
        conversion.stamp_ns(block.first_index, dt),
    )
    for event in contact_events.feed(block):
        msg = conversion.contact_event(event, dt)
        yield CONTACT_EVENTS, msg, conversion.stamp_ns(event.sample_index, dt)
    for row in conversion.state_rows(block, state_stride):
        ns = conversion.stamp_ns(block.first_index + row, dt)
        yield STATE, conversion.brake_state(block, row), ns
        yield JOINT_STATES, conversion.joint_state(block, row), ns
    if with_clock:
        ns = conversion.stamp_ns(block.first_index + len(block), dt)
        yield CLOCK, conversion.clock(ns), ns
