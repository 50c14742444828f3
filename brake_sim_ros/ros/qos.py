"""QoS of every topic the node offers or takes, and why.

REP 2003 ("Sensor Data and Map QoS Settings") asks a sensor *driver* to publish raw data
with the system-default QoS (reliable, volatile) and its *consumers* to subscribe with the
sensor-data QoS (best effort, volatile, small keep-last depth). The simulated brake is
such a driver, so:

* ``~/pivot_forces``, ``~/state``, ``~/joint_states`` (:data:`STREAM`): reliable,
  volatile, keep last 10. A reliable publisher matches both reliable subscribers (rosbag2,
  rqt_plot, a lossless recorder) and best-effort ones, whereas a best-effort publisher
  would be invisible to reliable subscribers. The small depth bounds memory and latency;
  it never blocks the publisher. Consumers should use :data:`STREAM_CONSUMER`
  (= ``qos_profile_sensor_data``, best effort), the REP 2003 consumer profile: a slow
  consumer then loses samples (visible as a jump of ``first_sample_index``) instead of
  slowing anything down.
* ``~/contact_events`` (:data:`EVENTS`): reliable, volatile, keep last 100. Like
  :data:`STREAM`, but each message is a labelled event, not one sample of a signal a
  consumer can afford to thin out, and a chunk of a bouncing shoe can carry dozens at
  once; the deeper history keeps a burst whole for a reliable subscriber that is briefly
  slow. Consumers that need every label should subscribe reliable too.
* ``~/defects`` (:data:`LATCHED`): reliable, transient local, keep last 1, like a map in
  REP 2003: a late subscriber gets the ground truth in force at once.
* ``/clock`` (:data:`CLOCK`): best effort, volatile, keep last 1, rclcpp's ``ClockQoS``
  and what rclpy's ``use_sim_time`` subscription asks for. Only the newest time matters,
  and no slow clock subscriber can hold the simulation back.
* ``/diagnostics`` (:data:`DIAGNOSTICS`): reliable, volatile, keep last 10, as
  diagnostic_updater does.
* ``~/actuation`` subscription (:data:`COMMANDS`): best effort, keep last 10. A
  best-effort subscription matches every publisher (reliable ones included, e.g.
  ``ros2 topic pub``); only the newest command matters, so a lost one is replaced by the
  next.
"""

from __future__ import annotations

from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    QoSProfile,
    ReliabilityPolicy,
    qos_profile_sensor_data,
)

STREAM = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=10,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
STREAM_CONSUMER = qos_profile_sensor_data
EVENTS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=100,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
LATCHED = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
CLOCK = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.BEST_EFFORT,
    durability=DurabilityPolicy.VOLATILE,
)
DIAGNOSTICS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=10,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
COMMANDS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=10,
    reliability=ReliabilityPolicy.BEST_EFFORT,
    durability=DurabilityPolicy.VOLATILE,
)
