"""The sample stream, transport-free: what the simulator publishes, as data.

``topics`` holds the one table of topics (name, type, QoS, rate); ``samples`` turns stepped
blocks into ``(topic, message, time_ns)``; ``conversion`` builds the messages; ``session``
is one run (start, advance, parameter changes, commands, reset), which ``offline``, the
node and re-simulation drive; ``run_parameters`` is the one table of run parameters;
``commands`` the actuation commands' rules; ``parameters`` maps the node's model
parameters onto the core's dataclasses and rebuilds the model from them. The node, the
MCAP recorder, the Rerun sink and the dataset writer all consume this one stream; nothing
here imports rclpy's transport, a file format or a viewer.
"""

from brake_sim_ros.stream.samples import (
    MeasuredStream,
    MessageSink,
    block_messages,
    samples_per,
)
from brake_sim_ros.stream.topics import (
    ACTUATION,
    CLOCK,
    CONTACT_EVENTS,
    DEFECTS,
    DIAGNOSTICS,
    DRIVE,
    JOINT_STATES,
    MEASURED,
    PIVOT_FORCES,
    STATE,
    TOPICS,
    Topic,
)

__all__ = [
    "ACTUATION",
    "CLOCK",
    "CONTACT_EVENTS",
    "DEFECTS",
    "DIAGNOSTICS",
    "DRIVE",
    "JOINT_STATES",
    "MEASURED",
    "PIVOT_FORCES",
    "STATE",
    "TOPICS",
    "MeasuredStream",
    "MessageSink",
    "Topic",
    "block_messages",
    "samples_per",
]
