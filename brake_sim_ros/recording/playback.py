"""A recording checked whole for replay: its topics, QoS and messages in log-time order.

The file is read by the checked reader (:mod:`brake_sim_ros.recording.reader`) and checked
whole when it is opened: every chunk's CRC, every message against the installed definition
of its type, the summary against the data. Only the types of the simulator's topic table
are accepted. ``brake_sim_ros.ros.replay`` publishes what this gives; nothing here talks
to ROS.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.recording import metadata
from brake_sim_ros.recording.reader import RecordingReadError, open_recording
from brake_sim_ros.stream.topics import QosSpec, offered_qos

_NS_PER_S = 1_000_000_000


@dataclass
class RecordedTopic:
    """One recorded channel: name, ROS type (``pkg/msg/Name``), QoS, message count."""

    name: str
    type_name: str
    qos: QosSpec
    count: int = 0
    channel_ids: list[int] = field(default_factory=list)


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
                profile = channel.qos or offered_qos(channel.topic)
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

    def brake(self) -> tuple[str, str]:
        """``(brake, "")``: the brake the recorded run simulated ("study" or "service"),
        from its ``brake_sim_model`` record (the run's model at the start of the
        recording); or ``("", why)``: why the recording does not say it (one clause)."""
        record = self._recording.metadata_record(metadata.MODEL)
        if record is None:
            return "", f"it has no {metadata.MODEL} metadata (not a brake-sim run's recording)"
        try:
            return metadata.model_from_record(record)[0].brake, ""
        except (BrakeSimError, ValueError, TypeError, KeyError, SyntaxError, RecursionError):
            return "", (
                f"its {metadata.MODEL} metadata is not a model this version reads (another"
                " version's recording?)"
            )

    def messages(self, start_ns: int | None = None) -> Iterator[tuple[str, bytes, int]]:
        """``(topic, CDR payload, log time ns)`` from ``start_ns`` on, in log-time order.

        Raises:
            RecordingReadError: the file changed since it was checked.
        """
        for message in self._recording.messages(topics=list(self.topics), start_ns=start_ns):
            yield message.topic.name, message.data, message.log_time_ns

    def latched_before(self, start_ns: int) -> list[tuple[str, bytes]]:
        """The newest message before ``start_ns`` of each transient-local topic."""
        latched = [t.name for t in self.topics.values() if t.qos.durability == "transient_local"]
        if not latched or start_ns <= self.start_ns:
            return []
        newest: dict[str, bytes] = {}
        for message in self._recording.messages(topics=latched, end_ns=start_ns):
            newest[message.topic.name] = message.data
        return list(newest.items())

    def close(self) -> None:
        self._recording.close()
