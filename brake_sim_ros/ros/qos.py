"""rclpy ``QoSProfile`` of the topic table's QoS (:mod:`brake_sim_ros.stream.topics`).

The table says which QoS each topic has and why; this module only translates.
"""

from __future__ import annotations

from rcl_interfaces.msg import SetParametersResult
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.qos_overriding_options import QoSOverridingOptions, QoSPolicyKind

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


def spec_of(profile: QoSProfile) -> QosSpec:
    """The table's form of an rclpy ``profile`` (what a publisher offers after overrides)."""
    return QosSpec(
        reliability=profile.reliability.name.lower(),
        durability=profile.durability.name.lower(),
        depth=profile.depth,
        history=profile.history.name.lower(),
    )


MAX_DEPTH = 100_000  # a keep-last history deeper than this is a typo, not a need


def _check_override(profile: QoSProfile) -> SetParametersResult:
    if profile.depth < 1 or profile.depth > MAX_DEPTH:
        reason = f"depth {profile.depth}: allowed an integer from 1 to {MAX_DEPTH}"
        return SetParametersResult(successful=False, reason=reason)
    return SetParametersResult(successful=True)


# the policies an operator may override on the node's publishers, the ROS 2 way
# (``-p qos_overrides./brake_sim/pivot_forces.publisher.depth:=2000``): a deeper history
# keeps a free-running node's burst for a reliable subscriber that is briefly slow
PUBLISHER_OVERRIDES = QoSOverridingOptions(
    [QoSPolicyKind.DEPTH, QoSPolicyKind.RELIABILITY], callback=_check_override
)


STREAM_CONSUMER = profile(STREAM_CONSUMER_QOS)  # REP 2003's consumer side of the stream
