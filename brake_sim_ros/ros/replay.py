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
import yaml
from mcap.exceptions import McapError
from mcap.reader import make_reader
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.utilities import remove_ros_args

from brake_sim_ros.errors import BrakeSimError
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
    """The Python class of ROS type ``pkg/msg/Name`` (``pkg/Name`` accepted too)."""
    parts = type_name.split("/")
    if len(parts) == 2:
        parts = [parts[0], "msg", parts[1]]
    if len(parts) != 3 or not all(parts):
        raise BrakeSimError(f"message type '{type_name}': expected 'package/msg/Name'")
    package, kind, name = parts
    try:
        return getattr(importlib.import_module(f"{package}.{kind}"), name)
    except (ImportError, AttributeError):
        raise BrakeSimError(
            f"message type '{type_name}' is not installed here (no Python module"
            f" {package}.{kind} with {name}); source the workspace that provides it"
        ) from None


def _policy(value, enum, field_name: str):
    """A QoS policy from rosbag2's YAML: a name ("reliable") or the enum's integer."""
    if isinstance(value, str):
        try:
            return enum[value.upper()]
        except KeyError:
            raise BrakeSimError(f"QoS {field_name} '{value}' is unknown") from None
    return enum(int(value))


def qos_from_metadata(offered_qos_profiles: str) -> QoSProfile | None:
    """The first profile of rosbag2's ``offered_qos_profiles`` YAML, or None if absent.

    Only history, depth, reliability and durability are replayed; deadline, lifespan and
    liveliness stay at their defaults (the recorder's "infinite" defaults).
    """
    if not offered_qos_profiles.strip():
        return None
    try:
        profiles = yaml.safe_load(offered_qos_profiles)
    except yaml.YAMLError as exc:
        raise BrakeSimError(f"offered_qos_profiles is not YAML: {exc}") from None
    if not profiles:
        return None
    p = profiles[0]
    history = _policy(p.get("history", "keep_last"), HistoryPolicy, "history")
    if history == HistoryPolicy.SYSTEM_DEFAULT:
        history = HistoryPolicy.KEEP_LAST
    depth = int(p.get("depth", 10)) or 10
    return QoSProfile(
        history=history,
        depth=depth,
        reliability=_policy(p.get("reliability", "reliable"), ReliabilityPolicy, "reliability"),
        durability=_policy(p.get("durability", "volatile"), DurabilityPolicy, "durability"),
    )


@dataclass(frozen=True)
class Schedule:
    """When a recorded message is due: ``(log_time - start_ns) / rate`` s after the start."""

    start_ns: int
    rate: float

    def due_s(self, log_time_ns: int) -> float:
        return (log_time_ns - self.start_ns) / _NS_PER_S / self.rate


class Recording:
    """An MCAP file opened for replay: its topics and its messages in log-time order."""

    def __init__(self, path: Path, topics: list[str] | None = None) -> None:
        self.path = path
        if not path.is_file():
            raise BrakeSimError(f"recording {path}: no such file")
        self._file = path.open("rb")
        try:
            reader = make_reader(self._file)
            summary = reader.get_summary()
        except (McapError, ValueError, EOFError) as exc:
            self._file.close()
            raise BrakeSimError(
                f"recording {path} cannot be read ({exc}); if it was cut short, restore it"
                " with: brake-sim recover BROKEN.mcap FIXED.mcap"
            ) from None
        if summary is None or summary.statistics is None:
            self._file.close()
            raise BrakeSimError(
                f"recording {path} has no summary (not closed cleanly?); restore it with:"
                " brake-sim recover BROKEN.mcap FIXED.mcap"
            )
        self._reader = reader
        self.start_ns = summary.statistics.message_start_time
        self.end_ns = summary.statistics.message_end_time
        self.topics: dict[str, RecordedTopic] = {}
        for channel in summary.channels.values():
            schema = summary.schemas.get(channel.schema_id)
            if channel.message_encoding != "cdr" or schema is None:
                continue  # not a ROS 2 message: nothing to publish it as
            known = self.topics.get(channel.topic)
            if known is None:
                profile = qos_from_metadata(channel.metadata.get("offered_qos_profiles", ""))
                known = self.topics[channel.topic] = RecordedTopic(
                    channel.topic,
                    schema.name,
                    profile or _KNOWN_QOS.get(channel.topic, _DEFAULT_QOS),
                )
            known.channel_ids.append(channel.id)
            known.count += summary.statistics.channel_message_counts.get(channel.id, 0)
        if topics is not None:
            missing = sorted(set(topics) - self.topics.keys())
            if missing:
                raise BrakeSimError(
                    f"topic(s) {missing} are not in {path}; it holds {sorted(self.topics)}"
                )
            self.topics = {t: self.topics[t] for t in topics}
        if not self.topics:
            raise BrakeSimError(f"recording {path} holds no ROS 2 (cdr) messages")
        self._channel_topic = {cid: t.name for t in self.topics.values() for cid in t.channel_ids}

    @property
    def duration_s(self) -> float:
        return (self.end_ns - self.start_ns) / _NS_PER_S

    def messages(self, start_ns: int | None = None) -> Iterator[tuple[str, bytes, int]]:
        """``(topic, CDR payload, log time ns)`` from ``start_ns`` on, in log-time order."""
        for _schema, channel, message in self._reader.iter_messages(
            topics=list(self.topics), start_time=start_ns, log_time_order=True
        ):
            topic = self._channel_topic.get(channel.id)
            if topic is not None:
                yield topic, bytes(message.data), message.log_time

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
        for _schema, channel, message in self._reader.iter_messages(
            topics=latched, end_time=start_ns, log_time_order=True
        ):
            newest[channel.topic] = bytes(message.data)
        return list(newest.items())

    def close(self) -> None:
        self._file.close()


class ReplayNode(Node):
    """Publishes a :class:`Recording` with its original timing (or ``rate`` times faster)."""

    def __init__(self, recording: Recording, *, rate: float, start_offset_s: float) -> None:
        super().__init__(NODE_NAME)
        self.recording = recording
        self.rate = rate
        self.start_ns = recording.start_ns + round(start_offset_s * _NS_PER_S)
        self.published = 0
        self.loops = 0
        self._publishers_by_topic = {
            t.name: self.create_publisher(message_class(t.type_name), t.name, t.qos)
            for t in recording.topics.values()
        }

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
    except (KeyboardInterrupt, ExternalShutdownException):
        return 0
    finally:
        if node is not None:
            node.destroy_node()
        recording.close()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main())
