"""The sensors follow the fidelity plan: ``measured_signals`` in ``[needs]`` builds them
(the structure with the accelerometers), a ``[needs]`` without it builds none, and every
path that measures (Parquet, the offline stream, the recorder, ``scenarios --channels``)
follows the plan or refuses in one line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from brake_sim_ros import cli
from brake_sim_ros.errors import FidelityError, ScenarioError
from brake_sim_ros.model.fidelity import LEVELS, Needs, levels_serving, plan
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.stream.build import measures, sensor_bank_for
from brake_sim_ros.stream.run import run_scenario

SENSOR_INPUTS = (
    "drum_angle_rad",
    "left_pivot_fx_n",
    "left_pivot_fy_n",
    "right_pivot_fx_n",
    "right_pivot_fy_n",
    "left_actuation_force_n",
    "right_actuation_force_n",
)


def _scenario_text(outputs: list[str] | None, name: str = "needs_test") -> str:
    needs = "" if outputs is None else f"\n[needs]\noutputs = {json.dumps(outputs)}\n"
    return f'name = "{name}"\nduration_s = 0.1\n{needs}'


# --- the planner ------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("outputs", "sensors"),
    [
        (None, True),  # no [needs]: the full model, every signal, sensors included
        (("measured_signals",), True),
        (("impacts", "measured_signals"), True),
        (("impacts",), False),
        (("stop_time", "braking_torque"), False),
        (("energy_balance", "shoe_motion", "torsional_vibration"), False),  # full, no sensors
    ],
)
def test_plan_builds_sensors_only_when_they_are_asked(outputs, sensors):
    chosen = plan(None if outputs is None else Needs(outputs=outputs))
    assert chosen.sensors is sensors
    if outputs is not None and sensors:
        assert chosen.level.name == "full"
        assert set(SENSOR_INPUTS) <= set(chosen.columns)  # what the bank reads is kept
        assert "no sensors" not in chosen.reason
    elif outputs is not None:
        assert "no sensors" in chosen.reason


def test_only_the_full_level_delivers_measured_signals():
    assert levels_serving("measured_signals") == ["full"]
    assert [lv.name for lv in LEVELS if "measured_signals" in lv.outputs] == ["full"]


@pytest.mark.parametrize("level", ["contact_regime_rigid", "contact_regime", "rigid"])
def test_a_forced_level_without_sensors_is_refused_in_one_line(level):
    with pytest.raises(FidelityError) as exc:
        plan(Needs(outputs=("contact_regime_forces", "measured_signals"), level=level))
    msg = str(exc.value)
    assert "\n" not in msg and f"level {level!r}" in msg
    assert "'measured_signals'" in msg and "['full']" in msg
    assert plan(Needs(outputs=("measured_signals",), level="full")).sensors


def test_measured_signals_keep_both_shoes_in_the_model():
    """The structure sums both pivot forces: asking one shoe's signals with measured
    signals never gives a one-shoe model, and both shoes' sensor inputs are kept."""
    chosen = plan(Needs(outputs=("impacts", "measured_signals"), shoes=("left",)))
    assert chosen.shoes == ("left", "right") and chosen.sensors
    assert set(SENSOR_INPUTS) <= set(chosen.columns)


def test_a_scenario_file_refuses_measured_signals_at_a_level_that_cannot():
    text = _scenario_text(["measured_signals"]) + 'level = "rigid"\n'
    with pytest.raises(ScenarioError) as exc:
        parse_scenario(text, source="forced.toml")
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith("forced.toml: needs level 'rigid'")
    assert "'measured_signals'" in msg and "['full']" in msg


# --- the paths that measure ------------------------------------------------------------


def test_sensor_bank_follows_the_plan():
    without = parse_scenario(_scenario_text(["impacts"]), source="n.toml")
    assert not measures(without) and sensor_bank_for(without) is None
    asked = parse_scenario(_scenario_text(["impacts", "measured_signals"]), source="m.toml")
    bank = sensor_bank_for(asked)
    assert bank is not None and bank.structure is not None  # accelerometers: the structure
    assert sensor_bank_for(load_scenario("symmetric")) is not None  # no [needs]


def _simulate_parquet(tmp_path, outputs: list[str] | None, name: str):
    pq = pytest.importorskip("pyarrow.parquet")
    source = tmp_path / f"{name}.toml"
    source.write_text(_scenario_text(outputs, name="needs_test"))
    out = tmp_path / f"{name}.parquet"
    assert cli.main(["simulate", str(source), "--out", str(out), "--quiet"]) == 0
    return pq.read_table(out)


def test_simulate_parquet_has_measured_columns_only_when_the_plan_measures(tmp_path):
    """Needs without measured_signals: no measured or fault column, the metadata says so.
    With it: the same measured bits as the scenario without [needs] (same model, seed)."""
    lean = _simulate_parquet(tmp_path, ["impacts"], "lean")
    assert not [c for c in lean.column_names if c.startswith(("measured:", "fault:"))]
    meta = json.loads(lean.schema.metadata[b"brake_sim"])
    assert meta["sensors"] is False and meta["fidelity_level"] == "rigid"
    assert lean.num_rows == round(0.1 * 25_600)

    asked = _simulate_parquet(tmp_path, ["impacts", "measured_signals"], "asked")
    every = _simulate_parquet(tmp_path, None, "every")
    measured = [c for c in every.column_names if c.startswith("measured:")]
    assert measured and [c for c in asked.column_names if c.startswith("measured:")] == measured
    assert json.loads(asked.schema.metadata[b"brake_sim"])["sensors"] is True
    for name in measured:
        assert np.array_equal(
            asked[name].to_numpy(zero_copy_only=False),
            every[name].to_numpy(zero_copy_only=False),
            equal_nan=True,
        ), name
    assert len(asked.column_names) < len(every.column_names)  # the plan keeps fewer columns


def test_scenarios_channels_says_why_a_plan_has_none(tmp_path, capsys):
    source = tmp_path / "lean.toml"
    source.write_text(_scenario_text(["stop_time"]))
    assert cli.main(["scenarios", "--channels", str(source)]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1 and "no measured channels" in out[0] and "measured_signals" in out[0]


def test_publish_measured_on_a_scenario_without_sensors_is_refused(tmp_path):
    pytest.importorskip("brake_sim_msgs", reason="ROS interfaces not built")
    from brake_sim_ros.recording.record import record_offline
    from brake_sim_ros.stream.offline import StreamSettings, offline_messages

    scenario = parse_scenario(_scenario_text(["impacts"]), source="n.toml")
    on = StreamSettings(publish_measured=True)
    with pytest.raises(FidelityError) as exc:
        next(iter(offline_messages(scenario, settings=on)))
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith("publish_measured: ") and "measured_signals" in msg
    out = tmp_path / "run.mcap"
    with pytest.raises(FidelityError, match="measured_signals"):
        record_offline(scenario, out, settings=on)
    assert not out.exists()  # refused before the file is opened
    # publish_measured off: the stream runs, with no ~/measured
    from brake_sim_ros import stream

    topics = {topic for topic, _msg, _ns in offline_messages(scenario, duration_s=0.02)}
    assert stream.PIVOT_FORCES in topics and stream.MEASURED not in topics


def test_run_scenario_keeps_what_the_sensors_read():
    """A plan with sensors keeps their inputs, so the bank can measure its samples."""
    scenario = parse_scenario(_scenario_text(["impacts", "measured_signals"]), source="m.toml")
    run = run_scenario(scenario, duration_s=0.02)
    assert run.samples.has(*SENSOR_INPUTS)
    bank = sensor_bank_for(scenario)
    assert bank is not None
    frame = bank.advance(run.samples)
    assert "backing_plate_accel_x" in frame.series


def test_bench_sensors_says_which_plan_it_measured(tmp_path, capsys):
    from brake_sim_ros.studies.sensors_bench import cost

    lean = tmp_path / "lean.toml"
    lean.write_text(_scenario_text(["pivot_forces"]))
    cost(str(lean), 0.02, 256, 1)
    out = capsys.readouterr().out
    assert "fidelity plan: level full, sensors off" in out and "no structure" in out
    asked = tmp_path / "asked.toml"
    asked.write_text(_scenario_text(["pivot_forces", "measured_signals"]))
    cost(str(asked), 0.02, 256, 1)
    out = capsys.readouterr().out
    assert "sensors on" in out and "physics with the sensors streamed" in out
