"""rclpy ``QoSProfile`` of the topic table's QoS (:mod:`brake_sim_ros.stream.topics`).

The table says which QoS each topic has and why; this module only translates.
"""

from __future__ import annotations

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from brake_sim_ros.stream.topics import STREAM_CONSUMER_QOS, QosSpec, Topic


def profile(spec: QosSpec) -> QoSProfile:
    """The rclpy profile of ``spec`` (deadline, lifespan and liveliness at rmw defaults)."""
    return QoSProfile(
        history=HistoryPolicy[spec.history.upper()],
        depth=spec.depth,
        reliability=ReliabilityPolicy[spec.reliability.upper()],
        durability=DurabilityPolicy[spec.durability.upper()],
    )


def for_topic(topic: Topic) -> QoSProfile:
    """What the simulator offers (or asks, for its subscription) on ``topic``."""
    return profile(topic.qos)


STREAM_CONSUMER = profile(STREAM_CONSUMER_QOS)  # REP 2003's consumer side of the stream
