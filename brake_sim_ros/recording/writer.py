"""``McapRecorder``: a :class:`~brake_sim_ros.stream.MessageSink` that writes a rosbag2 MCAP.

The file is what ``ros2 bag`` (rosbag2_storage_mcap, Jazzy) writes: profile ``ros2``, one
schema per type with its complete ``ros2msg`` definition (:mod:`.schemas`), channels with
``cdr`` encoding and rosbag2's ``offered_qos_profiles`` / ``topic_type_hash`` metadata,
log time = publish time = the simulated time in ns the stream gives each message, zstd (or
no) chunk compression, message indexes and a summary. The records of :mod:`.metadata`
make it explain itself.

Serialization. CDR (little endian, XCDR1 as ROS 2 uses it) by mcap_ros2's encoder, built
from the same complete definition the schema holds. Not ``rclpy.serialization.
serialize_message``: with Fast DDS (rmw_fastrtps, Jazzy wheels) its buffers carry
uninitialised alignment padding and trailing bytes (seen: 8 extra bytes of heap content
after a JointState), so the same message gave different bytes from run to run and leaked
process memory into the file. These bytes are deterministic and exactly as long as the
message; rclpy's ``deserialize_message`` and rosbags decode them to the same values (the
tests check both).

Bounded loss. A chunk is written only when it is closed, so a hard kill (SIGKILL, power
loss) loses the open chunk and nothing before it (:mod:`.recover`). The recorder closes
the open chunk whenever it spans ``flush_interval_s`` of simulated time or more: before
adding a message whose log time is ``flush_interval_s`` or more after the open chunk's
first one (or earlier than it, after a ~/reset), it calls ``mcap.Writer.flush()``, which
ends the chunk, writes it with its message indexes and flushes the stream. The stream is
unbuffered (each record batch of the mcap writer goes to the OS at once, also for chunks
the writer closes itself when they reach ``chunk_size_bytes``), and with ``durable`` the
file is fsync'ed at each such flush (power loss). So a crash loses less than
``flush_interval_s`` of simulated signal (or one ``chunk_size_bytes`` chunk, if that is
reached first).

Failures. Opening (path, permissions, a full disk: the header, metadata and channels are
written and flushed at once) raises :class:`RecordingError` naming the path and the cause;
a write that fails later raises it too and the recorder stops (the node drops it and
simulates on). Time is never taken from the wall clock here.
"""

from __future__ import annotations

import contextlib
import math
import os
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import mcap
from mcap.writer import CompressionType, Writer
from mcap_ros2._dynamic import EncoderFunction, serialize_dynamic

from brake_sim_ros import __version__
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.recording import metadata, schemas
from brake_sim_ros.stream import Topic

PROFILE = "ros2"
SCHEMA_ENCODING = "ros2msg"
MESSAGE_ENCODING = "cdr"
COMPRESSIONS = {"zstd": CompressionType.ZSTD, "none": CompressionType.NONE}
_BYTE_FIELD = re.compile(r"^\s*byte(\[[^\]]*\])?\s", re.MULTILINE)


class _ByteFieldsAsInts:
    """A read-only view of an rclpy message with ``byte`` values (``b"\x01"``) as ints.

    rclpy holds a ``byte`` field as a one-byte ``bytes``; mcap_ros2's encoder wants an
    int. Used only for types with a ``byte`` field somewhere (DiagnosticStatus.level).
    """

    __slots__ = ("_msg",)

    def __init__(self, msg: Any) -> None:
        self._msg = msg

    def __getattr__(self, name: str) -> Any:
        return _as_encodable(getattr(self._msg, name))


def _as_encodable(value: Any) -> Any:
    if isinstance(value, bytes) and len(value) == 1:
        return value[0]
    if isinstance(value, list):
        return [_as_encodable(v) for v in value]
    if hasattr(value, "get_fields_and_field_types"):  # a nested rclpy message
        return _ByteFieldsAsInts(value)
    return value


def _encoder(type_name: str, definition: str) -> EncoderFunction:
    encode = serialize_dynamic(type_name, definition)[type_name]
    if _BYTE_FIELD.search(definition) is None:
        return encode
    return lambda msg: encode(_ByteFieldsAsInts(msg))


class RecordingError(BrakeSimError):
    """A recording that cannot be opened, written or closed (the message says where, why)."""


@dataclass(frozen=True)
class RecordingOptions:
    """How a recording is written.

    Attributes:
        compression: chunk compression, ``"zstd"`` (default) or ``"none"``.
        flush_interval_s: simulated seconds a chunk may span before it is closed and
            written; bounds what a hard kill loses (> 0, finite; default 1 s).
        chunk_size_bytes: uncompressed bytes after which a chunk is closed anyway.
        durable: fsync the file whenever a chunk is written by the interval (survives a
            power loss, not only a killed process).
    """

    compression: str = "zstd"
    flush_interval_s: float = 1.0
    chunk_size_bytes: int = 4 * 1024 * 1024
    durable: bool = True

    def __post_init__(self) -> None:
        if self.compression not in COMPRESSIONS:
            raise RecordingError(
                f"compression {self.compression!r}: allowed {', '.join(COMPRESSIONS)}"
            )
        if not (math.isfinite(self.flush_interval_s) and self.flush_interval_s > 0.0):
            raise RecordingError(
                f"flush interval {self.flush_interval_s!r} s: allowed a finite time > 0 s"
            )
        if self.chunk_size_bytes < 1024:
            raise RecordingError(
                f"chunk size {self.chunk_size_bytes} bytes: allowed at least 1024 bytes"
            )


class _DirectFile:
    """An unbuffered binary file for ``mcap.Writer``: every ``write`` reaches the OS.

    (``mcap.Writer`` wraps raw files in a ``BufferedWriter``; this object is not one.)
    """

    def __init__(self, path: Path) -> None:
        # never through a symbolic link; whether an existing file may be replaced is the
        # caller's rule (recording/output.py's check_output, applied before the run)
        flags = os.O_WRONLY | os.O_CREAT | os.O_TRUNC | getattr(os, "O_NOFOLLOW", 0)
        self._fd = os.open(path, flags, 0o644)
        self._position = 0

    def write(self, data: bytes | memoryview) -> int:
        view = memoryview(data)
        while view:
            written = os.write(self._fd, view)
            view = view[written:]
        self._position += len(data)
        return len(data)

    def tell(self) -> int:
        return self._position

    def flush(self) -> None:
        """Nothing is buffered here."""

    def fsync(self) -> None:
        os.fsync(self._fd)

    def close(self) -> None:
        if self._fd >= 0:
            fd, self._fd = self._fd, -1
            os.close(fd)


@dataclass
class _Channel:
    channel_id: int
    topic: Topic
    count: int = 0


@dataclass
class RecordingStats:
    """What a recorder wrote so far."""

    messages: int = 0
    first_ns: int | None = None
    last_ns: int | None = None
    interval_flushes: int = 0
    per_topic: dict[str, int] = field(default_factory=dict)


class McapRecorder:
    """Writes the stream's messages to an MCAP file, rosbag2 style (see the module doc).

    Args:
        path: the ``.mcap`` file to create (its directory is created; an existing file is
            replaced).
        records: MCAP metadata records to write first, ``{name: {key: value}}``.
        options: compression, flush interval, chunk size, fsync.
        topics: topics whose channels are registered at once (others on first use).
        custom_data: key-values for the ``rosbag2`` record's ``custom_data``.

    Raises:
        RecordingError: the file cannot be created or written (path, cause).
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        records: Mapping[str, Mapping[str, str]],
        options: RecordingOptions | None = None,
        topics: Iterable[Topic] = (),
        custom_data: Mapping[str, str] | None = None,
    ) -> None:
        self.path = Path(path)
        self.options = options or RecordingOptions()
        self.stats = RecordingStats()
        self._custom_data = dict(custom_data or {})
        self._channels: dict[str, _Channel] = {}
        self._schemas: dict[str, int] = {}
        self._encoders: dict[str, EncoderFunction] = {}
        self._interval_ns = round(self.options.flush_interval_s * 1e9)
        self._chunk_first_ns: int | None = None
        self._closed = False
        self._file: _DirectFile | None = None
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._file = _DirectFile(self.path)
            self._writer = Writer(
                self._file,  # type: ignore[arg-type]  # write/tell/flush is all it uses
                chunk_size=self.options.chunk_size_bytes,
                compression=COMPRESSIONS[self.options.compression],
            )
            self._writer.start(
                profile=PROFILE, library=f"brake-sim-ros {__version__}; mcap {mcap.__version__}"
            )
            for name, record in records.items():
                self._writer.add_metadata(name, dict(record))
            for topic in topics:
                self._channel(topic)
            self._flush(sync=True)  # a full disk or a bad device fails here, not later
        except OSError as exc:
            self._abandon()
            raise RecordingError(f"cannot record to {self.path}: {_cause(exc)}") from None
        except schemas.SchemaError as exc:
            self._abandon()
            raise RecordingError(f"cannot record to {self.path}: {exc}") from None

    def __repr__(self) -> str:
        return f"McapRecorder({str(self.path)!r})"

    # -- writing ------------------------------------------------------------------------------
    def _channel(self, topic: Topic) -> _Channel:
        channel = self._channels.get(topic.name)
        if channel is not None:
            if channel.topic.type_name != topic.type_name:
                raise RecordingError(
                    f"{self.path}: topic {topic.name} has type {channel.topic.type_name},"
                    f" not {topic.type_name}"
                )
            return channel
        schema_id = self._schemas.get(topic.type_name)
        if schema_id is None:
            definition = schemas.full_definition(topic.type_name)
            self._encoders[topic.type_name] = _encoder(topic.type_name, definition)
            schema_id = self._writer.register_schema(
                name=topic.type_name, encoding=SCHEMA_ENCODING, data=definition.encode()
            )
            self._schemas[topic.type_name] = schema_id
        channel_id = self._writer.register_channel(
            topic=topic.name,
            message_encoding=MESSAGE_ENCODING,
            schema_id=schema_id,
            metadata={
                "offered_qos_profiles": metadata.qos_yaml([topic.qos]),
                "topic_type_hash": schemas.type_hash(topic.type_name),
            },
        )
        channel = self._channels[topic.name] = _Channel(channel_id, topic)
        return channel

    def write(self, topic: Topic, msg: Any, time_ns: int) -> None:
        """Add one message at simulated time ``time_ns`` (ns, >= 0) on ``topic``.

        Raises:
            RecordingError: the recorder is closed, or writing failed (it is then closed).
        """
        if self._closed:
            raise RecordingError(f"{self.path}: the recording is closed")
        if time_ns < 0:
            raise RecordingError(f"{self.path}: message time {time_ns} ns: allowed >= 0 ns")
        try:
            channel = self._channel(topic)
            data = self._encoders[topic.type_name](msg)
            first = self._chunk_first_ns
            if first is not None and (time_ns < first or time_ns - first >= self._interval_ns):
                self._flush(sync=self.options.durable)
                self.stats.interval_flushes += 1
            self._writer.add_message(
                channel.channel_id, log_time=time_ns, data=data, publish_time=time_ns
            )
        except OSError as exc:
            self._abandon()
            raise RecordingError(
                f"recording to {self.path} stopped after {self.stats.messages} messages"
                f"{self._upto()}: {_cause(exc)}; the chunks written before are in the file"
                " (brake-sim recover makes it whole)"
            ) from None
        except schemas.SchemaError as exc:
            raise RecordingError(f"{self.path}: cannot record {topic.name}: {exc}") from None
        if self._chunk_first_ns is None:
            self._chunk_first_ns = time_ns
        channel.count += 1
        s = self.stats
        s.messages += 1
        s.first_ns = time_ns if s.first_ns is None else min(s.first_ns, time_ns)
        s.last_ns = time_ns if s.last_ns is None else max(s.last_ns, time_ns)

    def parameter_change(self, changes: Mapping[str, Any], sample_index: int, time_ns: int) -> None:
        """Record a parameter change of a live node, at ``sample_index`` (simulated time
        ``time_ns``, unused: the record carries the sample): a
        ``brake_sim_parameter_change`` metadata record (:mod:`.metadata`), after the
        messages written before it.

        Raises:
            RecordingError: the recorder is closed, or writing failed (it is then closed).
        """
        if self._closed:
            raise RecordingError(f"{self.path}: the recording is closed")
        try:
            self._flush(sync=False)  # the messages before the change come before it in the file
            self._writer.add_metadata(
                metadata.PARAMETER_CHANGE, metadata.parameter_change_record(changes, sample_index)
            )
        except OSError as exc:
            self._abandon()
            raise RecordingError(
                f"recording to {self.path} stopped at a parameter change{self._upto()}:"
                f" {_cause(exc)}"
            ) from None

    def _flush(self, *, sync: bool) -> None:
        self._writer.flush()
        self._chunk_first_ns = None
        if sync and self._file is not None:
            self._file.fsync()

    def _upto(self) -> str:
        last = self.stats.last_ns
        return "" if last is None else f" (up to t = {last / 1e9:.6f} s)"

    # -- closing ----------------------------------------------------------------------------------
    def close(self) -> None:
        """Write the ``rosbag2`` record and the summary, fsync and close. Idempotent.

        Raises:
            RecordingError: the end of the file could not be written.
        """
        if self._closed:
            return
        self._closed = True
        s = self.stats
        topics = [
            {
                "name": c.topic.name,
                "type": c.topic.type_name,
                "qos_yaml": metadata.qos_yaml([c.topic.qos]),
                "type_hash": schemas.type_hash(c.topic.type_name),
                "message_count": c.count,
            }
            for c in self._channels.values()
        ]
        s.per_topic = {c.topic.name: c.count for c in self._channels.values()}
        try:
            self._writer.flush()
            self._writer.add_metadata(
                metadata.ROSBAG2,
                metadata.rosbag2_record(
                    file_name=self.path.name,
                    topics=topics,
                    message_count=s.messages,
                    start_ns=s.first_ns or 0,
                    end_ns=s.last_ns or 0,
                    custom_data=self._custom_data,
                ),
            )
            self._writer.finish()
            assert self._file is not None
            self._file.fsync()
        except OSError as exc:
            raise RecordingError(
                f"{self.path}: could not finish the file after {s.messages} messages"
                f"{self._upto()}: {_cause(exc)} (brake-sim recover makes it whole)"
            ) from None
        finally:
            self._release()

    def _abandon(self) -> None:
        """Stop after a failure: no more writes, the descriptor closed, errors ignored."""
        self._closed = True
        self._release()

    def _release(self) -> None:
        if self._file is not None:
            with contextlib.suppress(OSError):  # the failure that got us here was reported
                self._file.close()
            self._file = None

    def __enter__(self) -> McapRecorder:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def describe(self) -> str:
        """One line: messages per topic and the simulated time covered."""
        s = self.stats
        per_topic = ", ".join(f"{c.topic.name} {c.count}" for c in self._channels.values())
        span = "" if s.first_ns is None else f", t = {s.first_ns / 1e9:g} .. {s.last_ns / 1e9:g} s"
        return f"{self.path}: {s.messages} messages ({per_topic}){span}"


def _cause(exc: OSError) -> str:
    where = f" ({exc.filename})" if exc.filename else ""
    return f"{exc.strerror or exc}{where} [errno {exc.errno}]" if exc.errno else f"{exc}{where}"
