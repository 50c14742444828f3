"""Replay an MCAP recording on ROS 2 with its original timing: ``brake-sim replay FILE.mcap``.

Every recorded message is published again, byte for byte (its CDR payload goes out
as-is), on its recorded topic with its recorded type and QoS, at the wall time its log
time calls for: ``(log_time - start) / rate`` after the replay starts. Recorded /clock
messages go out like any other, so subscribers with ``use_sim_time`` follow the
recording's simulated time; stamps inside messages are untouched. To a monitoring node a
replay looks like the live run.

Options (rate, start offset, loop, topics): :mod:`brake_sim_ros.app.replay`.

The node says the brake the recorded run simulated in its read-only ROS parameter
``brake`` (the recording's ``brake_sim_model``; not declared when the recording does not
say it), as the simulator node does, so that ``brake-sim monitor`` asks it as it would
ask the simulator. :func:`serve` answers parameter requests beside the play.

Topics whose QoS keeps the last message for late joiners (transient local, e.g. the
defect ground truth) get the newest message recorded before the start offset published
at the start, so a replay from an offset still carries the ground truth in force.

The recording (:class:`brake_sim_ros.recording.playback.Recording`, handed in by
``brake_sim_ros.app.replay``) is checked whole before the node is created: every chunk's
CRC, every message against the installed definition of its type, the summary against the
data. Only the types of the
simulator's topic table are published (a type name from the file never picks a module to
import). A damaged or foreign file is refused with one line and nothing is published;
``brake-sim recover`` keeps its intact chunks.
"""

from __future__ import annotations

import contextlib
import dataclasses
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Protocol

import rclpy
from rclpy.exceptions import InvalidTopicNameException
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.ros import qos
from brake_sim_ros.ros.descriptors import descriptor
from brake_sim_ros.ros.messages import message_class
from brake_sim_ros.ros.node_parameters import BRAKE
from brake_sim_ros.stream.topics import QosSpec

NODE_NAME = "brake_sim_replay"
_NS_PER_S = 1_000_000_000
MAX_SLEEP_S = 0.05  # the replay loop wakes at least this often (Ctrl-C, shutdown)
# after a publisher matches its subscribers, the time given their side of discovery to
# match it back (loopback DDS: a few ms; a loaded machine: tens of ms)
MATCH_SETTLE_S = 0.25


class ReplayTopic(Protocol):
    name: str
    type_name: str
    qos: QosSpec


class ReplaySource(Protocol):
    """What the node replays: topics, the first log time and raw messages in order."""

    path: object
    start_ns: int

    @property
    def topics(self) -> dict[str, ReplayTopic]: ...

    def messages(self, start_ns: int | None = None) -> Iterator[tuple[str, bytes, int]]: ...

    def latched_before(self, start_ns: int) -> list[tuple[str, bytes]]: ...


@dataclass(frozen=True)
class Schedule:
    """When a recorded message is due: ``(log_time - start_ns) / rate`` s after the start."""

    start_ns: int
    rate: float

    def due_s(self, log_time_ns: int) -> float:
        return (log_time_ns - self.start_ns) / _NS_PER_S / self.rate


class ReplayNode(Node):
    """Publishes a recording with its original timing (or ``rate`` times faster)."""

    def __init__(
        self, recording: ReplaySource, *, rate: float, start_offset_s: float, brake: str = ""
    ) -> None:
        super().__init__(NODE_NAME)
        if brake:  # the recording's; nothing sets it later
            spec = dataclasses.replace(
                BRAKE,
                default=brake,
                description="The brake the recorded run simulated (the recording's"
                " brake_sim_model): study or service. Read-only.",
                constraints="study or service (the recording's)",
            )
            self.declare_parameter(spec.name, brake, descriptor(spec, read_only=True))
        self.recording = recording
        self.rate = rate
        self.start_ns = recording.start_ns + round(start_offset_s * _NS_PER_S)
        self.published = 0
        self.loops = 0
        self._publishers_by_topic = {}
        for t in recording.topics.values():
            try:
                publisher = self.create_publisher(
                    message_class(t.type_name), t.name, qos.profile(t.qos)
                )
            except InvalidTopicNameException:
                raise BrakeSimError(
                    f"topic {t.name} of {recording.path}: not a topic name ROS accepts"
                ) from None
            self._publishers_by_topic[t.name] = publisher

    def wait_for_subscribers(self, count: int, timeout_s: float) -> bool:
        """Wait until every topic has ``count`` matched subscriptions, then
        :data:`MATCH_SETTLE_S` more (True), or time out (False).

        The publisher's match is its side of discovery only: a subscriber that has not yet
        matched the publisher back drops what arrives before, and a volatile topic does not
        send it again, so the replay's first messages could be lost to it."""
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            pubs = self._publishers_by_topic.values()
            if all(p.get_subscription_count() >= count for p in pubs):
                time.sleep(MATCH_SETTLE_S)
                return True
            time.sleep(0.02)
        return False

    def play_once(self, stopped: Callable[[], bool] = lambda: not rclpy.ok()) -> None:
        """One pass from the start offset to the end of the recording, or until ``stopped()``
        (checked before every message and while waiting for one)."""
        for topic, data in self.recording.latched_before(self.start_ns):
            self._publish(topic, data)
        schedule = Schedule(self.start_ns, self.rate)
        wall0 = time.monotonic()
        for topic, data, log_ns in self.recording.messages(self.start_ns):
            due = wall0 + schedule.due_s(log_ns)
            while True:
                if stopped():
                    return
                wait = due - time.monotonic()
                if wait <= 0.0:
                    break
                time.sleep(min(wait, MAX_SLEEP_S))
            self._publish(topic, data)
        self.loops += 1

    def _publish(self, topic: str, data: bytes) -> None:
        self._publishers_by_topic[topic].publish(data)
        self.published += 1


@contextlib.contextmanager
def serve(node: Node) -> Iterator[None]:
    """Spin ``node`` on a thread of its own for the block (its parameter services answer
    while the caller's thread plays); the executor is shut down at the end."""
    executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)
    thread = threading.Thread(target=executor.spin, name="replay-services", daemon=True)
    thread.start()
    try:
        yield
    finally:
        executor.shutdown(timeout_sec=1.0)
        thread.join(timeout=1.0)
