"""``brake-sim recover BROKEN.mcap FIXED.mcap``: keep every intact chunk of a damaged recording.

A recording cut short (SIGKILL, power loss, full disk) has no summary and may end inside a
record; a damaged one (a bad sector, a bad copy) has chunks whose bytes changed anywhere.
:func:`recover` walks the file record by record (:mod:`.intact_scan`, the first pass) and
keeps

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
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from mcap.writer import CompressionType, Writer

from brake_sim_ros import __version__
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.recording import cdr, metadata, schemas
from brake_sim_ros.recording.channel_qos import offered_qos
from brake_sim_ros.recording.intact_scan import DroppedRegion, IntactScan, KeptChunk, scan_intact
from brake_sim_ros.recording.mcap_format import (
    DEFAULT_LIMITS,
    FRAME_BYTES,
    MESSAGE_ENCODING,
    PROFILE,
    SCHEMA_ENCODING,
    Channel,
    Limits,
    MalformedError,
    Op,
    Source,
    check_channel,
    check_schema,
    describe_path,
    parse_chunk,
    parse_message,
    read_frame,
    verify_chunk,
)
from brake_sim_ros.recording.output import atomic_output, check_output
from brake_sim_ros.stream.topics import TOPIC_BY_TYPE


class RecoverError(BrakeSimError, ValueError):
    """An input with nothing to recover, or an output that cannot be written (one line)."""


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
class _Usable:
    channel: Channel
    type_name: str
    qos_yaml: str


def _usable_channels(
    scan: IntactScan, result: Recovery
) -> tuple[dict[int, _Usable], dict[int, str]]:
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

    def __init__(self, src: Source, limits: Limits, scan: IntactScan, result: Recovery) -> None:
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
        self, chunk: KeptChunk, writer: Writer, channel_ids: dict[int, int], counts: Counter
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
            metadata.RECOVERY,  # str() of ints
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
        scan = scan_intact(src, limits)
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


__all__ = ["RecoverError", "Recovery", "recover"]
