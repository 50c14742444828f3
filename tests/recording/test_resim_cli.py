"""``brake-sim resim``: a recording re-simulated offline from its own metadata, as a user
runs it (real processes, real files, read back by the independent ``mcap`` reader), and
the hostile inputs it refuses in one line without writing anything.

The live recording with commands, re-simulated bit for bit, is in
tests/ros/test_resim_node.py (a real node over DDS).
"""

from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.writer import Writer
from mcap_ros2.decoder import DecoderFactory

from brake_sim_ros import stream
from brake_sim_ros.recording import metadata
from brake_sim_ros.recording.record import record_offline
from brake_sim_ros.recording.writer import McapRecorder
from brake_sim_ros.scenarios import load_scenario, parse_scenario
from brake_sim_ros.stream import conversion
from brake_sim_ros.stream.offline import offline_messages
from tests import cli_process
from tests.stream.test_drive_command import RIG

SECONDS = 0.25


def resim(*args):
    """``brake-sim resim ARGS`` in a process of its own (str() of each argument)."""
    return cli_process.run(
        [sys.executable, "-m", "brake_sim_ros.cli", "resim", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=600,
    )


def pivot_arrays(path: Path) -> dict[str, np.ndarray]:
    """Every recorded pivot-force sample by column, and the sample index, read by ``mcap``
    with the decoder built from the file's own schemas."""
    chunks = []
    with path.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _s, _c, _m, msg in reader.iter_decoded_messages(topics=[stream.PIVOT_FORCES.name]):
            chunks.append(msg)
    out = {
        name: np.concatenate([np.asarray(getattr(c, name), dtype=float) for c in chunks])
        for name in conversion.PIVOT_CHUNK_ARRAYS
    }
    out["index"] = np.concatenate(
        [c.first_sample_index + np.arange(len(c.left_fx_n)) for c in chunks]
    )
    return out


def run_record(path: Path) -> dict[str, str]:
    with path.open("rb") as f:
        return {m.name: m.metadata for m in make_reader(f).iter_metadata()}["brake_sim_run"]


@pytest.fixture(scope="module")
def recorded(tmp_path_factory) -> Path:
    """An offline recording of the published stop's first quarter second (impacts)."""
    path = tmp_path_factory.mktemp("resim") / "stop.mcap"
    record_offline(load_scenario("symmetric"), path, duration_s=SECONDS)
    return path


@pytest.mark.slow
def test_an_offline_recording_resimulates_to_the_same_bits(recorded, tmp_path):
    out = tmp_path / "again.mcap"
    r = resim(recorded, "--out", out)
    assert r.returncode == 0, r.stderr
    n = round(SECONDS * 25_600)
    assert f"{n} samples equal to the recording's, bit for bit" in r.stdout
    a, b = pivot_arrays(recorded), pivot_arrays(out)
    np.testing.assert_array_equal(a["index"], np.arange(n))
    assert np.abs(a["left_fx_n"]).max() > 100.0  # the shoes are on the drum
    for name, values in a.items():
        assert values.tobytes() == b[name].tobytes(), name
    run = run_record(out)
    assert run["mode"] == "resim" and run["recorded_mode"] == "offline"
    assert run["run_id"] == run_record(recorded)["run_id"]


@pytest.mark.slow
def test_a_resimulation_resimulates_again_as_the_run_it_came_from(tmp_path):
    """An offline run whose defect grows (from 0.05 s), re-simulated, then re-simulated
    again: each time bit for bit (the second from the first's file alone, which says the
    run was offline: the scenario's own setup, growth and all)."""
    growing = (
        'name = "growing"\nduration_s = 1.0\n[defects.left]\n'
        'pivot_radius_change_pct = {value = 4.0, onset_s = 0.05, growth = "linear",'
        " rate_per_s = 40.0}\n"
    )
    first = tmp_path / "grown.mcap"
    record_offline(parse_scenario(growing, "growing.toml"), first, duration_s=0.2)
    again, twice = tmp_path / "again.mcap", tmp_path / "twice.mcap"
    for source, out in ((first, again), (again, twice)):
        r = resim(source, "--out", out)
        assert r.returncode == 0 and "5120 samples equal" in r.stdout, r.stdout + r.stderr
    assert run_record(twice)["recorded_mode"] == "offline"
    assert pivot_arrays(twice)["left_fx_n"].tobytes() == pivot_arrays(first)["left_fx_n"].tobytes()


@pytest.mark.slow
def test_a_recording_holds_the_live_drives_settings(tmp_path):
    """A run that takes live drive commands records the settings in force (brake_sim_run)
    and its re-simulation keeps them."""
    text = RIG.replace("[vehicle]\n", "[vehicle]\nmax_drive_torque_n_m = 90.0\n")
    path = tmp_path / "rig.mcap"
    record_offline(parse_scenario(text, "rig.toml"), path, duration_s=0.1)
    run = run_record(path)
    assert (run["max_drive_torque_n_m"], run["speed_time_constant_s"]) == ("90.0", "1.0")
    out = tmp_path / "again.mcap"
    r = resim(path, "--out", out)
    assert r.returncode == 0, r.stderr
    assert run_record(out)["max_drive_torque_n_m"] == "90.0"
    assert "max_drive_torque_n_m" not in run_record(recorded_symmetric(tmp_path))


def recorded_symmetric(folder: Path) -> Path:
    path = folder / "symmetric.mcap"
    record_offline(load_scenario("symmetric"), path, duration_s=0.01)
    return path


@pytest.mark.slow
def test_another_preset_resimulates_and_says_the_samples_differ(recorded, tmp_path):
    """The same recording under another preset (another physics step): written, and the
    comparison names the first sample that differs instead of claiming equality."""
    out = tmp_path / "fine.mcap"
    r = resim(recorded, "--out", out, "--preset", "accurate")
    assert r.returncode == 0, r.stderr
    assert "samples differ from the recording's from sample" in r.stdout
    assert run_record(recorded)["preset"] != "accurate" == run_record(out)["preset"]


def test_sensors_added_later_measure_the_same_samples(recorded, tmp_path):
    """--measured: the recording had no ~/measured; the re-simulation runs the scenario's
    sensors on the same samples (the pivot forces still equal, bit for bit)."""
    out = tmp_path / "measured.mcap"
    r = resim(recorded, "--out", out, "--measured")
    assert r.returncode == 0, r.stderr
    assert "bit for bit" in r.stdout
    with out.open("rb") as f:
        topics = {c.topic for _s, c, _m in make_reader(f).iter_messages()}
    with recorded.open("rb") as f:
        before = {c.topic for _s, c, _m in make_reader(f).iter_messages()}
    assert stream.MEASURED.name in topics - before
    assert run_record(out)["publish_measured"] == "True"


def test_a_recording_of_two_runs_is_refused(tmp_path):
    """Two runs in one file (as a ~/reset leaves it: sample indices and times start again
    under a new run id): refused in one line, nothing written."""
    scenario = load_scenario("symmetric")
    first = tmp_path / "first.mcap"
    record_offline(scenario, first, duration_s=0.01, run_id="first")
    with first.open("rb") as f:
        records = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
    del records["rosbag2"]
    both = tmp_path / "both.mcap"
    recorder = McapRecorder(both, records=records)
    for run_id in ("first", "second"):
        for topic, msg, ns in offline_messages(scenario, duration_s=0.01, run_id=run_id):
            recorder.write(topic, msg, ns)
    recorder.close()
    out = tmp_path / "out.mcap"
    _refused(resim(both, "--out", out), out, "(a ~/reset")


@pytest.mark.parametrize(
    ("change", "says"),
    [
        ({"run_id": "other"}, "parameter 'run_id' set at sample 64: not re-simulated"),
        ({"command_timeout_s": "soon"}, "at sample 64: command_timeout_s="),
    ],
)
def test_a_parameter_change_it_cannot_resimulate_is_refused(tmp_path, change, says):
    """A recorded change of a parameter resim does not re-simulate, or of a value the
    node's own checks refuse: one line, nothing written (the run stops there)."""
    scenario = load_scenario("symmetric")
    source = tmp_path / "source.mcap"
    record_offline(scenario, source, duration_s=0.01)
    with source.open("rb") as f:
        records = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
    del records["rosbag2"]
    changed = tmp_path / "changed.mcap"
    recorder = McapRecorder(changed, records=records)
    recorder.parameter_change(change, 64, 0)
    for topic, msg, ns in offline_messages(
        scenario, duration_s=0.01, run_id=records["brake_sim_run"]["run_id"]
    ):
        recorder.write(topic, msg, ns)
    recorder.close()
    out = tmp_path / "out.mcap"
    _refused(resim(changed, "--out", out), out, says)


def _refused(r, out: Path, says: str) -> None:
    assert r.returncode != 0
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and says in lines[0], r.stderr
    assert "Traceback" not in r.stderr
    assert not out.exists() and not out.is_symlink()
    assert not [p for p in out.parent.iterdir() if ".partial" in p.name]


def test_a_missing_file_is_refused_in_one_line(tmp_path):
    out = tmp_path / "out.mcap"
    _refused(resim(tmp_path / "missing.mcap", "--out", out), out, "missing.mcap")


def test_a_file_that_is_not_mcap_is_refused_in_one_line(tmp_path):
    notes = tmp_path / "notes.mcap"
    notes.write_text("not a recording\n")
    out = tmp_path / "out.mcap"
    _refused(resim(notes, "--out", out), out, "notes.mcap is not an MCAP file")


def test_a_damaged_recording_is_refused_in_one_line(recorded, tmp_path):
    """Cut short (a crash): the checked reader refuses it whole and points to recover."""
    data = recorded.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    out = tmp_path / "out.mcap"
    _refused(resim(cut, "--out", out), out, "brake-sim recover")


def test_an_mcap_without_the_simulators_metadata_is_refused_in_one_line(tmp_path):
    foreign = tmp_path / "foreign.mcap"
    with foreign.open("wb") as f:
        writer = Writer(f)
        writer.start(profile="ros2", library="someone else")
        writer.add_metadata("notes", {"what": "a foreign file"})
        writer.finish()
    out = tmp_path / "out.mcap"
    _refused(resim(foreign, "--out", out), out, "no brake_sim_scenario, brake_sim_unit,")


@pytest.mark.slow
def test_the_input_as_output_is_refused_and_left_as_it_was(recorded):
    before = hashlib.sha256(recorded.read_bytes()).hexdigest()
    for extra in ((), ("--overwrite",)):
        r = resim(recorded, "--out", recorded, *extra)
        assert r.returncode != 0 and len(r.stderr.strip().splitlines()) == 1
        assert "is the input" in r.stderr, r.stderr
    assert hashlib.sha256(recorded.read_bytes()).hexdigest() == before


@pytest.mark.slow
def test_an_output_through_a_symlink_is_refused(recorded, tmp_path):
    target = tmp_path / "elsewhere.mcap"
    link = tmp_path / "link.mcap"
    link.symlink_to(target)
    r = resim(recorded, "--out", link, "--overwrite")
    assert r.returncode != 0 and "symbolic link" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert not target.exists() and os.readlink(link) == str(target)


def test_an_existing_output_needs_overwrite(recorded, tmp_path):
    out = tmp_path / "taken.mcap"
    out.write_bytes(b"mine")
    r = resim(recorded, "--out", out)
    assert r.returncode != 0 and "pass --overwrite" in r.stderr
    assert out.read_bytes() == b"mine"


@pytest.mark.slow
@pytest.mark.parametrize(
    ("options", "samples"),
    [(("--sample-rate", "5120"), 256), (("--preset", "accurate", "--max-step", "1e-5"), 1280)],
)
def test_a_run_made_with_solver_options_resimulates_with_them(tmp_path, options, samples):
    """``simulate --sample-rate`` / ``--preset`` / ``--max-step`` change the run over its
    scenario's text: the recording says so, and re-simulation runs with them (it refused
    the other sample rate, and re-ran another preset with the text's)."""
    first, again = tmp_path / "first.mcap", tmp_path / "again.mcap"
    made = cli_process.run(
        [sys.executable, "-m", "brake_sim_ros.cli", "simulate", "symmetric", "--duration",
         "0.05", "--quiet", "--mcap", str(first), *options],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert made.returncode == 0, made.stderr
    r = resim(first, "--out", again)
    assert r.returncode == 0, r.stderr
    assert f"{samples} samples equal to the recording's, bit for bit" in r.stdout
    assert pivot_arrays(again)["left_fx_n"].tobytes() == pivot_arrays(first)["left_fx_n"].tobytes()


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("{", "not JSON"),
        ('{"preset": "fast"}', "allowed the keys"),
        ('[1, 2]', "allowed the keys"),
        ('{"preset": "fast", "method": "rk4", "max_step_s": true, "sample_rate_hz": 1}',
         "max_step_s: allowed a float"),
        ('{"preset": "warp", "method": "rk4", "max_step_s": 1e-5, "sample_rate_hz": 1e3}',
         "preset 'warp'"),
        ('{"preset": "fast", "method": "rk4", "max_step_s": 1e-5, "sample_rate_hz": 1e12}',
         "sample rate"),
    ],
)  # fmt: skip
def test_a_hostile_recorded_solver_is_one_line(text, says):
    from brake_sim_ros.app.resim import ResimError, _recorded_solver

    with pytest.raises(ResimError, match=says) as caught:
        _recorded_solver(load_scenario("symmetric"), text, "x.mcap")
    assert "\n" not in str(caught.value) and str(caught.value).startswith("x.mcap: ")


# a service brake with its own parameters from the file, braking from the first sample
SERVICE_TEXT = (
    'name = "service_stop"\nbrake = "service"\nroad_friction = 0.5\n'
    "[actuation]\npeak_force_n = 3000.0\nstart_s = 0.001\nfull_s = 0.05\n"
    "[parameters.service]\nreturn_spring_preload_n = 80.0\nline_compliance_m3_per_pa = 1.2e-12\n"
    "[parameters.service.tyre]\npresliding_stiffness_per_m = 50.0\n"
)
SERVICE_SECONDS = 0.08
ROAD_CHANGE_AT = 768  # sample 0.03 s in: the road turns to ice under the braking wheel


@pytest.mark.slow
def test_a_service_brake_recording_resimulates_to_the_same_bits(tmp_path):
    """The service brake's parameters from the file are in the model record (rebuilt to
    the scenario's), and a recorded change of the road under it (a node parameter) is
    re-simulated at its sample, bit for bit; without the change the samples after it
    differ, so the change is what the re-simulation reproduced."""
    scenario = parse_scenario(SERVICE_TEXT, "service_stop.toml")
    source, plain = tmp_path / "source.mcap", tmp_path / "plain.mcap"
    change = {"service.tyre.road_friction": 0.1}
    record_offline(scenario, source, duration_s=SERVICE_SECONDS, changes=[(ROAD_CHANGE_AT, change)])
    record_offline(scenario, plain, duration_s=SERVICE_SECONDS)
    with source.open("rb") as f:
        records = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
    params, _defects = metadata.model_from_record(records[metadata.MODEL])
    assert params == scenario.setup.params and params.service.return_spring_preload_n == 80.0
    out = tmp_path / "again.mcap"
    r = resim(source, "--out", out)
    assert r.returncode == 0, r.stderr
    n = round(SERVICE_SECONDS * 25_600)
    assert f"{n} samples equal to the recording's, bit for bit" in r.stdout
    a, b, c = pivot_arrays(source), pivot_arrays(out), pivot_arrays(plain)
    assert np.abs(a["left_fx_n"]).max() > 100.0  # the shoes are on the drum
    for name, values in a.items():
        assert values.tobytes() == b[name].tobytes(), name
    before, after = slice(0, ROAD_CHANGE_AT), slice(ROAD_CHANGE_AT + 1, None)
    assert a["left_fx_n"][before].tobytes() == c["left_fx_n"][before].tobytes()
    assert np.any(a["left_fx_n"][after] != c["left_fx_n"][after])
