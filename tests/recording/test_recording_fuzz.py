"""Damaged and hostile recordings through ``recover``, ``view`` and replay's loading path.

Two real bags are recorded (zstd and uncompressed chunks, a chunk every 0.1 s of
simulated time), then damaged in many seeded ways: truncated at random offsets, bytes
flipped in chunk payloads, CRC fields, record lengths, the magic, the footer and the
summary, regions zeroed, garbage appended, two faults at once; and rewritten as well-formed
but hostile files (a schema named ``this/msg/X`` or ``os/msg/system``, a truncated CDR
payload, no chunk CRC, an unknown QoS, a foreign type hash). Every case goes through

* ``brake-sim recover`` (in-process ``cli.main``): exit 0 with a valid file the strict
  reader accepts, or exit 2 with one line on stderr; no partial output either way. On
  success every message is a byte-for-byte copy of an original one (none invented), and
  every message of every chunk whose bytes are intact is kept (provided its channel
  definition survived: the chunk that holds it, or a summary whose bytes are intact);
* ``brake-sim view FILE --save OUT.rrd`` (in-process): exit 0 only for a file whose
  messages are exactly the original ones, else exit 2 with one line and no .rrd;
* replay's loading path (:class:`brake_sim_ros.recording.playback.Recording`, no DDS): the
  original messages exactly, or one :class:`BrakeSimError` line (and ``replay`` itself
  exits 1 with that line, before ROS is initialised).

A few cases run as real subprocesses to prove that no traceback escapes ``main()``.
The seed is fixed, so a failure reproduces; the suite takes about 30 s on 2 cores.
"""

from __future__ import annotations

import io
import os
import random
import struct
import sys
import zlib
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.records import Channel, Chunk
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import CompressionType, Writer

from brake_sim_ros import stream
from brake_sim_ros.app.replay import main as replay_main
from brake_sim_ros.cli import main as cli_main
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.recording.playback import Recording as ReplayRecording
from brake_sim_ros.recording.reader import RecordingReadError, open_recording
from brake_sim_ros.recording.record import record_offline
from brake_sim_ros.recording.writer import RecordingOptions
from brake_sim_ros.ros.harness import domain_id_for, ros_environment
from brake_sim_ros.scenarios import load_scenario
from tests import cli_process

pytestmark = [
    pytest.mark.ros,  # the recorder and the replay module need the ROS wheels (no DDS used)
    pytest.mark.filterwarnings("ignore:module 'sre_(parse|constants)' is deprecated"),
]

SEED = 20261123
DURATION_S = 0.45  # symmetric: impacts from 0.22 s, so the chunks hold varied data
OPTIONS = {
    "zstd": RecordingOptions(compression="zstd", flush_interval_s=0.1, durable=False),
    "none": RecordingOptions(compression="none", flush_interval_s=0.1, durable=False),
}
ROOT = Path(__file__).resolve().parents[2]
Key = tuple[str, int, bytes]  # topic, log time, payload


# -- the original bags and what they hold ----------------------------------------------------
@dataclass(frozen=True)
class ChunkFacts:
    offset: int
    length: int
    messages: tuple[Key, ...]
    defines_channels: frozenset[int]  # channel ids whose Channel record is in this chunk
    uses_channels: frozenset[int]


@dataclass(frozen=True)
class Bag:
    name: str
    path: Path
    data: bytes
    chunks: tuple[ChunkFacts, ...]
    summary_start: int
    messages: tuple[Key, ...]  # log-time order, as the readers give them
    topics: dict[int, str]  # channel id -> topic


def _chunk_facts(data: bytes, offset: int, length: int, topics: dict[int, str]) -> ChunkFacts:
    reader = StreamReader(
        io.BytesIO(data[offset : offset + length]), skip_magic=True, emit_chunks=True
    )
    chunk = next(iter(reader.records))
    assert isinstance(chunk, Chunk)
    records = breakup_chunk(chunk, validate_crc=True)
    defines = frozenset(r.id for r in records if isinstance(r, Channel))
    messages = tuple(
        (topics[r.channel_id], r.log_time, bytes(r.data)) for r in records if hasattr(r, "log_time")
    )
    uses = frozenset(r.channel_id for r in records if hasattr(r, "log_time"))
    return ChunkFacts(offset, length, messages, defines, uses)


def _make_bag(name: str, tmp_path_factory) -> Bag:
    path = tmp_path_factory.mktemp("bags") / f"symmetric_{name}.mcap"
    record_offline(load_scenario("symmetric"), path, duration_s=DURATION_S, options=OPTIONS[name])
    data = path.read_bytes()
    with path.open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        topics = {c.id: c.topic for c in summary.channels.values()}
        messages = tuple(
            (c.topic, m.log_time, bytes(m.data))
            for _s, c, m in reader.iter_messages(log_time_order=True)
        )
    chunks = tuple(
        _chunk_facts(data, i.chunk_start_offset, i.chunk_length, topics)
        for i in sorted(summary.chunk_indexes, key=lambda i: i.chunk_start_offset)
    )
    footer_summary_start = struct.unpack_from("<Q", data, len(data) - 8 - 20)[0]
    assert len(chunks) >= 5, "the bag should have several chunks"
    return Bag(name, path, data, chunks, footer_summary_start, messages, topics)


@pytest.fixture(scope="module")
def bags(tmp_path_factory) -> dict[str, Bag]:
    return {name: _make_bag(name, tmp_path_factory) for name in OPTIONS}


# -- damage ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class Case:
    """One way to damage a bag; ``apply`` turns the bag into the damaged bytes."""

    name: str
    kind: str
    args: tuple

    def __str__(self) -> str:
        return self.name


CHUNK_FIELDS = {  # offsets of a chunk record's fields from its opcode byte
    "length": 1,
    "start_time": 9,
    "uncompressed_size": 25,
    "crc": 33,
    "compression_length": 37,
}


def _cases() -> list[Case]:
    rng = random.Random(SEED)
    cases = [Case(f"truncate@{at}", "truncate_at", (at,)) for at in (0, 4, 8, 20, -1, -8, -9)]
    cases += [
        Case(f"truncate~{f:.3f}", "truncate", (f,)) for f in sorted(rng.random() for _ in range(8))
    ]
    for i in range(8):
        sel, pos, bit = rng.random(), rng.random(), 1 << rng.randrange(8)
        cases.append(Case(f"payload#{i}", "flip_chunk", (sel, pos, bit)))
    for field_name in CHUNK_FIELDS:
        for i in range(2):
            sel, byte = rng.random(), rng.randrange(8 if field_name != "crc" else 4)
            if field_name == "compression_length":
                byte = rng.randrange(4)
            cases.append(Case(f"{field_name}#{i}", "flip_chunk_field", (sel, field_name, byte)))
    cases += [Case("chunk_length_huge", "chunk_length_huge", (rng.random(),))]
    for i in range(10):
        cases.append(Case(f"anywhere#{i}", "flip", (rng.random(), 1 << rng.randrange(8))))
    for i in range(6):
        cases.append(Case(f"zeros#{i}", "zero", (rng.random(), rng.randrange(16, 5000))))
    cases += [Case(f"garbage#{i}", "append", (rng.randrange(1, 3000),)) for i in range(2)]
    cases += [Case(f"magic#{i}", "flip_at", (i, 0x40)) for i in (0, 5)]
    cases += [Case("tail_magic", "flip_at", (-3, 0x01))]
    cases += [Case(f"footer#{i}", "flip_at", (-8 - 20 + i, 0x10)) for i in (0, 9, 17)]
    cases += [Case(f"summary#{i}", "flip_summary", (rng.random(),)) for i in range(3)]
    cases += [Case("first_chunk", "flip_chunk", (0.0, 0.5, 0x04))]
    cases += [Case("first_chunk+summary", "first_chunk_and_summary", ())]
    cases += [Case("first_chunk+truncated", "first_chunk_and_truncate", ())]
    cases += [Case("two_chunks", "two_chunks", (rng.random(), rng.random()))]
    cases += [Case("float_1e300", "poke_float", ())]
    cases += [Case("empty", "truncate_at", (0,)), Case("magic_only", "truncate_at", (8,))]
    crafted = [
        ("schema_this_msg_X", "rename_schema", ("this/msg/X",)),
        ("schema_os_msg_system", "rename_schema", ("os/msg/system",)),
        ("truncated_cdr", "truncate_message", (0.5,)),
        ("no_chunk_crc", "no_crc", ()),
        ("hostile_qos", "qos", ("- history: {a: [1, 2]}\n  depth: 99999999999\n",)),
        ("qos_yaml_bomb", "qos", ("[" * 5000 + "]" * 5000,)),
        ("foreign_type_hash", "type_hash", ("RIHS01_" + "0" * 64,)),
        ("topic_name_escape", "rename_topic", ("/brake_sim/\x1b[31mred",)),
    ]
    cases += [Case(name, kind, args) for name, kind, args in crafted]
    return cases


CASES = _cases()
CRAFTED = {"rename_schema", "truncate_message", "no_crc", "qos", "type_hash", "rename_topic"}


def _chunk(bag: Bag, sel: float) -> ChunkFacts:
    return bag.chunks[min(int(sel * len(bag.chunks)), len(bag.chunks) - 1)]


def _flip(data: bytearray, at: int, bit: int) -> None:
    data[at] ^= bit


def damage(bag: Bag, case: Case, tmp: Path) -> bytes:
    """The damaged bytes of ``bag`` for ``case``."""
    data = bytearray(bag.data)
    kind, args = case.kind, case.args
    if kind == "truncate_at":
        return bytes(data[: args[0]] if args[0] >= 0 else data[: len(data) + args[0]])
    if kind == "truncate":
        return bytes(data[: int(args[0] * len(data))])
    if kind == "flip_chunk":
        chunk = _chunk(bag, args[0])
        payload_start = chunk.offset + 9 + 40 + (4 if bag.name == "zstd" else 0)
        _flip(
            data,
            payload_start + int(args[1] * (chunk.offset + chunk.length - payload_start)),
            args[2],
        )
    elif kind == "flip_chunk_field":
        chunk = _chunk(bag, args[0])
        _flip(data, chunk.offset + CHUNK_FIELDS[args[1]] + args[2], 0x01)
    elif kind == "chunk_length_huge":
        data[_chunk(bag, args[0]).offset + 1 : _chunk(bag, args[0]).offset + 9] = b"\xff" * 8
    elif kind == "flip":
        _flip(data, int(args[0] * (len(data) - 1)), args[1])
    elif kind == "zero":
        at = int(args[0] * len(data))
        data[at : at + args[1]] = bytes(len(data[at : at + args[1]]))
    elif kind == "append":
        data += random.Random(args[0]).randbytes(args[0])
    elif kind == "flip_at":
        _flip(data, args[0], args[1])
    elif kind == "flip_summary":
        _flip(data, bag.summary_start + int(args[0] * (len(data) - 40 - bag.summary_start)), 0x02)
    elif kind == "first_chunk_and_summary":
        _flip(data, bag.chunks[0].offset + bag.chunks[0].length // 2, 0x08)
        _flip(data, bag.summary_start + 30, 0x08)
    elif kind == "first_chunk_and_truncate":
        _flip(data, bag.chunks[0].offset + bag.chunks[0].length // 2, 0x08)
        return bytes(data[: bag.chunks[-2].offset + 5])
    elif kind == "two_chunks":
        for sel in args:
            chunk = _chunk(bag, sel)
            _flip(data, chunk.offset + chunk.length - 3, 0x20)
    elif kind == "poke_float":  # the issue's 1e300 N: a force value replaced in place
        chunk = bag.chunks[len(bag.chunks) // 2]
        at = chunk.offset + chunk.length // 2
        data[at : at + 8] = struct.pack("<d", 1e300)
    else:
        return _crafted(bag, case, tmp)
    return bytes(data)


def _crafted(bag: Bag, case: Case, tmp: Path) -> bytes:
    """A well-formed MCAP (valid CRCs) with one hostile change, written by mcap's Writer."""
    kind, args = case.kind, case.args
    out = io.BytesIO()
    with bag.path.open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        writer = Writer(
            out,
            chunk_size=64 * 1024,
            compression=CompressionType.ZSTD,
            enable_crcs=kind != "no_crc",
        )
        writer.start(profile="ros2", library="fuzz")
        schema_ids = {}
        for schema in summary.schemas.values():
            name = schema.name
            if kind == "rename_schema" and name == stream.PIVOT_FORCES.type_name:
                name = args[0]
            schema_ids[schema.id] = writer.register_schema(name, schema.encoding, schema.data)
        channel_ids = {}
        for channel in summary.channels.values():
            meta = dict(channel.metadata)
            topic = channel.topic
            if channel.topic == stream.STATE.name:
                if kind == "qos":
                    meta["offered_qos_profiles"] = args[0]
                elif kind == "type_hash":
                    meta["topic_type_hash"] = args[0]
                elif kind == "rename_topic":
                    topic = args[0]
            channel_ids[channel.id] = writer.register_channel(
                topic, channel.message_encoding, schema_ids[channel.schema_id], meta
            )
        for record in reader.iter_metadata():
            writer.add_metadata(record.name, dict(record.metadata))
        pivot = [
            m.log_time
            for _s, c, m in reader.iter_messages(log_time_order=False)
            if c.topic == stream.PIVOT_FORCES.name
        ]
        victim = pivot[int(args[0] * len(pivot))] if kind == "truncate_message" else None
        for _s, channel, message in reader.iter_messages(log_time_order=False):
            data = bytes(message.data)
            if channel.topic == stream.PIVOT_FORCES.name and message.log_time == victim:
                data = data[: len(data) // 2]
            writer.add_message(
                channel_ids[channel.id],
                message.log_time,
                data,
                message.publish_time,
                message.sequence,
            )
        writer.finish()
    return out.getvalue()


# -- what must survive -------------------------------------------------------------------------
def must_keep(bag: Bag, case: Case, broken: bytes) -> Counter[Key]:
    """Messages recover must keep: those of intact chunks whose channels can be known."""
    if case.kind in CRAFTED:
        return _crafted_keep(bag, case)
    intact = [
        c
        for c in bag.chunks
        if broken[c.offset : c.offset + c.length] == bag.data[c.offset : c.offset + c.length]
    ]
    summary_intact = (
        len(broken) == len(bag.data)
        and broken[bag.summary_start :] == bag.data[bag.summary_start :]
    )
    known: set[int] = set(bag.topics) if summary_intact else set()
    for chunk in intact:
        known |= chunk.defines_channels
    names = {bag.topics[k] for k in known}
    return Counter(m for c in intact for m in c.messages if m[0] in names)


def _crafted_keep(bag: Bag, case: Case) -> Counter[Key]:
    everything = Counter(bag.messages)
    if case.kind == "rename_schema":
        return Counter({m: n for m, n in everything.items() if m[0] != stream.PIVOT_FORCES.name})
    if case.kind == "truncate_message":
        return Counter()  # checked separately: all but one
    if case.kind in ("type_hash", "rename_topic"):
        return Counter({m: n for m, n in everything.items() if m[0] != stream.STATE.name})
    if case.kind == "no_crc":
        return Counter()
    return everything  # qos: the channel is kept with the recorder's QoS


def _messages_of(path: Path) -> Counter[Key]:
    with open_recording(path) as recording:
        return Counter((m.topic.name, m.log_time_ns, m.data) for m in recording.messages())


def _one_line_error(err: str) -> str:
    assert "Traceback" not in err, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, f"expected one line on stderr, got {len(lines)}:\n{err}"
    return lines[0]


def _leftovers(directory: Path, keep: set[str]) -> list[str]:
    return sorted(p.name for p in directory.iterdir() if p.name not in keep)


# -- the tests ------------------------------------------------------------------------------------
@pytest.fixture(params=list(OPTIONS))
def bag(request, bags) -> Bag:
    return bags[request.param]


@pytest.mark.parametrize("case", CASES, ids=str)
def test_recover(bag: Bag, case: Case, tmp_path: Path, capfd):
    broken = tmp_path / "broken.mcap"
    damaged = damage(bag, case, tmp_path)
    broken.write_bytes(damaged)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    fixed = out_dir / "fixed.mcap"
    code = cli_main(["recover", str(broken), str(fixed)])
    out, err = capfd.readouterr()
    assert broken.read_bytes() == damaged, "the input was changed"
    if code != 0:
        assert code == 2
        line = _one_line_error(err)
        assert line.startswith("brake-sim: error: ")
        assert _leftovers(out_dir, set()) == [], "partial output left behind"
        must = must_keep(bag, case, damaged)
        assert not must, f"refused, but {sum(must.values())} intact messages could be kept: {line}"
        return
    assert "Traceback" not in err
    assert _leftovers(out_dir, {"fixed.mcap"}) == []
    assert out.startswith("recovered "), out
    kept = _messages_of(fixed)  # the strict reader accepts the output
    original = Counter(bag.messages)
    invented = kept - original
    assert not invented, f"{sum(invented.values())} messages not in the original"
    missing = must_keep(bag, case, damaged) - kept
    assert not missing, f"{sum(missing.values())} intact messages dropped:\n{out}"
    if case.kind == "truncate_message":
        assert sum(kept.values()) == len(bag.messages) - 1
        assert "do not decode as brake_sim_msgs/msg/PivotForceChunk" in out
    if sum(kept.values()) < len(bag.messages):
        assert "dropped" in out, out  # what was dropped is reported


@pytest.mark.parametrize("case", CASES, ids=str)
def test_view(bag: Bag, case: Case, tmp_path: Path, capfd):
    broken = tmp_path / "broken.mcap"
    broken.write_bytes(damage(bag, case, tmp_path))
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    rrd = out_dir / "view.rrd"
    code = cli_main(["view", str(broken), "--save", str(rrd)])
    _out, err = capfd.readouterr()
    if code != 0:
        assert code == 2
        line = _one_line_error(err)
        assert line.startswith("brake-sim: error: ")
        assert _leftovers(out_dir, set()) == [], "partial output left behind"
        _expect_reason(case, line)
        return
    assert _leftovers(out_dir, {"view.rrd"}) == [] and rrd.stat().st_size > 0
    assert case.kind not in CRAFTED, "a hostile file was shown"
    assert _messages_of(broken) == Counter(bag.messages), "a damaged recording was shown"


@pytest.mark.parametrize("case", CASES, ids=str)
def test_replay_loading(bag: Bag, case: Case, tmp_path: Path, capfd):
    broken = tmp_path / "broken.mcap"
    broken.write_bytes(damage(bag, case, tmp_path))
    try:
        recording = ReplayRecording(broken)
    except BrakeSimError as exc:
        assert "\n" not in str(exc)
        _expect_reason(case, str(exc))
        code = replay_main(["brake-sim replay", str(broken)])  # refused before ROS starts
        assert code == 1
        line = _one_line_error(capfd.readouterr().err)
        assert line == f"brake-sim replay: error: {exc}"
        return
    try:
        got = Counter((t, ns, data) for t, data, ns in recording.messages())
        recording.latched_before(recording.start_ns + 200_000_000)
    finally:
        recording.close()
    assert got == Counter(bag.messages), "a damaged recording would be replayed"


def _expect_reason(case: Case, line: str) -> None:
    """The refusals of the issue's cases name what is wrong and where."""
    assert "\x1b" not in line, "file contents echoed"
    if case.kind == "rename_schema":
        assert f"names type '{case.args[0]}', not one this project records" in line
    elif case.kind == "truncate_message":
        assert "/brake_sim/pivot_forces" in line and "message " in line
        assert "does not decode as brake_sim_msgs/msg/PivotForceChunk" in line
    elif case.kind == "no_crc":
        assert "carries no CRC" in line
    elif case.kind in ("flip_chunk", "two_chunks", "poke_float"):
        assert "chunk" in line and "brake-sim recover" in line
    elif case.kind == "rename_topic":
        assert "not shown" in line


@pytest.mark.parametrize("path", sorted((ROOT / "bags").glob("*.mcap")), ids=lambda p: p.name)
def test_the_shipped_bags_pass_the_strict_reader(path: Path):
    with open_recording(path) as recording:
        assert recording.message_count == sum(1 for _ in recording.messages()) > 0


def test_the_cases_cover_the_issue():
    kinds = {c.kind for c in CASES}
    assert {
        "truncate",
        "flip_chunk",
        "flip_chunk_field",
        "rename_schema",
        "truncate_message",
    } <= kinds
    assert {"flip_at", "flip_summary", "zero", "append", "poke_float"} <= kinds
    assert len(CASES) >= 60


def test_issue_pattern_damaged_chunk_keeps_before_and_after(bags, tmp_path):
    """One damaged chunk in the middle: every other chunk's messages are kept and the report
    names the chunk's offset and the time lost."""
    bag = bags["zstd"]
    middle = bag.chunks[len(bag.chunks) // 2]
    data = bytearray(bag.data)
    data[middle.offset + middle.length // 2] ^= 0x10
    broken, fixed = tmp_path / "broken.mcap", tmp_path / "fixed.mcap"
    broken.write_bytes(data)
    from brake_sim_ros.recording.recover import recover

    result = recover(broken, fixed)
    assert result.messages == len(bag.messages) - len(middle.messages)
    assert [r.start for r in result.regions] == [middle.offset]
    assert result.regions[0].chunks == 1
    assert result.lost_s == pytest.approx(0.1, abs=1e-9)  # one 0.1 s chunk
    text = result.describe()
    assert f"of {len(bag.messages)} messages" in text and f"bytes {middle.offset}.." in text


# -- real processes: no traceback escapes main() ----------------------------------------------
SUBPROCESS_CASES = ("payload#0", "schema_this_msg_X")


@pytest.mark.slow
def test_subprocesses_refuse_with_one_line(bags, tmp_path):
    """view and replay refuse the damaged file; recover refuses to write over its input."""
    by_name = {c.name: c for c in CASES}
    env = {**ros_environment(domain_id_for(7)), "PYTHONPATH": str(ROOT)}
    cli = [sys.executable, "-m", "brake_sim_ros.cli"]
    for i, name in enumerate(SUBPROCESS_CASES):
        broken = tmp_path / f"case{i}.mcap"
        broken.write_bytes(damage(bags["zstd"], by_name[name], tmp_path))
        commands = {
            "view": [*cli, "view", str(broken), "--save", str(tmp_path / f"case{i}.rrd")],
            "replay": [*cli, "replay", str(broken)],
            "recover": [*cli, "recover", str(broken), str(broken), "--overwrite"],
        }
        for what, argv in commands.items():
            proc = cli_process.run(argv, env=env, capture_output=True, text=True, timeout=120)
            assert proc.returncode in (1, 2), (
                name,
                what,
                proc.returncode,
                proc.stdout,
                proc.stderr,
            )
            line = _one_line_error(proc.stderr)
            assert line.startswith("brake-sim"), line
    assert not list(tmp_path.glob("*.rrd")) and not list(tmp_path.glob(".*partial*"))


def test_non_files_are_refused_without_waiting(tmp_path, capfd):
    fifo = tmp_path / "pipe.mcap"
    os.mkfifo(fifo)
    for argv in (
        ["view", str(fifo), "--save", str(tmp_path / "x.rrd")],
        ["recover", str(fifo), str(tmp_path / "x.mcap")],
        ["view", str(tmp_path), "--save", str(tmp_path / "x.rrd")],
        ["recover", "/dev/zero", str(tmp_path / "x.mcap")],
    ):
        assert cli_main(argv) == 2
        line = _one_line_error(capfd.readouterr().err)
        assert "not a regular file" in line or "is a directory" in line, line
    with pytest.raises(RecordingReadError, match="not a regular file"):
        ReplayRecording(fifo)


def test_limits_refuse_before_reading(bags, tmp_path):
    from brake_sim_ros.recording.mcap_format import Limits

    with pytest.raises(RecordingReadError, match="over the 1000-byte limit"):
        open_recording(bags["zstd"].path, limits=Limits(max_file_bytes=1000))
    small = Limits(max_record_bytes=4096)
    with pytest.raises(RecordingReadError, match="over the 4096-byte limit"):
        open_recording(bags["zstd"].path, limits=small)


def test_crc_of_a_checked_chunk_is_compared_again_when_read(bags, tmp_path):
    """A file that changes after it was checked stops the reading with one line."""
    bag = bags["none"]
    path = tmp_path / "changing.mcap"
    path.write_bytes(bag.data)
    with open_recording(path) as recording:
        chunk = recording.chunks[-1]
        data = bytearray(bag.data)
        data[chunk.offset + chunk.length - 2] ^= 0x01
        path.write_bytes(data)  # same inode, new contents
        with pytest.raises(RecordingReadError, match="changed since the file was checked"):
            list(recording.messages())
    assert zlib.crc32(path.read_bytes()) != zlib.crc32(bag.data)
