"""The whole-file check of a recording (:class:`CheckedFile`): header, every chunk, every
message, the summary against what the data section holds, the footer and its CRC, as the
module doc of :mod:`.reader` lists; any fault is one :class:`RecordingReadError` line
naming the file, the offset, the chunk or message and what is allowed. What the check
finds (the channels, the chunks, the metadata, the message counts and times) is what
:class:`.reader.Recording` reads from.
"""

from __future__ import annotations

import struct
import zlib
from dataclasses import dataclass, field

from brake_sim_ros.recording import cdr
from brake_sim_ros.recording.channel_qos import offered_qos
from brake_sim_ros.recording.mcap_format import (
    FOOTER_BYTES,
    FRAME_BYTES,
    MAGIC,
    MIN_FILE_BYTES,
    OP_NAMES,
    PROFILE,
    Channel,
    Footer,
    Limits,
    MalformedError,
    Message,
    Op,
    RecordingReadError,
    Schema,
    Source,
    Statistics,
    check_channel,
    check_schema,
    parse_channel,
    parse_chunk,
    parse_chunk_index,
    parse_data_end,
    parse_footer,
    parse_header,
    parse_message,
    parse_message_index,
    parse_metadata,
    parse_metadata_index,
    parse_schema,
    parse_statistics,
    parse_summary_offset,
    read_frame,
    recover_hint,
    shown,
    verify_chunk,
)
from brake_sim_ros.stream import Topic
from brake_sim_ros.stream.topics import QosSpec


@dataclass(frozen=True)
class RecordedChannel:
    """One channel of a checked recording."""

    channel_id: int
    topic: Topic  # name and type (a type of the topic table)
    qos: QosSpec | None  # the recorded offer (None when the channel has none)
    message_count: int


@dataclass(frozen=True)
class ChunkInfo:
    """Where a checked chunk is and what it holds."""

    number: int  # 0-based, in file order
    offset: int
    length: int  # whole record, frame included
    start_ns: int
    end_ns: int
    crc: int
    first_index: int  # file-order index of its first message
    message_count: int


@dataclass
class Catalog:
    """The schemas and channels of a file, each checked against the installed definitions,
    and the messages checked against them."""

    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    types: dict[int, str] = field(default_factory=dict)  # channel id -> type

    def add_schema(self, schema: Schema) -> None:
        check_schema(schema)
        known = self.schemas.setdefault(schema.id, schema)
        if known != schema:
            raise MalformedError(f"schema {schema.id} is defined twice, differently")

    def add_channel(self, channel: Channel) -> None:
        type_name = check_channel(channel, self.schemas)
        known = self.channels.setdefault(channel.id, channel)
        if known != channel:
            raise MalformedError(f"channel {channel.id} is defined twice, differently")
        self.types[channel.id] = type_name

    def check_message(self, message: Message, start_ns: int, end_ns: int) -> Topic:
        channel = self.channels.get(message.channel_id)
        if channel is None:
            raise MalformedError(f"channel {message.channel_id} is not defined before it")
        if not start_ns <= message.log_time <= end_ns:
            raise MalformedError(
                f"log time {message.log_time} ns outside its chunk's {start_ns}..{end_ns} ns"
            )
        topic = Topic(channel.topic, self.types[message.channel_id])
        try:
            cdr.check(topic.type_name, message.data)
        except cdr.CdrError as exc:
            raise MalformedError(f"does not decode as {topic.type_name}: {exc}") from None
        return topic


class CheckedFile:
    """A recording's file checked from end to end by :meth:`_check` (what it holds: the
    attributes of :class:`.reader.Recording`)."""

    def __init__(self, src: Source, limits: Limits) -> None:
        self._src = src
        self._limits = limits
        self.path = src.path
        self.name = src.name
        self.size_bytes = src.size
        self.profile = ""
        self.library = ""
        self.metadata: list[tuple[str, dict[str, str]]] = []
        self.channels: dict[int, RecordedChannel] = {}
        self.chunks: list[ChunkInfo] = []
        self.message_count = 0
        self.start_ns: int | None = None
        self.end_ns: int | None = None
        self._catalog = Catalog()
        self._counts: dict[int, int] = {}

    def _fail(self, where: str, problem: str, *, hint: bool = True) -> RecordingReadError:
        tail = f"; {recover_hint(self.name)}" if hint else ""
        return RecordingReadError(f"{self.name}: {where}: {problem}{tail}")

    def _check(self) -> None:
        src = self._src
        size = src.size
        if size < len(MAGIC) or src.read(0, len(MAGIC)) != MAGIC:
            raise RecordingReadError(
                f"{self.name} is not an MCAP file (it does not start with the MCAP magic);"
                " allowed: a recording written by brake-sim (--record / --mcap); if it is one"
                f" whose start was damaged, {recover_hint(self.name)}"
            )
        if size < MIN_FILE_BYTES or src.read(size - len(MAGIC), len(MAGIC)) != MAGIC:
            raise self._fail(
                f"{size} bytes",
                "the file does not end with the MCAP footer and magic, so it was cut short"
                " or not closed (killed, power loss, full disk)",
            )
        footer_at = size - len(MAGIC) - FOOTER_BYTES
        frame = src.read(footer_at, FRAME_BYTES)
        if frame != struct.pack("<BQ", Op.FOOTER, FOOTER_BYTES - FRAME_BYTES):
            raise self._fail(f"offset {footer_at}", "no footer record before the final magic")
        footer = parse_footer(src.read(footer_at + FRAME_BYTES, FOOTER_BYTES - FRAME_BYTES))
        if footer.summary_start == 0:
            raise self._fail(
                f"offset {footer_at}", "the footer points to no summary (the file is not indexed)"
            )
        if not len(MAGIC) < footer.summary_start <= footer_at:
            raise self._fail(
                f"offset {footer_at}",
                f"the footer's summary start {footer.summary_start} is outside the file's"
                f" summary area (after the data, before offset {footer_at})",
            )
        data_end = self._check_data_section(footer.summary_start)
        if data_end != footer.summary_start:
            raise self._fail(
                f"offset {data_end}",
                f"the data section ends here, the footer says the summary starts at"
                f" {footer.summary_start}",
            )
        self._check_summary(footer, footer_at)
        catalog = self._catalog
        for channel_id, channel in sorted(catalog.channels.items()):
            try:
                qos = offered_qos(channel.metadata.get("offered_qos_profiles", ""))
            except MalformedError as exc:
                raise self._fail(f"channel {channel_id} ({channel.topic})", str(exc)) from None
            self.channels[channel_id] = RecordedChannel(
                channel_id,
                Topic(channel.topic, catalog.types[channel_id]),
                qos,
                self._counts.get(channel_id, 0),
            )

    def _check_data_section(self, limit: int) -> int:
        """Walk the data section from the header to DataEnd; the offset after DataEnd."""
        src, lim = self._src, self._limits
        offset = len(MAGIC)
        running_crc = zlib.crc32(MAGIC)
        metadata_bytes = 0
        first = True
        while True:
            where = f"offset {offset}"
            try:
                opcode, length = read_frame(src, offset, limit, lim.max_record_bytes)
                if opcode != Op.CHUNK and length > lim.max_small_record_bytes:
                    raise MalformedError(
                        f"{OP_NAMES.get(opcode, 'record')} of {length} bytes, over the"
                        f" {lim.max_small_record_bytes}-byte limit"
                    )
                raw_frame = src.read(offset, FRAME_BYTES)
                body = src.read(offset + FRAME_BYTES, length)
            except MalformedError as exc:
                raise self._fail(where, str(exc)) from None
            name = OP_NAMES.get(opcode, f"record with opcode 0x{opcode:02x}")
            if first:
                if opcode != Op.HEADER:
                    raise self._fail(where, f"a {name} where the header must be")
                try:
                    self.profile, self.library = parse_header(body)
                except MalformedError as exc:
                    raise self._fail(f"{where} (header)", str(exc)) from None
                if self.profile != PROFILE:
                    raise self._fail(
                        f"{where} (header)",
                        f"profile {shown(self.profile)}: allowed {PROFILE!r}",
                        hint=False,
                    )
                first = False
            elif opcode == Op.DATA_END:
                try:
                    crc = parse_data_end(body)
                except MalformedError as exc:
                    raise self._fail(f"{where} (data end)", str(exc)) from None
                if crc and crc != running_crc:
                    raise self._fail(
                        f"{where} (data end)",
                        f"data section CRC 0x{running_crc:08x}, the file says 0x{crc:08x}",
                    )
                return offset + FRAME_BYTES + length
            elif opcode == Op.CHUNK:
                self._check_chunk(offset, FRAME_BYTES + length, body)
            elif opcode == Op.METADATA:
                try:
                    self.metadata.append(parse_metadata(body))
                except MalformedError as exc:
                    raise self._fail(f"{where} (metadata)", str(exc)) from None
                metadata_bytes += length
                if metadata_bytes > lim.max_metadata_bytes:
                    raise self._fail(
                        where, f"metadata over the {lim.max_metadata_bytes}-byte limit"
                    )
            elif opcode == Op.MESSAGE_INDEX:
                try:
                    parse_message_index(body)
                except MalformedError as exc:
                    raise self._fail(f"{where} (message index)", str(exc)) from None
            elif opcode in (Op.SCHEMA, Op.CHANNEL):
                try:
                    if opcode == Op.SCHEMA:
                        self._catalog.add_schema(parse_schema(body))
                    else:
                        self._catalog.add_channel(parse_channel(body))
                except MalformedError as exc:
                    raise self._fail(f"{where} ({name})", str(exc), hint=False) from None
            else:
                raise self._fail(
                    where,
                    f"a {name} in the data section: allowed header, metadata, schema,"
                    " channel, chunk, message index and data end records (every message in"
                    " a chunk, as the recorder writes)",
                )
            running_crc = zlib.crc32(body, zlib.crc32(raw_frame, running_crc))
            offset += FRAME_BYTES + length

    def _check_chunk(self, offset: int, length: int, body: bytes) -> None:
        number = len(self.chunks)
        where = f"chunk {number} at offset {offset}"
        try:
            header = parse_chunk(body)
            records = verify_chunk(header, self._limits)
        except MalformedError as exc:
            raise self._fail(where, str(exc)) from None
        if header.start_ns > header.end_ns:
            raise self._fail(where, "its start time is after its end time")
        count = 0
        for inner, op, record in records:
            try:
                if op == Op.SCHEMA:
                    self._catalog.add_schema(parse_schema(record))
                    continue
                if op == Op.CHANNEL:
                    self._catalog.add_channel(parse_channel(record))
                    continue
                message = parse_message(record)
                topic = self._catalog.check_message(message, header.start_ns, header.end_ns)
            except MalformedError as exc:
                what = {Op.SCHEMA: "schema", Op.CHANNEL: "channel"}.get(op)
                if what is None:
                    what = f"message {self.message_count + count}"
                    channel_id = struct.unpack_from("<H", record)[0] if len(record) > 1 else -1
                    channel = self._catalog.channels.get(channel_id)
                    if channel is not None:
                        what += f" on {channel.topic}"
                raise self._fail(
                    f"{where}, {what} (byte {inner} of the chunk)", str(exc), hint=op == Op.MESSAGE
                ) from None
            count += 1
            self._count(message.channel_id, topic, message.log_time)
        self.chunks.append(
            ChunkInfo(
                number,
                offset,
                length,
                header.start_ns,
                header.end_ns,
                header.crc,
                self.message_count - count,
                count,
            )
        )

    def _count(self, channel_id: int, topic: Topic, log_time: int) -> None:
        self._counts[channel_id] = self._counts.get(channel_id, 0) + 1
        self.message_count += 1
        self.start_ns = log_time if self.start_ns is None else min(self.start_ns, log_time)
        self.end_ns = log_time if self.end_ns is None else max(self.end_ns, log_time)

    def _check_summary(self, footer: Footer, footer_at: int) -> None:
        src, lim = self._src, self._limits
        start = footer.summary_start
        if footer.summary_crc:
            crc, offset, end = 0, start, footer_at + FRAME_BYTES + 16
            while offset < end:
                block = src.read(offset, min(end - offset, 1 << 20))
                crc = zlib.crc32(block, crc)
                offset += len(block)
            if crc != footer.summary_crc:
                raise self._fail(
                    f"summary at offset {start}",
                    f"CRC 0x{crc:08x}, the footer says 0x{footer.summary_crc:08x}",
                )
        statistics: Statistics | None = None
        chunk_indexes: set[tuple[int, int]] = set()
        offset = start
        while offset < footer_at:
            where = f"summary record at offset {offset}"
            try:
                opcode, length = read_frame(src, offset, footer_at, lim.max_small_record_bytes)
                body = src.read(offset + FRAME_BYTES, length)
                if opcode == Op.SCHEMA:
                    schema = parse_schema(body)
                    if self._catalog.schemas.get(schema.id, schema) != schema:
                        raise MalformedError(f"schema {schema.id} differs from the data section's")
                    self._catalog.add_schema(schema)
                elif opcode == Op.CHANNEL:
                    channel = parse_channel(body)
                    if self._catalog.channels.get(channel.id, channel) != channel:
                        raise MalformedError(
                            f"channel {channel.id} differs from the data section's"
                        )
                    self._catalog.add_channel(channel)
                elif opcode == Op.STATISTICS:
                    statistics = parse_statistics(body)
                elif opcode == Op.CHUNK_INDEX:
                    chunk_indexes.add(parse_chunk_index(body))
                elif opcode == Op.METADATA_INDEX:
                    parse_metadata_index(body)
                elif opcode == Op.SUMMARY_OFFSET:
                    parse_summary_offset(body)
                else:
                    name = OP_NAMES.get(opcode, f"record with opcode 0x{opcode:02x}")
                    raise MalformedError(
                        f"a {name}: allowed schema, channel, statistics, chunk index, metadata"
                        " index and summary offset records"
                    )
            except MalformedError as exc:
                raise self._fail(where, str(exc)) from None
            offset += FRAME_BYTES + length
        self._compare_summary(statistics, chunk_indexes, start)

    def _compare_summary(
        self, statistics: Statistics | None, chunk_indexes: set[tuple[int, int]], start: int
    ) -> None:
        where = f"summary at offset {start}"
        if statistics is None:
            raise self._fail(where, "no statistics record")
        counts = self._counts
        stated = {k: v for k, v in statistics.channel_message_counts.items() if v}
        if (
            statistics.message_count != self.message_count
            or stated != counts
            or statistics.chunk_count != len(self.chunks)
        ):
            raise self._fail(
                where,
                f"the statistics count {statistics.message_count} messages in"
                f" {statistics.chunk_count} chunks, the data section holds"
                f" {self.message_count} in {len(self.chunks)}",
            )
        if self.message_count and (statistics.start_ns, statistics.end_ns) != (
            self.start_ns,
            self.end_ns,
        ):
            raise self._fail(where, "the statistics' time span differs from the messages'")
        scanned = {(c.offset, c.length) for c in self.chunks}
        if chunk_indexes != scanned:
            raise self._fail(where, "the chunk indexes do not match the chunks in the file")


__all__ = ["Catalog", "CheckedFile", "ChunkInfo", "RecordedChannel"]
