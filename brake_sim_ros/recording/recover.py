"""``brake-sim recover BROKEN.mcap FIXED.mcap``: make a truncated recording whole again.

A recording cut short (SIGKILL, power loss, full disk) has no summary and may end in the
middle of a record. :func:`recover` reads it from the start, record by record, and keeps
every record that is complete: the header, schemas, channels, metadata, loose messages and
every chunk whose bytes are all there and whose CRC matches. It stops at the first
incomplete or damaged record (what follows cannot be framed). The output is a valid,
indexed MCAP with the same profile, schemas, channels and metadata (a fresh ``rosbag2``
record with the recovered counts replaces any old one) and a ``brake_sim_recovery``
record saying what was recovered from where.
"""

from __future__ import annotations

import os
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

from mcap.exceptions import McapError
from mcap.records import Channel, Chunk, DataEnd, Footer, Header, Message, Metadata, Schema
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import CompressionType, Writer

from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.recording import metadata
from brake_sim_ros.recording.writer import RecordingError

MAGIC = b"\x89MCAP0\r\n"
RECOVERY = "brake_sim_recovery"


class RecoverError(BrakeSimError, ValueError):
    """An input that is not an MCAP file, or an output that cannot be written."""


class _TruncatedError(McapError):
    """Fewer bytes left than a record needs."""


class _StrictReader:
    """A binary reader whose ``read(n)`` returns exactly ``n`` bytes or raises _TruncatedError."""

    def __init__(self, raw: IO[bytes]) -> None:
        self._raw = raw

    def read(self, n: int = -1) -> bytes:
        data = self._raw.read(n)
        if n >= 0 and len(data) < n:
            raise _TruncatedError(f"{n} bytes wanted, {len(data)} left")
        return data

    def tell(self) -> int:
        return self._raw.tell()


@dataclass
class Recovery:
    """What :func:`recover` found and wrote."""

    source: str
    output: str
    source_bytes: int
    used_bytes: int = 0  # bytes of the input up to the end of the last complete record
    complete: bool = False  # the data section ended (DataEnd read): no message was missing
    stop_reason: str = ""
    chunks: int = 0
    messages: int = 0
    per_topic: Counter[str] = field(default_factory=Counter)
    first_ns: int | None = None
    last_ns: int | None = None

    def describe(self) -> str:
        lines = [
            f"recovered {self.messages} messages in {self.chunks} chunks from {self.source}"
            f" ({self.used_bytes} of {self.source_bytes} bytes used) into {self.output}"
        ]
        for topic, count in sorted(self.per_topic.items()):
            lines.append(f"  {topic}: {count}")
        if self.last_ns is not None:
            lines.append(
                f"  simulated time {self.first_ns / 1e9:.6f} .. {self.last_ns / 1e9:.6f} s"
            )
        if self.complete:
            lines.append("  the data section was complete: no message lost")
        else:
            lost = self.source_bytes - self.used_bytes
            lines.append(
                f"  lost: the {lost} bytes after the last complete record ({self.stop_reason});"
                " the messages in them cannot be counted"
            )
        return "\n".join(lines)


def _check_magic(path: Path) -> None:
    try:
        with path.open("rb") as f:
            head = f.read(len(MAGIC))
    except OSError as exc:
        raise RecoverError(f"cannot read {path}: {exc.strerror}") from None
    if head != MAGIC:
        raise RecoverError(
            f"{path} is not an MCAP file: it starts with {head[:8]!r}, an MCAP file with {MAGIC!r}"
        )


def recover(broken: str | os.PathLike[str], fixed: str | os.PathLike[str]) -> Recovery:
    """Copy every complete record of ``broken`` into a valid MCAP file ``fixed``.

    Raises:
        RecoverError: ``broken`` is unreadable or not MCAP, ``fixed`` is ``broken`` or
            cannot be written.
    """
    src, dst = Path(broken), Path(fixed)
    _check_magic(src)
    if dst.exists() and dst.resolve() == src.resolve():
        raise RecoverError(f"{dst}: the output must be another file than the input")
    result = Recovery(str(src), str(dst), source_bytes=src.stat().st_size)
    header: Header | None = None
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    records: list[Metadata] = []
    messages: list[Message] = []
    compression = CompressionType.NONE
    with src.open("rb") as raw:
        reader = _StrictReader(raw)
        stream = StreamReader(reader, emit_chunks=True, validate_crcs=False)  # type: ignore[arg-type]
        iterator = stream.records
        while True:
            try:
                record = next(iterator)
                is_chunk = isinstance(record, Chunk)
                inner = breakup_chunk(record, validate_crc=True) if is_chunk else []
            except StopIteration:
                break
            except (McapError, ValueError, EOFError) as exc:  # incl. CRC, zstd, truncation
                result.stop_reason = f"{type(exc).__name__}: {exc}".rstrip(": ")
                break
            result.used_bytes = reader.tell()
            if isinstance(record, Chunk):
                result.chunks += 1
                if record.compression == "zstd":
                    compression = CompressionType.ZSTD
                items = inner
            else:
                items = [record]
            for item in items:
                if isinstance(item, Header):
                    header = item
                elif isinstance(item, Schema):
                    schemas.setdefault(item.id, item)
                elif isinstance(item, Channel):
                    channels.setdefault(item.id, item)
                elif isinstance(item, Metadata):
                    if item.name not in (metadata.ROSBAG2, RECOVERY):
                        records.append(item)
                elif isinstance(item, Message):
                    messages.append(item)
            if isinstance(record, DataEnd):
                break  # the summary that follows is rebuilt
            if isinstance(record, Footer):
                break
    result.complete = not result.stop_reason
    if header is None:
        raise RecoverError(f"{src}: not even the MCAP header is complete; nothing to recover")
    _write(dst, header, schemas, channels, records, messages, compression, result)
    return result


def _write(
    dst: Path,
    header: Header,
    schemas: dict[int, Schema],
    channels: dict[int, Channel],
    records: list[Metadata],
    messages: list[Message],
    compression: CompressionType,
    result: Recovery,
) -> None:
    try:
        dst.parent.mkdir(parents=True, exist_ok=True)
        with dst.open("wb") as out:
            writer = Writer(out, compression=compression)
            writer.start(profile=header.profile, library=header.library)
            schema_ids = {
                s.id: writer.register_schema(s.name, s.encoding, s.data) for s in schemas.values()
            }
            channel_ids: dict[int, int] = {}
            for c in channels.values():
                channel_ids[c.id] = writer.register_channel(
                    topic=c.topic,
                    message_encoding=c.message_encoding,
                    metadata=c.metadata,
                    schema_id=schema_ids.get(c.schema_id, 0),
                )
            for record in records:
                writer.add_metadata(record.name, record.metadata)
            counts: Counter[int] = Counter()
            for m in messages:
                if m.channel_id not in channel_ids:
                    continue  # a message whose channel record was lost cannot be decoded
                writer.add_message(
                    channel_ids[m.channel_id], m.log_time, m.data, m.publish_time, m.sequence
                )
                counts[m.channel_id] += 1
                result.first_ns = (
                    m.log_time if result.first_ns is None else min(result.first_ns, m.log_time)
                )
                result.last_ns = (
                    m.log_time if result.last_ns is None else max(result.last_ns, m.log_time)
                )
            result.messages = sum(counts.values())
            result.per_topic = Counter({channels[k].topic: v for k, v in counts.items()})
            topics = [
                {
                    "name": c.topic,
                    "type": schemas[c.schema_id].name if c.schema_id in schemas else "",
                    "qos_yaml": c.metadata.get("offered_qos_profiles", ""),
                    "type_hash": c.metadata.get("topic_type_hash", ""),
                    "message_count": counts[c.id],
                }
                for c in channels.values()
            ]
            custom = {}
            for record in records:
                if record.name == metadata.SCENARIO:
                    custom["brake_sim_scenario"] = record.metadata.get("name", "")
            writer.add_metadata(
                metadata.ROSBAG2,
                metadata.rosbag2_record(
                    file_name=dst.name,
                    topics=topics,
                    message_count=result.messages,
                    start_ns=result.first_ns or 0,
                    end_ns=result.last_ns or 0,
                    custom_data=custom,
                ),
            )
            writer.add_metadata(
                RECOVERY,  # str() of ints, repr() of the flag
                {
                    "source": str(result.source),
                    "source_bytes": str(result.source_bytes),
                    "used_bytes": str(result.used_bytes),
                    "source_complete": repr(result.complete),
                    "stop_reason": result.stop_reason,
                    "chunks_recovered": str(result.chunks),
                    "messages_recovered": str(result.messages),
                    "last_time_ns": str(result.last_ns),
                },
            )
            writer.finish()
    except OSError as exc:
        raise RecoverError(f"cannot write {dst}: {exc.strerror or exc}") from None


__all__ = ["RecordingError", "RecoverError", "Recovery", "recover"]
