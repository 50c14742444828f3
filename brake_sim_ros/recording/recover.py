"""``brake-sim recover BROKEN.mcap FIXED.mcap``: keep every intact chunk of a damaged recording.

A recording cut short (SIGKILL, power loss, full disk) has no summary and may end inside a
record; a damaged one (a bad sector, a bad copy) has chunks whose bytes changed anywhere.
:func:`recover` walks the file record by record (:mod:`.mcap_format`) and keeps

* every chunk whose CRC matches and whose records all parse, before *and after* any
  damage: after a record that does not frame or a chunk that does not verify, it scans
  forward byte by byte for the next record that proves itself (a chunk whose CRC matches,
  a metadata record of this project that parses exactly) and goes on from there;
* the metadata records (except ``rosbag2`` and ``brake_sim_recovery``, written afresh);
* the schemas and channels those chunks define, and those of the summary when the
  footer's summary CRC matches (so a damaged first chunk does not orphan the rest).

A message is kept only if its channel is known and of a type this project records, and
its payload checks (:func:`.cdr.check`); nothing is invented: every kept message is a
byte-for-byte copy from a chunk whose CRC matched. What is dropped is reported: each
damaged region (offsets, reason, chunks seen in it, the simulated time with no messages
around it) and messages dropped for a lost or foreign channel.

The output is a valid, indexed MCAP (profile ``ros2``, the installed definitions as
schemas, the channels' recorded QoS when it parses) with a fresh ``rosbag2`` record and a
``brake_sim_recovery`` record saying what was recovered from where. It is written by
:func:`.output.atomic_output`: refused if it exists (unless ``overwrite``), is a link or
is the input, and renamed into place only when complete. A file with nothing to recover
is refused and nothing is written.
"""

from __future__ import annotations

import itertools
import os
import re
import zlib
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from mcap.writer import CompressionType, Writer

from brake_sim_ros import __version__
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.recording import cdr, metadata, schemas
from brake_sim_ros.recording.mcap_format import (
    DEFAULT_LIMITS,
    FOOTER_BYTES,
    FRAME_BYTES,
    MAGIC,
    MESSAGE_ENCODING,
    OP_NAMES,
    PROFILE,
    SCHEMA_ENCODING,
    Channel,
    Limits,
    MalformedError,
    Op,
    Schema,
    Source,
    check_channel,
    check_schema,
    describe_path,
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
from brake_sim_ros.recording.output import atomic_output, check_output
from brake_sim_ros.recording.reader import offered_qos
from brake_sim_ros.stream.topics import TOPIC_BY_TYPE

RECOVERY = "brake_sim_recovery"
_REBUILT = (metadata.ROSBAG2, RECOVERY)
_OUR_METADATA = re.compile(r"^(brake_sim_[a-z_]+|rosbag2)$")
_CANDIDATES = re.compile(rb"[\x06\x0c\x0f]")  # chunk, metadata, data end: records to resync on
_SCAN_WINDOW = 1 << 20
_MIN_CHUNK_BODY = 8 + 8 + 8 + 4 + 4 + 8  # a chunk's fixed fields


class RecoverError(BrakeSimError, ValueError):
    """An input with nothing to recover, or an output that cannot be written (one line)."""


@dataclass(frozen=True)
class DroppedRegion:
    """Bytes ``[start, end)`` of the input that were not kept, and why."""

    start: int
    end: int
    reason: str
    chunks: int  # chunk records seen in it (their frame parsed), so at least this many lost
    before_ns: int | None = None  # last log time kept before it, if any
    after_ns: int | None = None  # first log time kept after it, if any


@dataclass
class Recovery:
    """What :func:`recover` found and wrote."""

    source: str
    output: str
    source_bytes: int
    messages: int = 0
    chunks_kept: int = 0
    per_topic: Counter[str] = field(default_factory=Counter)
    first_ns: int | None = None
    last_ns: int | None = None
    regions: list[DroppedRegion] = field(default_factory=list)
    dropped_messages: Counter[str] = field(default_factory=Counter)  # reason -> count
    summary_messages: int | None = None  # the count an intact summary gives
    summary_span_ns: tuple[int, int] | None = None
    metadata_kept: list[str] = field(default_factory=list)
    cut_short: bool = False  # the file ends without its data end: not closed by the recorder
    cadence_ns: int = 0  # the largest step between consecutive kept messages of one chunk
    notes: list[str] = field(default_factory=list)

    @property
    def complete(self) -> bool:
        """Nothing was dropped: no damaged region, no message left out, not cut short."""
        return not (self.regions or self.dropped_messages or self.cut_short)

    def region_lost_ns(self, region: DroppedRegion) -> int | None:
        """Simulated time lost in ``region``: the gap between the kept messages around it,
        less the recording's own cadence (None when an end of the gap is unknown)."""
        before, after = region.before_ns, region.after_ns
        if before is None and self.summary_span_ns is not None:
            before = self.summary_span_ns[0] - self.cadence_ns
        if after is None and self.summary_span_ns is not None:
            after = self.summary_span_ns[1] + self.cadence_ns
        if before is None or after is None:
            return None
        return max(0, after - before - self.cadence_ns)

    @property
    def lost_s(self) -> float:
        """Simulated time lost in the damaged regions whose both ends are known."""
        return sum(self.region_lost_ns(r) or 0 for r in self.regions) / 1e9

    def describe(self) -> str:
        """What was kept and what was dropped, one fact a line."""
        of = "" if self.summary_messages is None else f" of {self.summary_messages}"
        lines = [
            f"recovered {self.messages}{of} messages from {self.chunks_kept} intact chunks of"
            f" {self.source} into {self.output}"
        ]
        lines += [f"  {topic}: {count}" for topic, count in sorted(self.per_topic.items())]
        if self.first_ns is not None and self.last_ns is not None:
            lines.append(
                f"  simulated time {self.first_ns / 1e9:.6f} .. {self.last_ns / 1e9:.6f} s"
            )
        if self.metadata_kept:
            lines.append(f"  metadata kept: {', '.join(self.metadata_kept)}")
        for region in self.regions:
            lines.append(f"  dropped {self._region_text(region)}")
        for reason, count in sorted(self.dropped_messages.items()):
            lines.append(f"  dropped {count} messages: {reason}")
        if self.cut_short:
            lines.append(
                "  the file ends without the recorder's closing records (killed, power loss):"
                " what it had not yet written is not in it"
            )
        lines += [f"  note: {note}" for note in self.notes]
        if self.complete:
            lines.append("  no message was lost")
        elif self.regions:
            unknown = any(self.region_lost_ns(r) is None for r in self.regions)
            lines.append(
                f"  signal lost: {self.lost_s:.6f} s of simulated time"
                + (" and an unknown span at an end of the recording" if unknown else "")
            )
        return "\n".join(lines)

    def _region_text(self, region: DroppedRegion) -> str:
        chunks = f", {region.chunks} chunk(s) in it" if region.chunks else ""
        before, after = region.before_ns, region.after_ns
        lost = self.region_lost_ns(region)
        if lost == 0:
            gap = "no gap in the messages kept around it"
        elif before is not None and after is not None:
            gap = f"no messages between t = {before / 1e9:.6f} and {after / 1e9:.6f} s"
        elif after is not None:
            gap = f"no messages before t = {after / 1e9:.6f} s"
        elif before is not None:
            gap = f"no messages after t = {before / 1e9:.6f} s"
        else:
            gap = "no message kept around it"
        if lost:
            gap += f" ({lost / 1e9:.6f} s lost)"
        return (
            f"bytes {region.start}..{region.end} ({region.end - region.start} bytes{chunks}):"
            f" {region.reason}; {gap}"
        )


@dataclass(frozen=True)
class _KeptChunk:
    offset: int
    length: int  # the whole record, frame included
    crc: int
    compression: str


@dataclass
class _Scan:
    """What the first pass found: kept items in file order, definitions, damage."""

    header_found: bool = False
    chunks: list[_KeptChunk] = field(default_factory=list)
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


def _scan(src: Source, limits: Limits) -> _Scan:
    """First pass: what is intact, what is not (see the module doc)."""
    scan = _Scan()
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


def _read_trusted_summary(src: Source, limits: Limits, scan: _Scan) -> None:
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


def _record_at(src: Source, offset: int, end: int, limits: Limits, scan: _Scan) -> str | int:
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
            if name not in _REBUILT:
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


def _keep_chunk(offset: int, length: int, body: bytes, limits: Limits, scan: _Scan) -> None:
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
    scan.chunks.append(_KeptChunk(offset, length, header.crc, header.compression))


def _frames_as_chunk(src: Source, offset: int, end: int, limits: Limits) -> bool:
    try:
        opcode, _length = read_frame(src, offset, end, limits.max_record_bytes)
    except MalformedError:
        return False
    return opcode == Op.CHUNK


def _resync(src: Source, start: int, end: int, limits: Limits, scan: _Scan) -> int:
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


def _proves_itself(src: Source, offset: int, end: int, limits: Limits, scan: _Scan) -> bool:
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


# -- writing -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Usable:
    channel: Channel
    type_name: str
    qos_yaml: str


def _usable_channels(scan: _Scan, result: Recovery) -> tuple[dict[int, _Usable], dict[int, str]]:
    """Channels whose messages can be kept, and why the others cannot."""
    usable: dict[int, _Usable] = {}
    refused: dict[int, str] = {}
    for channel_id, channel in sorted(scan.channels.items()):
        schema = scan.schemas.get(channel.schema_id)
        try:
            if schema is None:
                raise MalformedError(
                    f"channel {channel_id} refers to schema {channel.schema_id}, which was lost"
                )
            check_schema(schema)
            type_name = check_channel(channel, scan.schemas)
        except MalformedError as exc:
            refused[channel_id] = str(exc)
            continue
        try:
            profile = offered_qos(channel.metadata.get("offered_qos_profiles", ""))
        except MalformedError as exc:
            profile = None
            result.notes.append(
                f"channel {channel_id} ({channel.topic}): {exc}; the recorder's QoS for"
                f" {type_name} is written instead"
            )
        if profile is None:
            profile = TOPIC_BY_TYPE[type_name].qos
        usable[channel_id] = _Usable(channel, type_name, metadata.qos_yaml([profile]))
    return usable, refused


class _Writing:
    """The second pass: re-read the kept chunks (each must still have its CRC) and write."""

    def __init__(self, src: Source, limits: Limits, scan: _Scan, result: Recovery) -> None:
        self.src, self.limits, self.scan, self.result = src, limits, scan, result
        self.usable, self.refused = _usable_channels(scan, result)
        self.chunk_times: dict[int, tuple[int, int]] = {}  # chunk offset -> first, last kept

    def write(self, path: Path) -> None:
        scan, result = self.scan, self.result
        zstd = any(c.compression == "zstd" for c in scan.chunks) or not scan.chunks
        with path.open("wb") as out:
            writer = Writer(
                out,
                compression=CompressionType.ZSTD if zstd else CompressionType.NONE,
                enable_data_crcs=True,
            )
            writer.start(profile=PROFILE, library=f"brake-sim-ros {__version__} (recover)")
            schema_ids: dict[str, int] = {}
            channel_ids: dict[int, int] = {}
            for channel_id, usable in self.usable.items():
                if usable.type_name not in schema_ids:
                    schema_ids[usable.type_name] = writer.register_schema(
                        name=usable.type_name,
                        encoding=SCHEMA_ENCODING,
                        data=schemas.full_definition(usable.type_name).encode(),
                    )
                channel_ids[channel_id] = writer.register_channel(
                    topic=usable.channel.topic,
                    message_encoding=MESSAGE_ENCODING,
                    schema_id=schema_ids[usable.type_name],
                    metadata={
                        "offered_qos_profiles": usable.qos_yaml,
                        "topic_type_hash": schemas.type_hash(usable.type_name),
                    },
                )
            for name, values in scan.metadata:
                writer.add_metadata(name, values)
                result.metadata_kept.append(name)
            counts: Counter[int] = Counter()
            for chunk in scan.chunks:
                self._copy_chunk(chunk, writer, channel_ids, counts)
            if not result.messages:
                raise RecoverError(
                    f"{describe_path(result.source)}: none of its {len(scan.chunks)} intact"
                    " chunks holds a message that can be kept "
                    + self._why_none()
                    + "; nothing written"
                )
            self._finish(writer, path, channel_ids, counts)
            out.flush()

    def _why_none(self) -> str:
        reasons = self.result.dropped_messages
        if reasons:
            return f"({max(reasons, key=reasons.__getitem__)})"
        return "(they hold no messages)"

    def _copy_chunk(
        self, chunk: _KeptChunk, writer: Writer, channel_ids: dict[int, int], counts: Counter
    ) -> None:
        result = self.result
        try:
            opcode, length = read_frame(
                self.src, chunk.offset, self.src.size, self.limits.max_record_bytes
            )
            header = parse_chunk(self.src.read(chunk.offset + FRAME_BYTES, length))
            if opcode != Op.CHUNK or header.crc != chunk.crc:
                raise MalformedError("it is not the chunk read before")
            records = verify_chunk(header, self.limits)
        except MalformedError as exc:
            raise RecoverError(
                f"{describe_path(result.source)} changed while it was recovered (chunk at"
                f" offset {chunk.offset}: {exc}); nothing written"
            ) from None
        times: list[int] = []
        for _inner, op, record in records:
            if op != Op.MESSAGE:
                continue
            message = parse_message(record)
            channel_id = message.channel_id
            if channel_id not in self.usable:
                why = self.refused.get(channel_id)
                if why is None:
                    why = f"channel {channel_id} was defined only in a damaged part of the file"
                result.dropped_messages[why] += 1
                continue
            usable = self.usable[channel_id]
            try:
                cdr.check(usable.type_name, message.data)
            except cdr.CdrError as exc:
                result.dropped_messages[
                    f"payloads on {usable.channel.topic} that do not decode as"
                    f" {usable.type_name} ({exc})"
                ] += 1
                continue
            writer.add_message(
                channel_ids[channel_id],
                log_time=message.log_time,
                data=message.data,
                publish_time=message.publish_time,
                sequence=message.sequence,
            )
            counts[channel_id] += 1
            result.messages += 1
            times.append(message.log_time)
        result.chunks_kept += 1
        if times:
            ordered = sorted(times)
            self.chunk_times[chunk.offset] = (ordered[0], ordered[-1])
            steps = [b - a for a, b in itertools.pairwise(ordered)]
            result.cadence_ns = max([result.cadence_ns, *steps])
            firsts = [ordered[0]] if result.first_ns is None else [result.first_ns, ordered[0]]
            lasts = [ordered[-1]] if result.last_ns is None else [result.last_ns, ordered[-1]]
            result.first_ns, result.last_ns = min(firsts), max(lasts)

    def _finish(
        self, writer: Writer, path: Path, channel_ids: dict[int, int], counts: Counter
    ) -> None:
        result = self.result
        result.per_topic = Counter(
            {self.usable[k].channel.topic: counts[k] for k in channel_ids if counts[k]}
        )
        topics = [
            {
                "name": self.usable[k].channel.topic,
                "type": self.usable[k].type_name,
                "qos_yaml": self.usable[k].qos_yaml,
                "type_hash": schemas.type_hash(self.usable[k].type_name),
                "message_count": counts[k],
            }
            for k in channel_ids
        ]
        scenario = next((v for n, v in self.scan.metadata if n == metadata.SCENARIO), {})
        custom = {"brake_sim_scenario": scenario["name"]} if "name" in scenario else {}
        writer.add_metadata(
            metadata.ROSBAG2,
            metadata.rosbag2_record(
                file_name=Path(result.output).name,
                topics=topics,
                message_count=result.messages,
                start_ns=result.first_ns or 0,
                end_ns=result.last_ns or 0,
                custom_data=custom,
            ),
        )
        result.regions = [self._timed(r) for r in self.scan.regions]
        writer.add_metadata(
            RECOVERY,  # str() of ints
            {
                "source": result.source,
                "source_bytes": str(result.source_bytes),
                "chunks_kept": str(result.chunks_kept),
                "messages_kept": str(result.messages),
                "summary_messages": str(result.summary_messages),
                "dropped_regions": "; ".join(
                    f"{r.start}..{r.end}: {r.reason}" for r in result.regions
                ),
                "dropped_messages": str(sum(result.dropped_messages.values())),
                "cut_short": repr(result.cut_short),
                "last_time_ns": str(result.last_ns),
            },
        )
        writer.finish()

    def _timed(self, region: DroppedRegion) -> DroppedRegion:
        before = [t[1] for off, t in self.chunk_times.items() if off < region.start]
        after = [t[0] for off, t in self.chunk_times.items() if off >= region.end]
        return DroppedRegion(
            region.start,
            region.end,
            region.reason,
            region.chunks,
            max(before) if before else None,
            min(after) if after else None,
        )


def recover(
    broken: str | os.PathLike[str],
    fixed: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    limits: Limits = DEFAULT_LIMITS,
) -> Recovery:
    """Copy every intact chunk of ``broken`` into a valid MCAP file ``fixed``.

    Raises:
        RecordingReadError: ``broken`` is missing, unreadable, not a regular file or over
            the size limit.
        OutputError: ``fixed`` exists (without ``overwrite``), is a link, is ``broken``,
            does not end in .mcap, or cannot be written.
        RecoverError: nothing in ``broken`` can be kept, or it changed while it was read.
    """
    with Source(broken, limits) as src:
        check_output(fixed, inputs=[broken], overwrite=overwrite, suffix=".mcap", option="FIXED")
        scan = _scan(src, limits)
        if not scan.chunks and not scan.header_found:
            raise RecoverError(
                f"{src.name} is not an MCAP file: no MCAP header and no intact chunk in its"
                f" {src.size} bytes; nothing written"
            )
        result = Recovery(
            source=os.fspath(broken),
            output=os.fspath(fixed),
            source_bytes=src.size,
            summary_messages=scan.summary_messages,
            summary_span_ns=scan.summary_span_ns,
            cut_short=not scan.ended and scan.summary_start is None,
        )
        if not scan.chunks:
            raise RecoverError(
                f"{src.name}: no intact chunk (every message is in a chunk); nothing written"
            )
        if scan.loose_messages:
            result.dropped_messages["messages outside a chunk (no CRC covers them)"] += (
                scan.loose_messages
            )
        if scan.summary_note:
            result.notes.append(scan.summary_note)
        if scan.conflicts:
            result.notes.append(
                f"{scan.conflicts} schema or channel records disagreed with an earlier one"
                " with the same id; the first was kept"
            )
        if scan.metadata_over_limit:
            result.notes.append(
                f"{scan.metadata_over_limit} metadata records over the"
                f" {limits.max_metadata_bytes}-byte limit were not kept"
            )
        writing = _Writing(src, limits, scan, result)
        with atomic_output(
            fixed, inputs=[broken], overwrite=overwrite, suffix=".mcap", option="FIXED"
        ) as tmp:
            try:
                writing.write(tmp)
            except OSError as exc:  # a full disk, an I/O error: nothing is left behind
                raise RecoverError(
                    f"cannot write {describe_path(fixed)}: {exc.strerror or exc}; nothing written"
                ) from None
    return result


__all__ = ["DroppedRegion", "RecoverError", "Recovery", "recover"]
