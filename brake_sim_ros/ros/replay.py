"""Replay an MCAP recording on ROS 2 with its original timing: ``brake-sim replay FILE.mcap``.

Every recorded message is published again, byte for byte (its CDR payload goes out
as-is), on its recorded topic with its recorded type and QoS, at the wall time its log
time calls for: ``(log_time - start) / rate`` after the replay starts. Recorded /clock
messages go out like any other, so subscribers with ``use_sim_time`` follow the
recording's simulated time; stamps inside messages are untouched. To a monitoring node a
replay looks like the live run.

Options:
    --rate R            replay speed factor (default 1: the original timing)
    --start-offset S    skip the first S seconds of the recording (log time)
    --loop              start again at the end, until interrupted
    --topics T [T ...]  replay only these topics (default: all)
    --wait-for-subscribers N  wait (up to 10 s) until every topic has N matched subscribers

Topics whose QoS keeps the last message for late joiners (transient local, e.g. the
defect ground truth) get the newest message recorded before the start offset published
at the start, so a replay from an offset still carries the ground truth in force.

The recording is read by the checked reader (:mod:`brake_sim_ros.recording.reader`) and
checked whole before the node is created: every chunk's CRC, every message against the
installed definition of its type, the summary against the data. Only the types of the
simulator's topic table are published (a type name from the file never picks a module to
import). A damaged or foreign file is refused with one line and nothing is published;
``brake-sim recover`` keeps its intact chunks.
"""

from __future__ import annotations

import argparse
import importlib
import math
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import rclpy
from rclpy.exceptions import InvalidTopicNameException
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from rclpy.utilities import remove_ros_args

from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.recording.cdr import RECORDED_TYPES
from brake_sim_ros.recording.reader import RecordingReadError, open_recording
from brake_sim_ros.ros import qos, stream

NODE_NAME = "brake_sim_replay"
_NS_PER_S = 1_000_000_000
MAX_SLEEP_S = 0.05  # the replay loop wakes at least this often (Ctrl-C, shutdown)
# QoS of the simulator's own topics, used when a recording carries none
_KNOWN_QOS = {
    stream.PIVOT_FORCES.name: qos.STREAM,
    stream.STATE.name: qos.STREAM,
    stream.JOINT_STATES.name: qos.STREAM,
    stream.DEFECTS.name: qos.LATCHED,
    stream.CLOCK.name: qos.CLOCK,
    stream.DIAGNOSTICS.name: qos.DIAGNOSTICS,
    stream.ACTUATION.name: qos.COMMANDS,
    stream.CONTACT_EVENTS.name: qos.EVENTS,
}
_DEFAULT_QOS = qos.STREAM


@dataclass
class RecordedTopic:
    """One recorded channel: name, ROS type (``pkg/msg/Name``), QoS, message count."""

    name: str
    type_name: str
    qos: QoSProfile
    count: int = 0
    channel_ids: list[int] = field(default_factory=list)


def message_class(type_name: str):
    """The Python class of a type of the topic table (``pkg/msg/Name``).

    Only those types are imported, from the module the table's name gives; any other
    name is refused before anything is imported.
    """
    if type_name not in RECORDED_TYPES:
        raise BrakeSimError(
            f"message type {type_name!r} is not one this project publishes; allowed: "
            + ", ".join(sorted(RECORDED_TYPES))
        )
    package, kind, name = type_name.split("/")
    try:
        return getattr(importlib.import_module(f"{package}.{kind}"), name)
    except (ImportError, AttributeError):
        raise BrakeSimError(
            f"message type {type_name} is not installed here (no Python module"
            f" {package}.{kind} with {name}); run scripts/setup.sh or source the workspace"
            " that provides it"
        ) from None


@dataclass(frozen=True)
class Schedule:
    """When a recorded message is due: ``(log_time - start_ns) / rate`` s after the start."""

    start_ns: int
    rate: float

    def due_s(self, log_time_ns: int) -> float:
        return (log_time_ns - self.start_ns) / _NS_PER_S / self.rate


class Recording:
    """An MCAP file checked whole for replay: its topics and its messages in log-time order.

    Raises:
        BrakeSimError: (RecordingReadError) a file the checked reader refuses, a topic
            recorded with two types, ``topics`` it does not hold, or no message at all.
    """

    def __init__(self, path: Path, topics: list[str] | None = None) -> None:
        self.path = path
        self._recording = open_recording(path)
        try:
            self._select(topics)
        except BaseException:
            self._recording.close()
            raise

    def _select(self, topics: list[str] | None) -> None:
        recording = self._recording
        self.topics: dict[str, RecordedTopic] = {}
        for channel in recording.channels.values():
            name, type_name = channel.topic.name, channel.topic.type_name
            known = self.topics.get(name)
            if known is None:
                profile = channel.qos or _KNOWN_QOS.get(name, _DEFAULT_QOS)
                known = self.topics[name] = RecordedTopic(name, type_name, profile)
            elif known.type_name != type_name:
                raise RecordingReadError(
                    f"{recording.name}: topic {name} is recorded as {known.type_name} and as"
                    f" {type_name}; allowed one type per topic"
                )
            known.channel_ids.append(channel.channel_id)
            known.count += channel.message_count
        if topics is not None:
            missing = sorted(set(topics) - self.topics.keys())
            if missing:
                raise BrakeSimError(
                    f"topic(s) {missing} are not in {recording.name}; it holds"
                    f" {sorted(self.topics)}"
                )
            self.topics = {t: self.topics[t] for t in topics}
        if recording.start_ns is None or recording.end_ns is None:
            raise BrakeSimError(f"recording {recording.name} holds no messages")
        self.start_ns, self.end_ns = recording.start_ns, recording.end_ns

    @property
    def duration_s(self) -> float:
        return (self.end_ns - self.start_ns) / _NS_PER_S

    def messages(self, start_ns: int | None = None) -> Iterator[tuple[str, bytes, int]]:
        """``(topic, CDR payload, log time ns)`` from ``start_ns`` on, in log-time order.

        Raises:
            RecordingReadError: the file changed since it was checked.
        """
        for message in self._recording.messages(topics=list(self.topics), start_ns=start_ns):
            yield message.topic.name, message.data, message.log_time_ns

    def latched_before(self, start_ns: int) -> list[tuple[str, bytes]]:
        """The newest message before ``start_ns`` of each transient-local topic."""
        latched = [
            t.name
            for t in self.topics.values()
            if t.qos.durability == DurabilityPolicy.TRANSIENT_LOCAL
        ]
        if not latched or start_ns <= self.start_ns:
            return []
        newest: dict[str, bytes] = {}
        for message in self._recording.messages(topics=latched, end_ns=start_ns):
            newest[message.topic.name] = message.data
        return list(newest.items())

    def close(self) -> None:
        self._recording.close()


class ReplayNode(Node):
    """Publishes a :class:`Recording` with its original timing (or ``rate`` times faster)."""

    def __init__(self, recording: Recording, *, rate: float, start_offset_s: float) -> None:
        super().__init__(NODE_NAME)
        self.recording = recording
        self.rate = rate
        self.start_ns = recording.start_ns + round(start_offset_s * _NS_PER_S)
        self.published = 0
        self.loops = 0
        self._publishers_by_topic = {}
        for t in recording.topics.values():
            try:
                publisher = self.create_publisher(message_class(t.type_name), t.name, t.qos)
            except InvalidTopicNameException:
                raise BrakeSimError(
                    f"topic {t.name} of {recording.path}: not a topic name ROS accepts"
                ) from None
            self._publishers_by_topic[t.name] = publisher

    def wait_for_subscribers(self, count: int, timeout_s: float) -> bool:
        """Wait until every topic has ``count`` matched subscriptions (True) or time out."""
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            pubs = self._publishers_by_topic.values()
            if all(p.get_subscription_count() >= count for p in pubs):
                return True
            time.sleep(0.02)
        return False

    def play_once(self) -> None:
        """One pass from the start offset to the end of the recording."""
        for topic, data in self.recording.latched_before(self.start_ns):
            self._publish(topic, data)
        schedule = Schedule(self.start_ns, self.rate)
        wall0 = time.monotonic()
        for topic, data, log_ns in self.recording.messages(self.start_ns):
            due = wall0 + schedule.due_s(log_ns)
            while True:
                wait = due - time.monotonic()
                if wait <= 0.0:
                    break
                if not rclpy.ok():
                    return
                time.sleep(min(wait, MAX_SLEEP_S))
            self._publish(topic, data)
        self.loops += 1

    def _publish(self, topic: str, data: bytes) -> None:
        self._publishers_by_topic[topic].publish(data)
        self.published += 1


def _parse_cli(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="brake-sim replay",
        description="Publish an MCAP recording on ROS 2 with its original timing.",
    )
    parser.add_argument("recording", type=Path, help="MCAP file (brake-sim --record/--mcap)")
    parser.add_argument("--rate", type=float, default=1.0, help="speed factor (default 1)")
    parser.add_argument(
        "--start-offset", type=float, default=0.0, metavar="S", help="skip the first S seconds"
    )
    parser.add_argument("--loop", action="store_true", help="play again from the start offset")
    parser.add_argument("--topics", nargs="+", metavar="TOPIC", help="only these topics")
    parser.add_argument(
        "--wait-for-subscribers",
        type=int,
        default=0,
        metavar="N",
        help="before playing, wait up to 10 s for N subscribers on every topic",
    )
    args = parser.parse_args(argv)
    if not (math.isfinite(args.rate) and args.rate > 0):
        parser.error(f"--rate {args.rate}: allowed a finite factor > 0")
    if not (math.isfinite(args.start_offset) and args.start_offset >= 0):
        parser.error(f"--start-offset {args.start_offset}: allowed a finite time >= 0 s")
    if args.wait_for_subscribers < 0:
        parser.error(f"--wait-for-subscribers {args.wait_for_subscribers}: allowed >= 0")
    return args


def main(args: list[str] | None = None) -> int:
    """Replay until the end (or, with --loop, until interrupted).

    Args:
        args: command line like ``sys.argv`` (program name first); default ``sys.argv``.

    Returns:
        0 after a complete replay or Ctrl-C / SIGTERM, 1 for a recording that cannot be
        replayed, 2 for bad options.
    """
    argv = list(sys.argv if args is None else args)
    cli = _parse_cli(remove_ros_args(argv)[1:])
    try:
        recording = Recording(cli.recording, cli.topics)
    except BrakeSimError as exc:
        print(f"brake-sim replay: {exc}", file=sys.stderr)
        return 1
    if cli.start_offset >= recording.duration_s and recording.duration_s > 0:
        recording.close()
        print(
            f"brake-sim replay: --start-offset {cli.start_offset:g} s is past the end of"
            f" {cli.recording} ({recording.duration_s:.6g} s)",
            file=sys.stderr,
        )
        return 1
    rclpy.init(args=argv)
    node = None
    try:
        try:
            node = ReplayNode(recording, rate=cli.rate, start_offset_s=cli.start_offset)
        except BrakeSimError as exc:
            print(f"brake-sim replay: {exc}", file=sys.stderr)
            return 1
        topics = ", ".join(f"{t.name} ({t.count})" for t in recording.topics.values())
        print(
            f"brake-sim replay: {cli.recording}, {recording.duration_s:.3f} s at {cli.rate:g}x"
            f" from {cli.start_offset:g} s: {topics}",
            flush=True,
        )
        if cli.wait_for_subscribers and not node.wait_for_subscribers(
            cli.wait_for_subscribers, 10.0
        ):
            print("brake-sim replay: not every topic has its subscribers; playing anyway")
        while rclpy.ok():
            node.play_once()
            if not cli.loop:
                break
        print(f"brake-sim replay: published {node.published} messages", flush=True)
        return 0
    except RecordingReadError as exc:  # the file changed after it was checked
        print(f"brake-sim replay: {exc}", file=sys.stderr)
        return 1
    except (KeyboardInterrupt, ExternalShutdownException):
        return 0
    finally:
        if node is not None:
            node.destroy_node()
        recording.close()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main())
