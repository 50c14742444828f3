"""The one table of topics: name, ROS type, QoS and rate of everything the simulator offers.

The node creates its publishers and subscription from it, the MCAP recorder writes each
channel's ``offered_qos_profiles`` from it, ``recover`` falls back on it, replay publishes
with it, and the test client subscribes with it. QoS is written here as plain data
(:class:`QosSpec`); ``brake_sim_ros.ros.qos`` turns it into rclpy's ``QoSProfile``.

Why each QoS: REP 2003 ("Sensor Data and Map QoS Settings") asks a sensor *driver* to
publish raw data with the system-default QoS (reliable, volatile) and its *consumers* to
subscribe with the sensor-data QoS (best effort, volatile, small keep-last depth). The
simulated brake is such a driver, so:

* ``pivot_forces``, ``measured``, ``state``, ``joint_states`` (:data:`STREAM_QOS`):
  reliable, volatile, keep last 10. A reliable publisher matches both reliable subscribers
  (rosbag2, rqt_plot, a lossless recorder) and best-effort ones, whereas a best-effort
  publisher would be invisible to reliable subscribers. The small depth bounds memory and
  latency; it never blocks the publisher. Consumers should use :data:`STREAM_CONSUMER_QOS`
  (= ``qos_profile_sensor_data``): a slow consumer then loses samples (visible as a jump of
  ``first_sample_index``) instead of slowing anything down.
* ``contact_events`` (:data:`EVENTS_QOS`): reliable, volatile, keep last 100. Each message
  is a labelled event, not one sample of a signal a consumer can afford to thin out, and a
  chunk of a bouncing shoe can carry dozens at once; the deeper history keeps a burst whole
  for a reliable subscriber that is briefly slow. Consumers that need every label should
  subscribe reliable too.
* ``defects`` (:data:`LATCHED_QOS`): reliable, transient local, keep last 1, like a map in
  REP 2003: a late subscriber gets the ground truth in force at once.
* ``/clock`` (:data:`CLOCK_QOS`): best effort, volatile, keep last 1, rclcpp's
  ``ClockQoS`` and what rclpy's ``use_sim_time`` subscription asks for. Only the newest
  time matters, and no slow clock subscriber can hold the simulation back.
* ``/diagnostics`` (:data:`DIAGNOSTICS_QOS`): reliable, volatile, keep last 10, as
  diagnostic_updater does.
* ``actuation`` and ``drive``, subscribed (:data:`COMMANDS_QOS`): best effort, keep
  last 10. A best-effort subscription matches every publisher (reliable ones included,
  e.g. ``ros2 topic pub``); only the newest command matters, so a lost one is replaced by
  the next (a drive command holds until the next: a rig that must not lose one publishes
  it reliably or again). They are recorded with that QoS too, so a replay offers commands
  as the node takes them.

Topic names are the resolved ones of a node named ``brake_sim`` (the node itself uses
``~/...`` names, so a renamed node publishes under its own name; sinks attached to a node
receive the names it actually resolved).
"""

from __future__ import annotations

from dataclasses import dataclass

# rosbag2's policy names, indexed by rmw's enum value (older rosbag2 wrote the numbers)
HISTORY_POLICIES = ("system_default", "keep_last", "keep_all")
RELIABILITY_POLICIES = ("system_default", "reliable", "best_effort", "best_available")
DURABILITY_POLICIES = ("system_default", "transient_local", "volatile", "best_available")


@dataclass(frozen=True)
class QosSpec:
    """A QoS profile as data: the four policies the simulator sets (others at defaults).

    Attributes:
        reliability: one of :data:`RELIABILITY_POLICIES`.
        durability: one of :data:`DURABILITY_POLICIES`.
        depth: keep-last history depth, >= 1.
        history: one of :data:`HISTORY_POLICIES`.
    """

    reliability: str
    durability: str
    depth: int
    history: str = "keep_last"

    def __post_init__(self) -> None:
        for value, allowed in (
            (self.reliability, RELIABILITY_POLICIES),
            (self.durability, DURABILITY_POLICIES),
            (self.history, HISTORY_POLICIES),
        ):
            if value not in allowed:
                raise ValueError(f"QoS policy {value!r}: allowed {', '.join(allowed)}")
        if isinstance(self.depth, bool) or not isinstance(self.depth, int) or self.depth < 1:
            raise ValueError(f"QoS depth {self.depth!r}: allowed an integer >= 1")


STREAM_QOS = QosSpec("reliable", "volatile", 10)
STREAM_CONSUMER_QOS = QosSpec("best_effort", "volatile", 5)  # = qos_profile_sensor_data
EVENTS_QOS = QosSpec("reliable", "volatile", 100)
LATCHED_QOS = QosSpec("reliable", "transient_local", 1)
CLOCK_QOS = QosSpec("best_effort", "volatile", 1)
DIAGNOSTICS_QOS = QosSpec("reliable", "volatile", 10)
COMMANDS_QOS = QosSpec("best_effort", "volatile", 10)


@dataclass(frozen=True)
class Topic:
    """One topic of the simulator.

    Attributes:
        name: resolved name (of a node named ``brake_sim``).
        type_name: ROS type, ``pkg/msg/Name``.
        qos: what the node offers (publishers) or asks (its subscription).
        rate: when messages come, in words, for the README and ``--help`` texts.
        relative: the name the node creates it under (``~/...`` or absolute).
        published: True for what the node publishes, False for what it subscribes.
    """

    name: str
    type_name: str
    qos: QosSpec = STREAM_QOS
    rate: str = ""
    relative: str = ""
    published: bool = True


PIVOT_FORCES = Topic(
    "/brake_sim/pivot_forces",
    "brake_sim_msgs/msg/PivotForceChunk",
    STREAM_QOS,
    "one chunk of samples per chunk period (parameter chunk_rate_hz, default 100 Hz)",
    "~/pivot_forces",
)
STATE = Topic(
    "/brake_sim/state",
    "brake_sim_msgs/msg/BrakeState",
    STREAM_QOS,
    "one message per state period (parameter state_rate_hz, default 100 Hz)",
    "~/state",
)
JOINT_STATES = Topic(
    "/brake_sim/joint_states",
    "sensor_msgs/msg/JointState",
    STREAM_QOS,
    "with each BrakeState",
    "~/joint_states",
)
CONTACT_EVENTS = Topic(
    "/brake_sim/contact_events",
    "brake_sim_msgs/msg/ContactEvent",
    EVENTS_QOS,
    "one per impact onset and contact change, in the chunk that holds it",
    "~/contact_events",
)
DEFECTS = Topic(
    "/brake_sim/defects",
    "brake_sim_msgs/msg/DefectState",
    LATCHED_QOS,
    "at start, reset and each change of a model parameter (latched)",
    "~/defects",
)
MEASURED = Topic(
    "/brake_sim/measured",
    "brake_sim_msgs/msg/MeasuredChunk",
    STREAM_QOS,
    "measured_rate_hz chunks per simulated second, default 10 Hz, and when the run ends,"
    " pauses, steps or resets (parameter publish_measured)",
    "~/measured",
)
CLOCK = Topic(
    "/clock",
    "rosgraph_msgs/msg/Clock",
    CLOCK_QOS,
    "after each chunk (parameter publish_clock)",
    "/clock",
)
DIAGNOSTICS = Topic(
    "/diagnostics",
    "diagnostic_msgs/msg/DiagnosticArray",
    DIAGNOSTICS_QOS,
    "every diagnostics_period_s of wall time (default 1 s)",
    "/diagnostics",
)
ACTUATION = Topic(
    "/brake_sim/actuation",
    "brake_sim_msgs/msg/ActuationCommand",
    COMMANDS_QOS,
    "as commanded (subscribed)",
    "~/actuation",
    published=False,
)
DRIVE = Topic(
    "/brake_sim/drive",
    "brake_sim_msgs/msg/DriveCommand",
    COMMANDS_QOS,
    "as commanded (subscribed)",
    "~/drive",
    published=False,
)

TOPICS = (
    PIVOT_FORCES,
    STATE,
    JOINT_STATES,
    DEFECTS,
    CLOCK,
    DIAGNOSTICS,
    ACTUATION,
    DRIVE,
    CONTACT_EVENTS,
    MEASURED,
)
TOPIC_BY_NAME = {t.name: t for t in TOPICS}
TOPIC_BY_TYPE = {t.type_name: t for t in TOPICS}  # each type has one topic
TYPES = frozenset(TOPIC_BY_TYPE)


def offered_qos(topic: Topic) -> QosSpec:
    """The QoS the simulator offers on ``topic``: the table's, found by name, then by type.

    A topic the simulator does not know (a renamed node's, say) gets the QoS of the
    table's topic of the same type, or :data:`STREAM_QOS`.
    """
    known = TOPIC_BY_NAME.get(topic.name) or TOPIC_BY_TYPE.get(topic.type_name)
    return known.qos if known is not None else STREAM_QOS
