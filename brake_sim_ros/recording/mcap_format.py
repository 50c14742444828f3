"""MCAP, record by record, for hostile input: framing, record parsers and chunk checks.

The format layer under :mod:`.reader` (the strict reader of ``view`` and ``replay``) and
:mod:`.recover` (which keeps what is intact). Nothing here trusts a length or an offset
the file gives: a record's length must fit in what is left (and under :class:`Limits`)
before it is read; each field must fit in its record and a record must be used up
exactly (:class:`Cursor`); a chunk must carry a CRC and decompress to exactly the size it
declares before one of its records is parsed (:func:`verify_chunk`). Bytes are read with
``pread`` at checked offsets (:class:`Source`), never through a memory map, so a file
truncated while it is read gives an error, not a crash. Messages say what is wrong and
where, never the file's bytes (:func:`shown`).
"""

from __future__ import annotations

import errno
import io
import os
import re
import stat
import struct
import zlib
from dataclasses import dataclass
from pathlib import Path

import zstandard

from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.recording import schemas
from brake_sim_ros.stream.topics import TYPES

MAGIC = b"\x89MCAP0\r\n"
PROFILE = "ros2"
SCHEMA_ENCODING = "ros2msg"
MESSAGE_ENCODING = "cdr"
COMPRESSIONS = ("zstd", "")  # what the recorder writes ("" = none)


class Op:
    """MCAP record opcodes (MCAP specification, version 0)."""

    HEADER = 0x01
    FOOTER = 0x02
    SCHEMA = 0x03
    CHANNEL = 0x04
    MESSAGE = 0x05
    CHUNK = 0x06
    MESSAGE_INDEX = 0x07
    CHUNK_INDEX = 0x08
    ATTACHMENT = 0x09
    ATTACHMENT_INDEX = 0x0A
    STATISTICS = 0x0B
    METADATA = 0x0C
    METADATA_INDEX = 0x0D
    SUMMARY_OFFSET = 0x0E
    DATA_END = 0x0F


OP_NAMES = {v: k.lower().replace("_", " ") for k, v in vars(Op).items() if k.isupper()}
FRAME_BYTES = 9  # opcode (1) + record length (8)
FOOTER_BYTES = FRAME_BYTES + 20
MIN_FILE_BYTES = 2 * len(MAGIC) + FRAME_BYTES + 8 + FRAME_BYTES + 4 + FOOTER_BYTES
# a ROS 2 topic name as the recorder writes it: absolute, tokens of [A-Za-z0-9_]
_TOPIC = re.compile(r"^(/[A-Za-z_][A-Za-z0-9_]*)+$")
_SHOWN = re.compile(r"^[A-Za-z0-9_./:=+-]{1,100}$")


class RecordingReadError(BrakeSimError, ValueError):
    """A recording that cannot be used: missing, not MCAP, damaged, or not this project's.

    The message is one line: the file, where (offset, chunk, message), what is wrong and
    what is allowed. It never quotes the file's bytes.
    """


class MalformedError(ValueError):
    """A record or field that does not fit; the message says what (no file contents)."""


@dataclass(frozen=True)
class Limits:
    """Sizes read before anything is allocated; larger inputs are refused.

    Attributes:
        max_file_bytes: the largest recording read (16 GiB, about 2 h of the stream).
        max_record_bytes: the largest record, and the largest uncompressed chunk (the
            recorder closes a chunk at 4 MiB by default).
        max_small_record_bytes: the largest record that is not a chunk (schemas,
            channels, metadata, summary records).
        max_metadata_bytes: all metadata records together (they are kept in memory).
    """

    max_file_bytes: int = 16 * 2**30
    max_record_bytes: int = 256 * 2**20
    max_small_record_bytes: int = 16 * 2**20
    max_metadata_bytes: int = 64 * 2**20


DEFAULT_LIMITS = Limits()


def shown(text: str) -> str:
    """``text`` quoted when it is a plain name, else only its length: file contents such as
    terminal escapes or megabytes of text never reach an error message."""
    if _SHOWN.match(text):
        return repr(text)
    return f"(a {len(text)}-character name, not shown)"


def describe_path(path: str | os.PathLike[str]) -> str:
    """A path for a message: as given when printable, else its ``repr``."""
    text = os.fspath(path)
    return text if text.isprintable() else repr(text)


def recover_hint(name: str) -> str:
    """What to run on a damaged recording (``name`` as :func:`describe_path` gives it)."""
    return f"brake-sim recover {name} FIXED.mcap keeps its intact chunks"


# -- the file --------------------------------------------------------------------------------
class Source:
    """A regular file opened for reading at checked offsets; its size is fixed at open.

    Raises:
        RecordingReadError: missing, unreadable, not a regular file, or over the limit.
    """

    def __init__(self, path: str | os.PathLike[str], limits: Limits = DEFAULT_LIMITS) -> None:
        self.path = Path(path)
        self.name = describe_path(path)
        try:
            # O_NONBLOCK: opening a FIFO does not wait for a writer; it is refused below
            fd = os.open(self.path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
        except OSError as exc:
            if exc.errno == errno.ENOENT:
                raise RecordingReadError(f"{self.name}: no such file") from None
            raise RecordingReadError(
                f"{self.name}: cannot open it ({exc.strerror or exc})"
            ) from None
        try:
            info = os.fstat(fd)
            if not stat.S_ISREG(info.st_mode):
                kind = "a directory" if stat.S_ISDIR(info.st_mode) else "not a regular file"
                raise RecordingReadError(f"{self.name} is {kind}: allowed an .mcap file")
            if info.st_size > limits.max_file_bytes:
                raise RecordingReadError(
                    f"{self.name}: {info.st_size} bytes, over the {limits.max_file_bytes}-byte"
                    " limit for a recording"
                )
        except BaseException:
            os.close(fd)
            raise
        self._fd = fd
        self.size = info.st_size
        self.identity = (info.st_dev, info.st_ino)

    def read(self, offset: int, n: int) -> bytes:
        """Exactly ``n`` bytes at ``offset`` (MalformedError if the file ends first)."""
        if offset < 0 or n < 0 or offset + n > self.size:
            raise MalformedError(
                f"{n} bytes at offset {offset} run past the end ({self.size} bytes)"
            )
        parts, got = [], 0
        while got < n:
            try:
                part = os.pread(self._fd, n - got, offset + got)
            except OSError as exc:
                raise RecordingReadError(
                    f"{self.name}: read error at offset {offset + got} ({exc.strerror or exc})"
                ) from None
            if not part:
                raise RecordingReadError(
                    f"{self.name}: the file became shorter while it was read (at offset"
                    f" {offset + got} of {self.size} bytes); nothing more is read"
                )
            parts.append(part)
            got += len(part)
        return parts[0] if len(parts) == 1 else b"".join(parts)

    def close(self) -> None:
        if self._fd >= 0:
            fd, self._fd = self._fd, -1
            os.close(fd)

    def __enter__(self) -> Source:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


# -- records ----------------------------------------------------------------------------------
class Cursor:
    """Reads the fields of one record body; each read checks that the field fits."""

    __slots__ = ("body", "offset")

    def __init__(self, body: bytes) -> None:
        self.body = body
        self.offset = 0

    def take(self, n: int, what: str) -> bytes:
        left = len(self.body) - self.offset
        if n > left:
            raise MalformedError(f"{what} needs {n} bytes, {left} left in the record")
        out = self.body[self.offset : self.offset + n]
        self.offset += n
        return out

    def u8(self, what: str) -> int:
        return self.take(1, what)[0]

    def u16(self, what: str) -> int:
        return struct.unpack("<H", self.take(2, what))[0]

    def u32(self, what: str) -> int:
        return struct.unpack("<I", self.take(4, what))[0]

    def u64(self, what: str) -> int:
        return struct.unpack("<Q", self.take(8, what))[0]

    def string(self, what: str) -> str:
        raw = self.take(self.u32(what), what)
        try:
            return raw.decode("utf-8")
        except UnicodeDecodeError:
            raise MalformedError(f"{what} is not UTF-8") from None

    def bytes32(self, what: str) -> bytes:
        return self.take(self.u32(what), what)

    def str_map(self, what: str) -> dict[str, str]:
        inner = Cursor(self.bytes32(what))
        out: dict[str, str] = {}
        while inner.offset < len(inner.body):
            key = inner.string(f"{what} key")
            out[key] = inner.string(f"{what} value")
        return out

    def int_map(self, what: str, key_bytes: int) -> dict[int, int]:
        inner = Cursor(self.bytes32(what))
        out: dict[int, int] = {}
        while inner.offset < len(inner.body):
            key = inner.u16(what) if key_bytes == 2 else inner.u32(what)
            out[key] = inner.u64(what)
        return out

    def rest(self) -> bytes:
        out = self.body[self.offset :]
        self.offset = len(self.body)
        return out

    def done(self, what: str) -> None:
        left = len(self.body) - self.offset
        if left:
            raise MalformedError(f"{what} has {left} bytes more than its fields")


@dataclass(frozen=True)
class Schema:
    """A schema record (MCAP opcode 0x03)."""

    id: int
    name: str
    encoding: str
    data: bytes


@dataclass(frozen=True)
class Channel:
    """A channel record (0x04)."""

    id: int
    schema_id: int
    topic: str
    message_encoding: str
    metadata: dict[str, str]


@dataclass(frozen=True)
class Message:
    """A message record (0x05); ``data`` is the CDR payload."""

    channel_id: int
    sequence: int
    log_time: int
    publish_time: int
    data: bytes


@dataclass(frozen=True)
class ChunkHeader:
    """A chunk record (0x06); ``records`` still compressed."""

    start_ns: int
    end_ns: int
    uncompressed_size: int
    crc: int
    compression: str
    records: bytes


@dataclass(frozen=True)
class Statistics:
    """What a statistics record (0x0B) counts."""

    message_count: int
    chunk_count: int
    start_ns: int
    end_ns: int
    channel_message_counts: dict[int, int]


@dataclass(frozen=True)
class Footer:
    """The footer record (0x02)."""

    summary_start: int
    summary_offset_start: int
    summary_crc: int


def parse_header(body: bytes) -> tuple[str, str]:
    c = Cursor(body)
    profile, library = c.string("profile"), c.string("library")
    c.done("the header")
    return profile, library


def parse_schema(body: bytes) -> Schema:
    c = Cursor(body)
    out = Schema(c.u16("schema id"), c.string("schema name"), c.string("schema encoding"), b"")
    out = Schema(out.id, out.name, out.encoding, c.bytes32("schema data"))
    c.done("the schema")
    return out


def parse_channel(body: bytes) -> Channel:
    c = Cursor(body)
    channel_id, schema_id = c.u16("channel id"), c.u16("schema id")
    topic, encoding = c.string("topic"), c.string("message encoding")
    out = Channel(channel_id, schema_id, topic, encoding, c.str_map("channel metadata"))
    c.done("the channel")
    return out


def parse_message(body: bytes) -> Message:
    c = Cursor(body)
    channel_id, sequence = c.u16("channel id"), c.u32("sequence")
    log_time, publish_time = c.u64("log time"), c.u64("publish time")
    return Message(channel_id, sequence, log_time, publish_time, c.rest())


def parse_chunk(body: bytes) -> ChunkHeader:
    c = Cursor(body)
    start, end = c.u64("message start time"), c.u64("message end time")
    size, crc = c.u64("uncompressed size"), c.u32("uncompressed CRC")
    compression = c.string("compression")
    records = c.take(c.u64("records length"), "records")
    c.done("the chunk")
    return ChunkHeader(start, end, size, crc, compression, records)


def parse_metadata(body: bytes) -> tuple[str, dict[str, str]]:
    c = Cursor(body)
    name = c.string("metadata name")
    values = c.str_map("metadata")
    c.done("the metadata")
    return name, values


def parse_message_index(body: bytes) -> int:
    c = Cursor(body)
    channel_id = c.u16("channel id")
    entries = c.bytes32("message index entries")
    if len(entries) % 16:
        raise MalformedError(f"message index entries of {len(entries)} bytes, not pairs of u64")
    c.done("the message index")
    return channel_id


def parse_data_end(body: bytes) -> int:
    c = Cursor(body)
    crc = c.u32("data section CRC")
    c.done("the data end")
    return crc


def parse_footer(body: bytes) -> Footer:
    c = Cursor(body)
    out = Footer(c.u64("summary start"), c.u64("summary offset start"), c.u32("summary CRC"))
    c.done("the footer")
    return out


def parse_statistics(body: bytes) -> Statistics:
    c = Cursor(body)
    count = c.u64("message count")
    c.u16("schema count")
    c.u32("channel count")
    c.u32("attachment count")
    c.u32("metadata count")
    chunks = c.u32("chunk count")
    start, end = c.u64("message start time"), c.u64("message end time")
    per_channel = c.int_map("channel message counts", 2)
    c.done("the statistics")
    return Statistics(count, chunks, start, end, per_channel)


def parse_chunk_index(body: bytes) -> tuple[int, int]:
    """(chunk start offset, chunk length) of a chunk index record."""
    c = Cursor(body)
    c.u64("message start time")
    c.u64("message end time")
    offset, length = c.u64("chunk start offset"), c.u64("chunk length")
    c.int_map("message index offsets", 2)
    c.u64("message index length")
    c.string("compression")
    c.u64("compressed size")
    c.u64("uncompressed size")
    c.done("the chunk index")
    return offset, length


def parse_metadata_index(body: bytes) -> None:
    c = Cursor(body)
    c.u64("offset")
    c.u64("length")
    c.string("name")
    c.done("the metadata index")


def parse_summary_offset(body: bytes) -> None:
    c = Cursor(body)
    c.u8("group opcode")
    c.u64("group start")
    c.u64("group length")
    c.done("the summary offset")


def read_frame(src: Source, offset: int, end: int, limit: int) -> tuple[int, int]:
    """``(opcode, body length)`` of the record at ``offset``; it must end by ``end``."""
    if end - offset < FRAME_BYTES:
        raise MalformedError(f"{end - offset} bytes left, a record needs at least {FRAME_BYTES}")
    opcode, length = struct.unpack("<BQ", src.read(offset, FRAME_BYTES))
    left = end - offset - FRAME_BYTES
    if length > left:
        raise MalformedError(
            f"{OP_NAMES.get(opcode, f'opcode 0x{opcode:02x}')} record of {length} bytes,"
            f" only {left} bytes left"
        )
    if length > limit:
        raise MalformedError(f"record of {length} bytes, over the {limit}-byte limit")
    return opcode, length


def check_schema(schema: Schema) -> None:
    """Refuse a schema that is not a ros2msg definition of a recorded type."""
    if schema.id == 0:
        raise MalformedError("schema id 0 (reserved for 'no schema')")
    if schema.encoding != SCHEMA_ENCODING:
        raise MalformedError(
            f"schema {schema.id} has encoding {shown(schema.encoding)}: allowed {SCHEMA_ENCODING!r}"
        )
    if schema.name not in TYPES:
        raise MalformedError(
            f"schema {schema.id} names type {shown(schema.name)}, not one this project"
            f" records; allowed: {', '.join(sorted(TYPES))}"
        )


def check_channel(channel: Channel, schemas_by_id: dict[int, Schema]) -> str:
    """The type of a valid channel (MalformedError for anything else)."""
    if not _TOPIC.match(channel.topic) or len(channel.topic) > 256:
        raise MalformedError(
            f"channel {channel.id} has topic {shown(channel.topic)}: allowed an absolute ROS"
            " topic name (/a/b_c, letters, digits and _)"
        )
    if channel.message_encoding != MESSAGE_ENCODING:
        raise MalformedError(
            f"channel {channel.id} ({channel.topic}) has message encoding"
            f" {shown(channel.message_encoding)}: allowed {MESSAGE_ENCODING!r}"
        )
    schema = schemas_by_id.get(channel.schema_id)
    if schema is None:
        raise MalformedError(
            f"channel {channel.id} ({channel.topic}) refers to schema {channel.schema_id},"
            " which is not defined before it"
        )
    recorded_hash = channel.metadata.get("topic_type_hash", "")
    installed = schemas.type_hash(schema.name) if recorded_hash else ""
    if recorded_hash and installed and recorded_hash != installed:
        raise MalformedError(
            f"channel {channel.id} ({channel.topic}) was recorded with another definition"
            f" of {schema.name} (its topic_type_hash differs from the installed one)"
        )
    return schema.name


def _decompress(header: ChunkHeader) -> bytes:
    """At most one byte more than the declared size (a longer frame is refused)."""
    wanted = header.uncompressed_size + 1
    parts: list[bytes] = []
    got = 0
    try:
        with zstandard.ZstdDecompressor().stream_reader(io.BytesIO(header.records)) as reader:
            while got < wanted:
                part = reader.read(wanted - got)
                if not part:
                    break
                parts.append(part)
                got += len(part)
    except (zstandard.ZstdError, ValueError) as exc:
        raise MalformedError(f"its zstd data does not decompress ({exc})") from None
    return b"".join(parts)


def verify_chunk(
    header: ChunkHeader, limits: Limits = DEFAULT_LIMITS
) -> list[tuple[int, int, bytes]]:
    """The records ``(offset in chunk, opcode, body)`` of a chunk whose CRC matches.

    Raises:
        MalformedError: an unknown compression, a size over the limit, data that does not
            decompress to the declared size, no CRC or a wrong one, records that do not
            frame, or a record a chunk may not hold.
    """
    if header.compression not in COMPRESSIONS:
        raise MalformedError(
            f"compression {shown(header.compression)}: allowed zstd or none, as the recorder writes"
        )
    if header.uncompressed_size > limits.max_record_bytes:
        raise MalformedError(
            f"declares {header.uncompressed_size} uncompressed bytes, over the"
            f" {limits.max_record_bytes}-byte limit"
        )
    if header.crc == 0:
        raise MalformedError("carries no CRC (0): every chunk the recorder writes has one")
    data = _decompress(header) if header.compression == "zstd" else header.records
    if len(data) != header.uncompressed_size:
        raise MalformedError(
            f"holds {len(data)}{'+' if len(data) > header.uncompressed_size else ''}"
            f" uncompressed bytes, its header says {header.uncompressed_size}"
        )
    crc = zlib.crc32(data)
    if crc != header.crc:
        raise MalformedError(f"CRC 0x{crc:08x} of its records, its header says 0x{header.crc:08x}")
    records = []
    offset = 0
    while offset < len(data):
        if len(data) - offset < FRAME_BYTES:
            raise MalformedError(f"{len(data) - offset} stray bytes at its end")
        opcode, length = struct.unpack_from("<BQ", data, offset)
        if length > len(data) - offset - FRAME_BYTES:
            raise MalformedError(f"a record at byte {offset} of its records runs past its end")
        if opcode not in (Op.SCHEMA, Op.CHANNEL, Op.MESSAGE):
            raise MalformedError(
                f"a {OP_NAMES.get(opcode, f'opcode 0x{opcode:02x}')} record at byte {offset}"
                " of its records: allowed schema, channel and message records"
            )
        start = offset + FRAME_BYTES
        records.append((offset, opcode, data[start : start + length]))
        offset = start + length
    return records
