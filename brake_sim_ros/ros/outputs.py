"""Where the node's messages go: its publishers and its sinks (a recorder, a viewer).

:class:`NodeOutputs` publishes each message of the run session on its topic (under the
name the node resolved) and hands it to every sink; a publisher that raises costs that
message, a sink that raises is dropped and closed, and the simulation goes on either way
(counted in the node's :class:`~brake_sim_ros.ros.diagnostics.RunStats`). Accepted
commands and parameter changes reach the sinks too, stamped with the sample they take
effect at, so that a recording can be re-simulated.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from rclpy.exceptions import ParameterException
from rclpy.node import Node
from rclpy.qos_overriding_options import InvalidQosOverridesError

from brake_sim_ros import stream
from brake_sim_ros.errors import ParameterError
from brake_sim_ros.ros import qos
from brake_sim_ros.ros.diagnostics import RunStats
from brake_sim_ros.ros.messages import message_class
from brake_sim_ros.stream import MessageSink, Topic
from brake_sim_ros.stream.topics import RELIABILITY_POLICIES


def _publisher(node: Node, topic: Topic) -> Any:
    """``topic``'s publisher, with the QoS overrides the operator gave (one line if bad)."""
    try:
        return node.create_publisher(
            message_class(topic.type_name),
            topic.relative,
            qos.for_topic(topic),
            qos_overriding_options=qos.PUBLISHER_OVERRIDES,
        )
    except (InvalidQosOverridesError, ParameterException, RuntimeError, ValueError) as exc:
        # rclpy's message may echo a hostile value at any length: name the parameters only
        name = f"qos_overrides.{node.resolve_topic_name(topic.relative)}.publisher"
        reason = exc.__class__.__name__
        raise ParameterError(
            f"--ros-args override refused: {name}.depth and .reliability ({reason}): allowed"
            f" depth an integer from 1 to {qos.MAX_DEPTH}, reliability one of"
            f" {', '.join(RELIABILITY_POLICIES)}"
        ) from None


class NodeOutputs:
    """The publishers of ``node`` (every published topic; ~/measured only when
    ``measured``) and the sinks that receive the same messages.

    Args:
        node: the node that owns the publishers (and logs).
        stats: the node's counters (publish failures, unheard chunks, sink failures).
        measured: publish ~/measured.
    """

    def __init__(self, node: Node, stats: RunStats, *, measured: bool) -> None:
        self._node, self._stats = node, stats
        # canonical topic -> (publisher, the topic under the name this node resolved)
        self._outputs: dict[Topic, tuple[Any, Topic]] = {}
        for topic in stream.TOPICS:
            if topic.published and (topic is not stream.MEASURED or measured):
                pub = _publisher(node, topic)
                offered = dataclasses.replace(
                    topic, name=pub.topic_name, qos=qos.spec_of(pub.qos_profile)
                )
                self._outputs[topic] = (pub, offered)
        self.sinks: list[MessageSink] = []

    def subscriber_count(self, topic: Topic) -> int:
        """How many subscriptions ``topic``'s publisher has now (0 if not published)."""
        out = self._outputs.get(topic)
        return 0 if out is None else out[0].get_subscription_count()

    def emit(self, topic: Topic, msg: Any, ns: int) -> None:
        """Publish ``msg`` on ``topic`` and hand it to every sink, at simulated time ``ns``.

        A publisher that raises costs that message, counted in ``publish_failures``; a
        chunk published while nothing subscribes is counted in ``chunks_unheard``.
        """
        pub, resolved = self._outputs[topic]
        try:
            if topic is stream.PIVOT_FORCES and pub.get_subscription_count() == 0:
                self._stats.chunks_unheard += 1
            pub.publish(msg)
        except Exception as exc:  # the simulation and the sinks go on without it
            self._stats.publish_failures += 1
            self._node.get_logger().error(
                f"publishing on {resolved.name} failed: {type(exc).__name__}",
                throttle_duration_sec=1.0,
            )
        self.to_sinks(resolved, msg, ns)

    def to_sinks(self, topic: Topic, msg: Any, ns: int) -> None:
        """Hand ``msg`` to every sink only (a command the node received on ``topic``)."""
        for sink in list(self.sinks):
            try:
                sink.write(topic, msg, ns)
            except Exception as exc:  # a sink's failure must not stop the simulation
                self.drop(sink, f"{type(exc).__name__}: {exc}")

    def parameter_change(self, changes: dict, index: int, ns: int) -> None:
        """Hand an accepted parameter change to the sinks that record changes (a
        recording: ``parameter_change``), at the sample it takes effect at."""
        for sink in list(self.sinks):
            note = getattr(sink, "parameter_change", None)
            if note is None:
                continue
            try:
                note(changes, index, ns)
            except Exception as exc:  # a sink's failure must not stop the simulation
                self.drop(sink, f"{type(exc).__name__}: {exc}")

    def drop(self, sink: MessageSink, reason: str) -> None:
        """Stop feeding a failed sink and close it; the simulation goes on."""
        self.sinks.remove(sink)
        self._stats.sink_failures += 1
        logger = self._node.get_logger()
        logger.error(f"{sink!r} stopped: {reason}; the simulation goes on")
        try:
            sink.close()
        except Exception as exc:
            logger.error(f"{sink!r} could not be closed: {exc}")

    def close(self) -> None:
        """Close every sink (flushes recordings); each failure is logged, none is raised."""
        for sink in list(self.sinks):
            self.sinks.remove(sink)
            try:
                sink.close()
            except Exception as exc:
                self._stats.sink_failures += 1
                self._node.get_logger().error(f"{sink!r} could not be closed: {exc}")
