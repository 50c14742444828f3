"""The first pass of ``brake-sim recover``: walk a damaged MCAP record by record and find
what is intact (:func:`scan_intact`).

It keeps every chunk whose CRC matches and whose records all parse, before and after any
damage: after a record that does not frame or a chunk that does not verify, it scans
forward byte by byte for the next record that proves itself (a chunk whose CRC matches, a
metadata record of this project that parses exactly, the data end just before a summary
whose CRC matched) and goes on from there. It collects the metadata records (except those
recovery writes afresh), the schemas and channels the kept chunks define, and those of the
summary when the footer's summary CRC matches; each damaged region is a
:class:`DroppedRegion`. Nothing is written here (:mod:`.recover` writes the output).
"""

from __future__ import annotations

import re
import zlib
from dataclasses import dataclass, field

from brake_sim_ros.recording import metadata
from brake_sim_ros.recording.mcap_format import (
    FOOTER_BYTES,
    FRAME_BYTES,
    MAGIC,
    OP_NAMES,
    Channel,
    Limits,
    MalformedError,
    Op,
    Schema,
    Source,
    parse_channel,
    parse_chunk,
    parse_data_end,
    parse_footer,
    parse_header,
    parse_message,
    parse_message_index,
    parse_metadata,
    parse_schema,
    parse_statistics,
    read_frame,
    verify_chunk,
)

# the metadata records recovery writes afresh (not copied from the input)
REBUILT_METADATA = (metadata.ROSBAG2, metadata.RECOVERY)
_OUR_METADATA = re.compile(r"^(brake_sim_[a-z_]+|rosbag2)$")
_CANDIDATES = re.compile(rb"[\x06\x0c\x0f]")  # chunk, metadata, data end: records to resync on
_SCAN_WINDOW = 1 << 20
_MIN_CHUNK_BODY = 8 + 8 + 8 + 4 + 4 + 8  # a chunk's fixed fields


@dataclass(frozen=True)
class DroppedRegion:
    """Bytes ``[start, end)`` of the input that were not kept, and why."""

    start: int
    end: int
    reason: str
    chunks: int  # chunk records seen in it (their frame parsed), so at least this many lost
    before_ns: int | None = None  # last log time kept before it, if any
    after_ns: int | None = None  # first log time kept after it, if any


@dataclass(frozen=True)
class KeptChunk:
    """A chunk record whose CRC matched and whose records all parse, to copy as it is."""

    offset: int
    length: int  # the whole record, frame included
    crc: int
    compression: str


@dataclass
class IntactScan:
    """What the first pass found: kept items in file order, definitions, damage."""

    header_found: bool = False
    chunks: list[KeptChunk] = field(default_factory=list)
    metadata: list[tuple[str, dict[str, str]]] = field(default_factory=list)
    metadata_bytes: int = 0
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    regions: list[DroppedRegion] = field(default_factory=list)
    ended: bool = False  # the data end (or footer) was read
    summary_start: int | None = None  # of a summary whose CRC matched
    summary_messages: int | None = None
    summary_span_ns: tuple[int, int] | None = None
    summary_note: str = ""  # why a summary at the end of the file was not used
    conflicts: int = 0  # definitions met twice with different contents (the first is kept)
    loose_messages: int = 0
    metadata_over_limit: int = 0

    def add_schema(self, schema: Schema) -> None:
        known = self.schemas.setdefault(schema.id, schema)
        self.conflicts += known != schema

    def add_channel(self, channel: Channel) -> None:
        known = self.channels.setdefault(channel.id, channel)
        self.conflicts += known != channel


def scan_intact(src: Source, limits: Limits) -> IntactScan:
    """What of ``src`` is intact and what is not (see the module doc)."""
    scan = IntactScan()
    _read_trusted_summary(src, limits, scan)
    end = scan.summary_start if scan.summary_start is not None else src.size
    damaged_from: int | None = None
    reason = ""
    chunks_seen = 0
    offset = len(MAGIC)
    if src.size < len(MAGIC) or src.read(0, len(MAGIC)) != MAGIC:
        damaged_from, reason = 0, "no MCAP magic at the start"  # the header may follow
    while offset < end:
        outcome = _record_at(src, offset, end, limits, scan)
        if isinstance(outcome, str):
            if damaged_from is None:
                damaged_from, reason, chunks_seen = offset, outcome, 0
            chunks_seen += _frames_as_chunk(src, offset, end, limits)
            offset = _resync(src, offset + 1, end, limits, scan)
            continue
        if damaged_from is not None:
            scan.regions.append(DroppedRegion(damaged_from, offset, reason, chunks_seen))
            damaged_from = None
        offset = outcome
        if scan.ended:
            break
    if damaged_from is not None:
        scan.regions.append(DroppedRegion(damaged_from, end, reason, chunks_seen))
    return scan


def _read_trusted_summary(src: Source, limits: Limits, scan: IntactScan) -> None:
    """Schemas, channels and statistics of the summary, if the footer's CRC vouches for it."""
    size = src.size
    footer_at = size - len(MAGIC) - FOOTER_BYTES
    if footer_at < len(MAGIC) or src.read(size - len(MAGIC), len(MAGIC)) != MAGIC:
        return
    found: list[tuple[int, bytes]] = []
    try:
        opcode, length = read_frame(src, footer_at, size - len(MAGIC), FOOTER_BYTES)
        if opcode != Op.FOOTER:
            return
        footer = parse_footer(src.read(footer_at + FRAME_BYTES, length))
        start = footer.summary_start
        if not footer.summary_crc or not len(MAGIC) < start <= footer_at:
            scan.summary_note = "the footer gives no summary with a CRC; the summary is rebuilt"
            return
        if footer_at - start > limits.max_record_bytes:
            return
        covered = src.read(start, footer_at + FRAME_BYTES + 16 - start)
        if zlib.crc32(covered) != footer.summary_crc:
            scan.summary_note = "the summary's CRC does not match (damaged); it is rebuilt"
            return
        offset = start
        while offset < footer_at:
            opcode, length = read_frame(src, offset, footer_at, limits.max_small_record_bytes)
            found.append((opcode, src.read(offset + FRAME_BYTES, length)))
            offset += FRAME_BYTES + length
    except MalformedError:
        return
    scan.summary_start = start
    for opcode, body in found:
        try:
            if opcode == Op.SCHEMA:
                scan.add_schema(parse_schema(body))
            elif opcode == Op.CHANNEL:
                scan.add_channel(parse_channel(body))
            elif opcode == Op.STATISTICS:
                statistics = parse_statistics(body)
                scan.summary_messages = statistics.message_count
                if statistics.message_count:
                    scan.summary_span_ns = (statistics.start_ns, statistics.end_ns)
        except MalformedError:
            continue


def _record_at(src: Source, offset: int, end: int, limits: Limits, scan: IntactScan) -> str | int:
    """The offset after the record at ``offset`` if it is intact (and kept), else why not."""
    opcode = src.read(offset, 1)[0]
    where = f"the {OP_NAMES[opcode]} record" if opcode in OP_NAMES else "the record"
    where += f" at offset {offset}"
    try:
        opcode, length = read_frame(src, offset, end, limits.max_record_bytes)
        if opcode != Op.CHUNK and length > limits.max_small_record_bytes:
            raise MalformedError(f"{length} bytes, over the limit for a record of its kind")
        body = src.read(offset + FRAME_BYTES, length)
        if opcode == Op.CHUNK:
            _keep_chunk(offset, FRAME_BYTES + length, body, limits, scan)
        elif opcode == Op.HEADER:
            parse_header(body)
            scan.header_found = True
        elif opcode == Op.METADATA:
            name, values = parse_metadata(body)
            if name not in REBUILT_METADATA:
                if scan.metadata_bytes + length > limits.max_metadata_bytes:
                    scan.metadata_over_limit += 1
                else:
                    scan.metadata.append((name, values))
                    scan.metadata_bytes += length
        elif opcode == Op.MESSAGE_INDEX:
            parse_message_index(body)
        elif opcode == Op.SCHEMA:
            scan.add_schema(parse_schema(body))
        elif opcode == Op.CHANNEL:
            scan.add_channel(parse_channel(body))
        elif opcode == Op.MESSAGE:
            parse_message(body)
            scan.loose_messages += 1  # no CRC covers it: not kept
        elif opcode in (Op.DATA_END, Op.FOOTER):
            (parse_data_end if opcode == Op.DATA_END else parse_footer)(body)
            scan.ended = True
        elif not (opcode in (Op.ATTACHMENT, Op.ATTACHMENT_INDEX) or opcode >= 0x80):
            raise MalformedError("not a record of an MCAP data section")
    except MalformedError as exc:
        return f"{where}: {exc}"
    return offset + FRAME_BYTES + length


def _keep_chunk(offset: int, length: int, body: bytes, limits: Limits, scan: IntactScan) -> None:
    header = parse_chunk(body)
    definitions: list[Schema | Channel] = []
    for _inner, op, record in verify_chunk(header, limits):
        if op == Op.SCHEMA:
            definitions.append(parse_schema(record))
        elif op == Op.CHANNEL:
            definitions.append(parse_channel(record))
        else:
            parse_message(record)
    for item in definitions:  # only once the whole chunk is known to be intact
        if isinstance(item, Schema):
            scan.add_schema(item)
        else:
            scan.add_channel(item)
    scan.chunks.append(KeptChunk(offset, length, header.crc, header.compression))


def _frames_as_chunk(src: Source, offset: int, end: int, limits: Limits) -> bool:
    try:
        opcode, _length = read_frame(src, offset, end, limits.max_record_bytes)
    except MalformedError:
        return False
    return opcode == Op.CHUNK


def _resync(src: Source, start: int, end: int, limits: Limits, scan: IntactScan) -> int:
    """The offset of the next record that proves itself (``end`` if there is none)."""
    base = start
    while base < end:
        window = src.read(base, min(_SCAN_WINDOW, end - base))
        for match in _CANDIDATES.finditer(window):
            offset = base + match.start()
            if _proves_itself(src, offset, end, limits, scan):
                return offset
        base += len(window)
    return end


def _proves_itself(src: Source, offset: int, end: int, limits: Limits, scan: IntactScan) -> bool:
    """A chunk whose CRC matches, a metadata record of ours that parses exactly, or the
    data end just before a summary whose CRC matched."""
    try:
        opcode, length = read_frame(src, offset, end, limits.max_record_bytes)
        if opcode == Op.CHUNK and length >= _MIN_CHUNK_BODY:
            verify_chunk(parse_chunk(src.read(offset + FRAME_BYTES, length)), limits)
            return True
        if opcode == Op.METADATA and length <= limits.max_small_record_bytes:
            name, _values = parse_metadata(src.read(offset + FRAME_BYTES, length))
            return _OUR_METADATA.match(name) is not None
        if opcode == Op.DATA_END and length == 4:
            return offset + FRAME_BYTES + 4 == scan.summary_start
    except MalformedError:
        return False
    return False


__all__ = ["REBUILT_METADATA", "DroppedRegion", "IntactScan", "KeptChunk", "scan_intact"]
