"""MCAP recordings written offline, read back by independent readers.

rosbags (its own MCAP parser and CDR decoder, typestore built from the file's schemas)
reads every topic and decodes every message; values are compared exactly with the
messages the stream produced. rclpy's decoder (the DDS typesupport) decodes every payload
to an equal message. Rerun's own MCAP loader (``rerun mcap convert``) opens the file.
Then the structure rosbag2 expects, the metadata records, recovery of truncated files
and the failures (full disk, bad path, bad options).
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytestmark = [
    pytest.mark.ros,
    # lark (pulled in by rclpy's type-description code) imports sre_parse.
    pytest.mark.filterwarnings("ignore:module 'sre_(parse|constants)' is deprecated"),
]
rclpy = pytest.importorskip("rclpy", reason="rclpy not installed (run scripts/setup.sh)")

import yaml  # noqa: E402  (PyYAML comes with the ROS wheels; rosbag2 YAML is checked with it)
from mcap.reader import make_reader  # noqa: E402
from rclpy.serialization import deserialize_message  # noqa: E402
from rosbags.rosbag2.storage_mcap import McapReader  # noqa: E402
from rosbags.typesys import Stores, get_types_from_msg, get_typestore  # noqa: E402

from brake_sim_ros import stream  # noqa: E402
from brake_sim_ros.model import catalogue  # noqa: E402
from brake_sim_ros.recording import metadata  # noqa: E402
from brake_sim_ros.recording.reader import RecordingReadError  # noqa: E402
from brake_sim_ros.recording.record import record_offline  # noqa: E402
from brake_sim_ros.recording.recover import RecoverError, recover  # noqa: E402
from brake_sim_ros.recording.writer import (  # noqa: E402
    McapRecorder,
    RecordingError,
    RecordingOptions,
)
from brake_sim_ros.scenarios import load_scenario  # noqa: E402
from brake_sim_ros.stream import conversion  # noqa: E402
from brake_sim_ros.stream import parameters as ros_params  # noqa: E402
from brake_sim_ros.stream.build import stepper_for  # noqa: E402
from brake_sim_ros.stream.offline import offline_messages  # noqa: E402
from tests import cli_process  # noqa: E402

SCENARIO = "case7_left_actuation"
DURATION_S = 2.5
RUN_ID = "5b1c0e7a9d2f4c6e8a0b1d3f5e7c9a2b"  # given to both: the stream and its recording
RERUN = Path(sys.executable).with_name("rerun")


@pytest.fixture(scope="module")
def scenario():
    return load_scenario(SCENARIO)


@pytest.fixture(scope="module")
def source(scenario):
    """The stream as produced: (topic, message, time ns), in order."""
    return list(offline_messages(scenario, duration_s=DURATION_S, run_id=RUN_ID))


@pytest.fixture(scope="module", params=["zstd", "none"])
def recording(request, scenario, tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("rec") / f"{SCENARIO}_{request.param}.mcap"
    options = RecordingOptions(compression=request.param, durable=False)
    record_offline(scenario, path, duration_s=DURATION_S, options=options, run_id=RUN_ID)
    return path


def _rosbags_messages(path: Path):
    """(topic, type, log time, decoded message) of every message, by rosbags alone."""
    reader = McapReader(path)
    reader.open()
    try:
        store = get_typestore(Stores.EMPTY)
        for conn in reader.connections:
            assert conn.msgdef.format.name == "MSG"
            store.register(get_types_from_msg(conn.msgdef.data, conn.msgtype))
        out = [
            (conn.topic, conn.msgtype, ns, store.deserialize_cdr(data, conn.msgtype))
            for conn, ns, data in reader.messages(reader.connections)
        ]
        return list(reader.connections), out
    finally:
        reader.close()


def test_rosbags_reads_every_topic_and_values_round_trip_exactly(recording, source):
    connections, decoded = _rosbags_messages(recording)
    topics = {t.name for t, _, _ in source}
    assert {c.topic for c in connections} == topics
    for conn in connections:
        assert conn.ext.serialization_format == "cdr"
        assert len(conn.ext.offered_qos_profiles) == 1
    # rosbags yields in log-time order; the stream's order within one time is kept
    by_time = sorted(range(len(source)), key=lambda i: source[i][2])
    assert [(d[0], d[2]) for d in decoded] == [(source[i][0].name, source[i][2]) for i in by_time]

    chunks = [d[3] for d in decoded if d[0] == stream.PIVOT_FORCES.name]
    src_chunks = [m for t, m, _ in source if t is stream.PIVOT_FORCES]
    for name in conversion.PIVOT_CHUNK_ARRAYS:
        got = np.concatenate([getattr(c, name) for c in chunks])
        want = np.concatenate([np.asarray(getattr(c, name)) for c in src_chunks])
        assert got.dtype == np.float64
        np.testing.assert_array_equal(got, want)  # exact, bit for bit
    assert [c.first_sample_index for c in chunks] == [c.first_sample_index for c in src_chunks]

    states = [d[3] for d in decoded if d[0] == stream.STATE.name]
    src_states = [m for t, m, _ in source if t is stream.STATE]
    assert len(states) == len(src_states) > 0
    for got, want in zip(states, src_states, strict=True):
        for field in want.get_fields_and_field_types():
            if field == "header":
                assert got.header.stamp.sec == want.header.stamp.sec
                assert got.header.stamp.nanosec == want.header.stamp.nanosec
                assert got.header.frame_id == want.header.frame_id
            else:
                assert getattr(got, field) == getattr(want, field), field

    joints = [d[3] for d in decoded if d[0] == stream.JOINT_STATES.name]
    src_joints = [m for t, m, _ in source if t is stream.JOINT_STATES]
    for got, want in zip(joints, src_joints, strict=True):
        assert list(got.name) == list(want.name)
        for field in ("position", "velocity", "effort"):
            np.testing.assert_array_equal(getattr(got, field), np.asarray(getattr(want, field)))


def test_rclpy_decodes_every_payload_to_the_same_message(recording, source):
    with recording.open("rb") as f:
        reader = make_reader(f)
        got = [
            (channel.topic, message.log_time, message.publish_time, schema.name, message.data)
            for schema, channel, message in reader.iter_messages(log_time_order=False)
        ]
    assert len(got) == len(source)
    for (topic, log_ns, pub_ns, type_name, data), (t, msg, ns) in zip(got, source, strict=True):
        assert (topic, log_ns, pub_ns, type_name) == (t.name, ns, ns, t.type_name)
        assert deserialize_message(data, type(msg)) == msg


def test_file_is_what_rosbag2_mcap_writes(recording, source):
    compression = "zstd" if recording.stem.endswith("zstd") else ""
    with recording.open("rb") as f:
        reader = make_reader(f)
        assert reader.get_header().profile == "ros2"
        summary = reader.get_summary()
        assert summary is not None and summary.statistics.message_count == len(source)
        for schema in summary.schemas.values():
            assert schema.encoding == "ros2msg"
            assert schema.name.count("/msg/") == 1
            for line in schema.data.decode().splitlines():
                if line.startswith("MSG: "):
                    assert line.split()[1].count("/") == 1  # rosbag2: as the field names it
        for channel in summary.channels.values():
            assert channel.message_encoding == "cdr"
            assert set(channel.metadata) == {"offered_qos_profiles", "topic_type_hash"}
            assert channel.metadata["topic_type_hash"].startswith("RIHS01_")
            profiles = yaml.safe_load(channel.metadata["offered_qos_profiles"])
            assert profiles[0]["history"] == "keep_last"
            assert profiles[0]["reliability"] in ("reliable", "best_effort")
        assert summary.chunk_indexes
        for index in summary.chunk_indexes:
            assert index.compression == compression
            # the flush interval (1 s simulated) bounds every chunk's span
            assert index.message_end_time - index.message_start_time < 1_000_000_000
        records = {m.name: m.metadata for m in reader.iter_metadata()}
    bag = yaml.safe_load(records["rosbag2"]["serialized_metadata"])
    assert bag["version"] == 9 and bag["storage_identifier"] == "mcap"
    assert bag["message_count"] == len(source)
    counts = {
        t["topic_metadata"]["name"]: t["message_count"] for t in bag["topics_with_message_count"]
    }
    assert counts == {
        name: sum(t.name == name for t, _, _ in source) for name in {t.name for t, _, _ in source}
    }
    assert bag["duration"]["nanoseconds"] == source[-1][2]


def test_metadata_explains_the_recording(recording, scenario):
    with recording.open("rb") as f:
        records = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
    model = records[metadata.MODEL]
    assert set(model) == set(ros_params.model_values(scenario.setup.params, scenario.setup.defects))
    params, defects = ros_params.build_model({k: ast.literal_eval(v) for k, v in model.items()})
    assert (params, defects) == (scenario.setup.params, scenario.setup.defects)
    assert records[metadata.SCENARIO]["toml"] == scenario.text
    assert records[metadata.SCENARIO]["name"] == scenario.name
    run = records[metadata.RUN]
    assert run["mode"] == "offline"
    assert run["run_id"] == RUN_ID
    assert ast.literal_eval(run["seed"]) == scenario.seed
    stepper = stepper_for(scenario)
    assert ast.literal_eval(run["sample_rate_hz"]) == scenario.sample_rate_hz == 25_600.0
    assert ast.literal_eval(run["sample_period_s"]) == stepper.sample_period_s
    assert ast.literal_eval(run["physics_step_s"]) == stepper.physics_step_s
    assert ast.literal_eval(run["substeps_per_sample"]) == stepper.substeps
    assert ast.literal_eval(run["step_limit_s"]) == stepper.limit.max_step_s
    assert (run["scheme"], run["preset"]) == ("rk4-located", "balanced")
    assert ast.literal_eval(run["duration_s"]) == DURATION_S
    assert run["software_version"].startswith("brake-sim-ros ")


@pytest.mark.skipif(not RERUN.exists(), reason="rerun CLI not installed")
def test_rerun_mcap_loader_opens_the_file(recording, tmp_path, source):
    out = tmp_path / "out.rrd"
    done = subprocess.run(
        [str(RERUN), "mcap", "convert", str(recording), "-o", str(out)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    assert out.stat().st_size > 0
    for topic in {t.name for t, _, _ in source}:
        assert f"    {topic},\n" in done.stderr, f"rerun made no entity for {topic}"
    verify = subprocess.run(
        [str(RERUN), "rrd", "verify", str(out)], capture_output=True, text=True, timeout=60
    )
    assert verify.returncode == 0, verify.stderr


# -- recovery ----------------------------------------------------------------------------------
def test_recover_keeps_every_complete_chunk_and_nothing_else(recording, source, tmp_path):
    data = recording.read_bytes()
    with recording.open("rb") as f:
        summary = make_reader(f).get_summary()
    indexes = summary.chunk_indexes
    assert len(indexes) >= 3
    cumulative = 0
    for i, index in enumerate(indexes[:-1]):
        # cut inside the next chunk: everything of chunks 0..i survives, nothing after
        cumulative += sum(
            1 for _t, _m, ns in source if index.message_start_time <= ns <= index.message_end_time
        )
        cut = indexes[i + 1].chunk_start_offset + indexes[i + 1].chunk_length // 2
        broken = tmp_path / f"broken{i}.mcap"
        broken.write_bytes(data[:cut])
        fixed = tmp_path / f"fixed{i}.mcap"
        result = recover(broken, fixed)
        assert not result.complete and result.chunks_kept == i + 1
        assert result.messages == cumulative
        with fixed.open("rb") as f:
            reader = make_reader(f)
            got = [
                (c.topic, m.log_time, m.data)
                for _s, c, m in reader.iter_messages(log_time_order=False)
            ]
            names = {m.name for m in reader.iter_metadata()}
        assert {metadata.MODEL, metadata.SCENARIO, metadata.RUN, "rosbag2"} <= names
        with recording.open("rb") as f:
            want = [
                (c.topic, m.log_time, m.data)
                for _s, c, m in make_reader(f).iter_messages(log_time_order=False)
            ][:cumulative]
        assert got == want
        _connections, decoded = _rosbags_messages(fixed)  # and rosbags reads it
        assert len(decoded) == cumulative


def test_recover_of_a_whole_file_loses_nothing(recording, source, tmp_path):
    result = recover(recording, tmp_path / "copy.mcap")
    assert result.complete and result.messages == len(source)


def test_recover_refuses_what_is_not_mcap(tmp_path):
    text = tmp_path / "notes.mcap"
    text.write_text("not a recording\n")
    with pytest.raises(RecoverError, match=r"notes\.mcap is not an MCAP file"):
        recover(text, tmp_path / "out.mcap")
    with pytest.raises(RecordingReadError, match=r"missing\.mcap: no such file"):
        recover(tmp_path / "missing.mcap", tmp_path / "out.mcap")


@pytest.mark.slow
def test_cli_simulate_mcap_and_recover(tmp_path):
    path = tmp_path / "cli.mcap"
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])}
    cli = [sys.executable, "-m", "brake_sim_ros.cli"]
    run = cli_process.run(
        [*cli, "simulate", "symmetric", "--duration", "0.5", "--quiet", "--mcap", str(path)],
        capture_output=True, text=True, timeout=120, env=env,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert f"recording: {path}" in run.stdout
    broken = tmp_path / "broken.mcap"
    broken.write_bytes(path.read_bytes()[:-100])
    run = cli_process.run(
        [*cli, "recover", str(broken), str(tmp_path / "fixed.mcap")],
        capture_output=True, text=True, timeout=60, env=env,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert "/brake_sim/pivot_forces: 50" in run.stdout
    run = cli_process.run(
        [*cli, "recover", str(Path(__file__)), str(tmp_path / "x.mcap")],
        capture_output=True, text=True, timeout=60, env=env,
    )  # fmt: skip
    assert run.returncode == 2 and "is not an MCAP file" in run.stderr


# -- failures ------------------------------------------------------------------------------------
RECORDS = {"test": {"k": "v"}}


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="no /dev/full")
def test_full_disk_at_open_is_reported():
    with pytest.raises(RecordingError, match=r"cannot record to /dev/full: No space left"):
        McapRecorder("/dev/full", records=RECORDS)


def test_unwritable_path_is_reported(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(RecordingError, match=r"cannot record to .*file/sub/x\.mcap: "):
        McapRecorder(blocker / "sub" / "x.mcap", records=RECORDS)


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="no /dev/full")
def test_disk_full_while_writing_stops_the_recorder_and_keeps_the_chunks(tmp_path, source):
    path = tmp_path / "rec.mcap"
    recorder = McapRecorder(path, records=RECORDS, options=RecordingOptions(durable=False))
    second = 1_000_000_000
    full_from_ns = 3 * second // 2  # after the first chunk ([0, 1 s)) was written
    filled = False
    for topic, msg, ns in source:
        if ns >= full_from_ns and not filled:
            filled = True
            full = os.open("/dev/full", os.O_WRONLY)
            os.dup2(full, recorder._file._fd)  # the disk is full from now on
            os.close(full)
        try:
            recorder.write(topic, msg, ns)
        except RecordingError as exc:
            assert "No space left on device" in str(exc)
            assert f"recording to {path} stopped after" in str(exc)
            break
    else:
        pytest.fail("writing to a full disk did not fail")
    recorder.close()  # after a failure: closes quietly
    with pytest.raises(RecordingError, match="closed"):
        recorder.write(*source[0])
    result = recover(path, tmp_path / "fixed.mcap")
    # the first second was written before the disk filled; the open chunk is lost
    assert result.messages == sum(ns < second for _t, _m, ns in source)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"compression": "lz5"}, "compression 'lz5': allowed zstd, none"),
        ({"flush_interval_s": 0.0}, "flush interval 0.0 s: allowed a finite time > 0 s"),
        ({"flush_interval_s": float("nan")}, "flush interval nan s"),
        ({"chunk_size_bytes": 10}, "chunk size 10 bytes: allowed at least 1024 bytes"),
    ],
)
def test_bad_options_are_refused(options, message):
    with pytest.raises(RecordingError, match=message):
        RecordingOptions(**options)


def test_diagnostics_and_commands_round_trip(tmp_path):
    """The live-only topics: DiagnosticArray (a ``byte`` field) and ActuationCommand."""
    from brake_sim_msgs.msg import ActuationCommand
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

    status = [
        DiagnosticStatus(
            level=bytes([level]), name="brake_sim", message=f"level {level}", hardware_id="b",
            values=[KeyValue(key="k", value=str(level))],
        )
        for level in range(4)
    ]  # fmt: skip
    messages = [
        (stream.DIAGNOSTICS, DiagnosticArray(status=status), 5),
        (stream.ACTUATION, ActuationCommand(left_force_n=123.25, right_force_n=-0.0), 7),
    ]
    path = tmp_path / "live_topics.mcap"
    with McapRecorder(path, records=RECORDS) as recorder:
        for topic, msg, ns in messages:
            recorder.write(topic, msg, ns)
    with path.open("rb") as f:
        payloads = [m.data for _s, _c, m in make_reader(f).iter_messages(log_time_order=False)]
    for data, (_topic, msg, _ns) in zip(payloads, messages, strict=True):
        assert deserialize_message(data, type(msg)) == msg
    _connections, decoded = _rosbags_messages(path)
    levels = [s.level for s in decoded[0][3].status]
    assert levels == [0, 1, 2, 3]
    assert [kv.value for s in decoded[0][3].status for kv in s.values] == ["0", "1", "2", "3"]
    command = decoded[1][3]
    assert (command.left_force_n, command.right_force_n) == (123.25, -0.0)


def test_record_offline_feeds_other_sinks_the_same_stream(tmp_path: Path):
    """``also=`` sinks (Rerun in ``simulate --mcap --rerun``) get exactly what is recorded,
    from the same single simulation."""

    class Collect:
        def __init__(self) -> None:
            self.seen: list[tuple[str, int]] = []

        def write(self, topic, msg, time_ns: int) -> None:
            self.seen.append((topic.name, time_ns))

        def close(self) -> None:
            pass

    sink = Collect()
    path = tmp_path / "both.mcap"
    record_offline(load_scenario("symmetric"), path, duration_s=0.3, also=[sink])
    with path.open("rb") as f:
        recorded = [
            (c.topic, m.log_time) for _s, c, m in make_reader(f).iter_messages(log_time_order=False)
        ]
    assert sink.seen == recorded


def test_measured_channels_are_recorded_and_read_back_checked(tmp_path: Path):
    """With publish_measured the MCAP holds ~/measured; the project's checked reader
    accepts its payloads and decodes them to what the stream sent, value for value."""
    from brake_sim_ros.recording import cdr
    from brake_sim_ros.recording.reader import open_recording
    from brake_sim_ros.stream.offline import StreamSettings

    scenario = load_scenario("symmetric")
    settings = StreamSettings(publish_measured=True)
    path = tmp_path / "measured.mcap"
    record_offline(scenario, path, duration_s=0.2, settings=settings, run_id=RUN_ID)
    sent = [
        m
        for t, m, _ns in offline_messages(
            scenario, duration_s=0.2, settings=settings, run_id=RUN_ID
        )
        if t is stream.MEASURED
    ]
    recording = open_recording(path)
    decode = cdr.decoder(stream.MEASURED.type_name)
    got = [decode(m.data) for m in recording.messages(topics=[stream.MEASURED.name])]
    assert len(got) == len(sent) == 2  # a chunk per 100 ms (measured_rate_hz)
    for a, b in zip(got, sent, strict=True):
        assert list(a.channel_names) == list(b.channel_names)
        assert list(a.units) == list(b.units)
        np.testing.assert_array_equal(np.asarray(a.values), np.asarray(b.values))
        assert bytes(a.fault_labels) == bytes(b.fault_labels)
        assert list(a.decimation) == list(b.decimation)
        assert a.first_sample_index == b.first_sample_index


def test_tone_ring_edges_are_recovered_from_a_recording_by_rosbags(tmp_path: Path):
    """~/measured in an MCAP, read back by rosbags alone (its parser, its CDR decoder, the
    file's own schema): the chunks' edge times, joined, are the run's edges, bit for bit,
    and give the drum speed the run had."""
    from brake_sim_ros.stream.build import sensor_bank_for
    from brake_sim_ros.stream.offline import StreamSettings
    from brake_sim_ros.stream.run import run_scenario

    scenario = load_scenario("symmetric")
    path = tmp_path / "edges.mcap"
    settings = StreamSettings(publish_measured=True)
    record_offline(scenario, path, duration_s=0.4, settings=settings, run_id=RUN_ID)
    _connections, decoded = _rosbags_messages(path)
    chunks = [m for topic, _type, _ns, m in decoded if topic == stream.MEASURED.name]
    assert len(chunks) == 4  # a chunk per 100 ms (measured_rate_hz)
    edges = conversion.measured_edges(chunks)
    run = run_scenario(scenario, duration_s=0.4)
    expected = sensor_bank_for(scenario).advance(run.samples).edges_s
    assert edges.keys() == expected.keys() == {"wheel_speed"}
    assert edges["wheel_speed"].size > 100
    assert edges["wheel_speed"].tobytes() == expected["wheel_speed"].tobytes()
    teeth = int(chunks[0].tone_ring_teeth[0])
    speed = (2 * np.pi / teeth) / np.diff(edges["wheel_speed"])
    middle = 0.5 * (edges["wheel_speed"][1:] + edges["wheel_speed"][:-1])
    true = np.interp(middle, run.samples.time_s, run.samples["drum_speed_rad_s"])
    assert np.max(np.abs(speed / true - 1)) < 0.02


def test_the_defect_ground_truth_round_trips_through_an_independent_reader(recording, scenario):
    """rosbags alone decodes the DefectState list (a nested message sequence) of the
    recording: the scenario's defects, catalogue kinds and units, run id and seed; every
    sample of the run lies after it, so each is labelled with it."""
    _, decoded = _rosbags_messages(recording)
    truths = [(ns, m) for topic, _, ns, m in decoded if topic == stream.DEFECTS.name]
    assert len(truths) == 1
    ns, truth = truths[0]
    assert ns == 0 and truth.run_id == RUN_ID and truth.seed == scenario.seed
    assert truth.scenario == SCENARIO and not truth.healthy and truth.unit_id == "nominal"
    expected = scenario.setup.defects.active()
    assert [
        (d.kind, d.location, d.severity, d.unit, d.onset_s, d.growth) for d in truth.defects
    ] == [(d.kind, d.location, d.severity, d.unit, d.onset_s, d.growth) for d in expected]
    assert {d.kind for d in truth.defects} <= set(catalogue.KIND_BY_NAME)
    assert list(truth.labels) == [d.label for d in expected]
    first_sample = min(ns for topic, _, ns, _ in decoded if topic == stream.PIVOT_FORCES.name)
    assert ns <= first_sample
