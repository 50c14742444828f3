"""The run-parameter table (``stream/run_parameters.py``) is the one place a run parameter
is declared: every entry reaches the recording's metadata and re-simulation, a change of
every entry that may change re-simulates to the same bytes, and a change of one fixed at
start is refused in one line. A parameter added to the table in a test reaches them all
with no edit elsewhere (the node's declared parameters: tests/ros/test_run_session_node.py).

Real files: each run is recorded offline to MCAP (the session with the change applied at
its sample, recorded as a node records it), re-simulated by :func:`resimulate`, and both
files are read back by the independent ``mcap`` reader.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from mcap.reader import make_reader

from brake_sim_ros.app.resim import ResimError, resimulate
from brake_sim_ros.recording.record import record_offline
from brake_sim_ros.recording.writer import McapRecorder
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.stream import run_parameters
from brake_sim_ros.stream.offline import offline_messages
from brake_sim_ros.stream.run_parameters import Affects, Change, RunParameter

SECONDS = 0.02  # 512 samples of the published stop
AT = 64  # the sample a change takes effect at (inside the first chunk of 256)
# a valid other value for the text parameters that may change (the rest are derived)
_OTHER_TEXT = {"on_command_timeout": "ramp_to_zero"}


def _other(p: RunParameter):
    """A valid value of ``p`` other than its default."""
    if isinstance(p.default, bool):
        return not p.default
    if isinstance(p.default, float):
        lo, hi = p.range
        value = 2.0 * p.default if p.default else 0.5 * (lo + hi)
        assert lo <= value <= hi, p.name
        return value
    if p.changes is Change.AT_START:
        return "x"
    assert p.name in _OTHER_TEXT, f"{p.name}: give this test a valid other value"
    return _OTHER_TEXT[p.name]


def _metadata(path: Path) -> dict[str, dict[str, str]]:
    with path.open("rb") as f:
        return {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}


def _messages(path: Path) -> list[tuple[str, int, bytes]]:
    with path.open("rb") as f:
        return [(c.topic, m.log_time, m.data) for _s, c, m in make_reader(f).iter_messages()]


@pytest.fixture(scope="module")
def scenario():
    return load_scenario("symmetric")


def test_every_entry_is_complete():
    """Name, default of a ROS type, a description with its unit or values, a range for
    every number (the node's descriptor and resim's check), when it changes, what it
    affects; names unique."""
    names = [p.name for p in run_parameters.RUN_PARAMETERS]
    assert len(names) == len(set(names))
    for p in run_parameters.RUN_PARAMETERS:
        assert type(p.default) in (float, int, bool, str), p.name
        assert p.description.strip(), p.name
        assert (p.range is not None) == (type(p.default) in (float, int)), p.name
        assert isinstance(p.changes, Change) and isinstance(p.affects, Affects), p.name
        fixed = "Fixed at start-up" in p.description
        assert fixed == (p.changes is Change.AT_START), p.name


@pytest.mark.parametrize("name", [p.name for p in run_parameters.RUN_PARAMETERS])
def test_a_change_of_every_entry_resimulates_or_is_refused_in_one_line(scenario, tmp_path, name):
    """A recording whose parameter ``name`` changes at sample 64: re-simulated to the same
    messages, byte for byte (every topic, every log time), with the run record carrying
    the value at the start; or, for a parameter fixed at start (which a node refuses to
    change), refused in one line naming it, nothing written."""
    p = run_parameters.by_name()[name]
    source, out = tmp_path / "source.mcap", tmp_path / "out.mcap"
    change = {name: _other(p)}
    if p.changes is Change.AT_START:
        record_offline(scenario, source, duration_s=SECONDS, run_id="fixed")
        records = _metadata(source)
        del records["rosbag2"]
        with_change = tmp_path / "with_change.mcap"
        recorder = McapRecorder(with_change, records=records)
        recorder.parameter_change(change, AT, 0)
        for topic, msg, ns in offline_messages(scenario, duration_s=SECONDS, run_id="fixed"):
            recorder.write(topic, msg, ns)
        recorder.close()
        with pytest.raises(ResimError) as refused:
            resimulate(with_change, out)
        message = str(refused.value)
        assert f"parameter {name!r} set at sample {AT}: not re-simulated" in message
        assert "fixed at start-up" in message and "\n" not in message
        assert not out.exists()
        return
    record_offline(scenario, source, duration_s=SECONDS, changes=[(AT, change)])
    recorded = _metadata(source)
    assert recorded["brake_sim_parameter_change"][name] == repr(change[name])
    if run_parameters.recorded(p):
        assert name in recorded["brake_sim_run"]
    result = resimulate(source, out)
    assert result.comparison.first_difference is None
    assert _messages(out) == _messages(source)
    again = _metadata(out)
    assert again["brake_sim_parameter_change"] == recorded["brake_sim_parameter_change"]
    if run_parameters.recorded(p):
        assert again["brake_sim_run"][name] == recorded["brake_sim_run"][name]


def test_a_change_of_the_stream_changes_the_messages(scenario, tmp_path):
    """The check above can fail: a recorded change of publish_clock and state_rate_hz
    changes what the run publishes after its sample (so resim had to apply it)."""
    plain, changed = tmp_path / "plain.mcap", tmp_path / "changed.mcap"
    record_offline(scenario, plain, duration_s=SECONDS, run_id="same")
    change = {"publish_clock": False, "state_rate_hz": 400.0}
    record_offline(scenario, changed, duration_s=SECONDS, run_id="same", changes=[(AT, change)])
    counts = [
        {t: sum(1 for m in _messages(path) if m[0] == t) for t in ("/clock", "/brake_sim/state")}
        for path in (plain, changed)
    ]
    assert counts[1]["/clock"] < counts[0]["/clock"]
    assert counts[1]["/brake_sim/state"] > counts[0]["/brake_sim/state"]


def test_a_parameter_added_to_the_table_reaches_the_recording_and_resim(
    scenario, tmp_path, monkeypatch
):
    """A new entry, declared in the table only: its value at the start is in the run
    record, a recorded change of it re-simulates, and resim reads its start value back
    (the run record's, not the default)."""
    knob = RunParameter("test_knob_hz", 7.0, "A knob only this test declares (Hz).", (0.0, 50.0))
    monkeypatch.setattr(run_parameters, "RUN_PARAMETERS", (*run_parameters.RUN_PARAMETERS, knob))
    source, out = tmp_path / "source.mcap", tmp_path / "out.mcap"
    record_offline(scenario, source, duration_s=SECONDS, changes=[(AT, {"test_knob_hz": 11.0})])
    recorded = _metadata(source)
    assert recorded["brake_sim_run"]["test_knob_hz"] == "7.0"
    assert recorded["brake_sim_parameter_change"]["test_knob_hz"] == "11.0"
    result = resimulate(source, out)
    assert result.comparison.first_difference is None
    assert _metadata(out)["brake_sim_run"]["test_knob_hz"] == "7.0"
    start = run_parameters.start_values({"test_knob_hz": 3.0}, None, "rec")
    assert start["test_knob_hz"] == 3.0 and start["chunk_rate_hz"] == 100.0


def test_a_recorded_value_out_of_the_tables_range_is_refused(tmp_path):
    with pytest.raises(ValueError, match=r"rec run record: state_rate_hz=0.0: allowed 1 to"):
        run_parameters.start_values({"state_rate_hz": 0.0}, None, "rec")
    with pytest.raises(ValueError, match=r"publish_clock='yes': allowed a bool"):
        run_parameters.start_values({}, {"publish_clock": "yes"}, "rec")
