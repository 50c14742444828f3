"""Unit-to-unit variability (fleet/scatter.py): draws, distributions, validity, wiring into
scenarios, ground truth and recordings, and the spread it gives a fleet."""

from __future__ import annotations

import itertools
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from brake_sim_ros.errors import ParameterError, ScenarioError
from brake_sim_ros.fleet import scatter
from brake_sim_ros.model.assembly import pack
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.scenarios import builtin_names, load_scenario, parse_scenario
from brake_sim_ros.sensing.sensors import default_sensor_set
from brake_sim_ros.studies import units as fleet_study
from tests import cli_process

ROOT = Path(__file__).resolve().parents[2]
SENSORS = default_sensor_set()


def _bits(unit_id: str, seed: int) -> list[str]:
    """Every drawn value of a unit, as exact hex floats."""
    p = scatter.unit_parameters(BrakeParameters(), unit_id, seed)
    s = scatter.unit_sensors(SENSORS, unit_id, seed)
    return [v.value.hex() for v in scatter.unit_values(BrakeParameters(), p, SENSORS, s)]


def test_same_unit_and_seed_give_identical_bits_in_another_process():
    here = _bits("VIN-0042", 7)
    assert here == _bits("VIN-0042", 7)
    code = (
        "from tests.fleet.test_units import _bits; import json;"
        " print(json.dumps(_bits('VIN-0042', 7)))"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONHASHSEED": "12345"}
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, env=env, timeout=120
    )
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout) == here


def test_the_fleet_seed_and_the_unit_id_each_change_the_draw():
    base = scatter.deviations("VIN-0042", 7)
    assert scatter.deviations("VIN-0042", 8) != base
    assert scatter.deviations("VIN-0043", 7) != base


def test_nominal_is_the_scenarios_brake_bit_for_bit():
    params = BrakeParameters()
    assert scatter.unit_parameters(params, scatter.NOMINAL_UNIT, 5) is params
    assert scatter.unit_sensors(SENSORS, scatter.NOMINAL_UNIT, 5) is SENSORS
    assert set(scatter.deviations(scatter.NOMINAL_UNIT, 5).values()) == {0.0}
    for name in builtin_names():  # every shipped scenario is unit "nominal"
        scenario = load_scenario(name)
        assert scenario.unit_id == scatter.NOMINAL_UNIT
        assert scenario.setup.params is scenario.drawing_params
        assert scenario.sensors is scenario.drawing_sensors
    symmetric = load_scenario("symmetric")
    assert symmetric.setup.params == params
    np.testing.assert_array_equal(
        pack(symmetric.setup.params, symmetric.setup.defects), pack(params, symmetric.setup.defects)
    )


def test_units_differ_and_stay_within_their_limits_and_valid():
    params = BrakeParameters()
    seen = set()
    for i in range(200):
        unit_id = f"unit-{i}"
        drawn = scatter.deviations(unit_id, 0)
        seen.add(tuple(drawn.values()))
        for s in scatter.SCATTER:
            assert abs(drawn[s.key]) <= s.limit
        unit = scatter.unit_parameters(params, unit_id, 0)
        sensors = scatter.unit_sensors(SENSORS, unit_id, 0)
        for v in scatter.unit_values(params, unit, SENSORS, sensors):
            if v.scatter.mode == "relative":
                assert abs(v.value / v.nominal - 1.0) <= v.scatter.limit * (1 + 1e-12), v.key
            else:
                assert abs(v.change) <= v.scatter.limit * (1 + 1e-9), v.key
            assert v.value != v.nominal, v.key  # every parameter scatters
        pack(unit, load_scenario("symmetric").setup.defects)  # a valid brake
    assert len(seen) == 200


def test_each_deviation_follows_its_truncated_normal():
    """2000 units: every parameter's deviations have the stated distribution (KS test
    against the normal truncated at +-limit), mean and standard deviation within four
    standard errors, and they fill the tolerance (some beyond 2.5 sigma; a uniform or an
    untruncated normal fails one of these)."""
    n = 2000
    ids = [f"fleet-{i}" for i in range(n)]
    draws = {s.key: [] for s in scatter.SCATTER}
    for unit_id in ids:
        for key, d in scatter.deviations(unit_id, 3).items():
            draws[key].append(d)
    for s in scatter.SCATTER:
        d = np.array(draws[s.key])
        c = s.truncation
        assert stats.kstest(d / s.sigma, stats.truncnorm(-c, c).cdf).pvalue > 1e-3, s.key
        assert abs(d.mean()) < 4 * s.std / math.sqrt(n), s.key
        assert abs(d.std(ddof=1) - s.std) < 4 * s.std / math.sqrt(2 * n), s.key
        assert np.abs(d).max() <= s.limit and np.any(np.abs(d) > 2.5 * s.sigma), s.key
    # and independent: no two parameters' deviations correlate beyond chance
    matrix = np.corrcoef(np.array([draws[s.key] for s in scatter.SCATTER]))
    off = matrix[~np.eye(len(scatter.SCATTER), dtype=bool)]
    assert np.abs(off).max() < 4 / math.sqrt(n)


def test_a_parameter_draws_the_same_whatever_else_the_table_holds(monkeypatch):
    before = scatter.deviations("VIN-7", 1)
    extra = scatter.Scatter("shoe.mass_centre_x_m", "absolute", 1e-4, 3e-4, "test")
    monkeypatch.setattr(scatter, "SCATTER", (extra, *reversed(scatter.SCATTER)))
    after = scatter.deviations("VIN-7", 1)
    assert {k: after[k] for k in before} == before


def test_the_corners_of_the_tolerance_box_are_valid_brakes():
    """Truncation keeps every unit valid: the shoe geometry at every corner of its
    tolerances (the parameters the core's geometric checks see) packs, for the defects of
    every shipped scenario, but an inward pin on the study brake. Its shoe has the heel in
    an eye on the pin: a pin 3 % in (cases 2 and 4) leaves the lining's toe end 0.28 mm off
    the drum, which the clearance's and the pin's tolerances can take: that unit with that
    defect would start on the drum, refused in one line naming the clearance."""
    geometry = [s for s in scatter.SCATTER if s.key.startswith("shoe.")]
    scenarios = [load_scenario(name) for name in builtin_names()]
    refused = set()
    for signs in itertools.product((-1.0, 1.0), repeat=len(geometry)):
        drawn = {s.key: sign * s.limit for s, sign in zip(geometry, signs, strict=True)}
        params = scatter.with_deviations(BrakeParameters(), drawn)
        for scenario in scenarios:
            try:
                pack(params, scenario.setup.defects, scenario.setup.options)
            except ParameterError as exc:
                assert "inside the drum" in str(exc) and "running clearance" in str(exc)
                refused.add(scenario.name)
    assert refused <= {"case2_left_pivot_in", "case4_right_pivot_in"}, refused


def test_scatter_applies_around_the_scenarios_own_values():
    text = (
        'name = "mine"\nunit_id = "VIN-9"\nfleet_seed = 4\n[parameters.friction]\n'
        "coefficient = 0.40\n"
    )
    scenario = parse_scenario(text)
    d = scatter.deviations("VIN-9", 4)["friction.coefficient"]
    assert scenario.drawing_params.friction.coefficient == 0.40
    assert scenario.setup.params.friction.coefficient == 0.40 * (1.0 + d)
    back = scenario.with_unit(scatter.NOMINAL_UNIT)
    assert back.setup.params == scenario.drawing_params and back.sensors == SENSORS
    # the same unit from the default file: the same deviation
    plain = parse_scenario('name = "mine"\nunit_id = "VIN-9"\nfleet_seed = 4\n')
    assert plain.setup.params.friction.coefficient == 0.285 * (1.0 + d)
    assert plain.with_unit(fleet_seed=5).setup.params != plain.setup.params
    # the run's seed is its noise: the same unit is the same brake in every run
    again = plain.with_unit(seed=5)
    assert again.setup.params == plain.setup.params and again.sensors == plain.sensors


def test_a_unit_beyond_the_models_limits_is_refused_in_one_line():
    """A scenario whose clearance is inside the clearance tolerance (0.3 mm) of zero: the
    units that draw it negative are refused, naming the file, unit and parameter."""
    text = 'name = "tight"\nunit_id = "u{}"\n[parameters.shoe]\nrunning_clearance_m = 0.0001\n'
    refused = []
    for i in range(40):
        try:
            parse_scenario(text.format(i), "tight.toml")
        except ScenarioError as exc:
            refused.append(str(exc))
    assert refused  # P(d < -0.1 mm) = 16 % per unit: 40 units all valid has odds 1e-3
    for message in refused:
        assert "\n" not in message and message.startswith("tight.toml: unit 'u")
        assert "running_clearance_m" in message


@pytest.mark.parametrize("value", ["-1", "2.5", '"7"', "true", str(2**63)])
def test_a_bad_fleet_seed_is_refused_in_one_line(value):
    with pytest.raises(ScenarioError, match="fleet_seed") as info:
        parse_scenario(f'name = "x"\nunit_id = "u"\nfleet_seed = {value}\n')
    assert "\n" not in str(info.value)
    with pytest.raises(ScenarioError, match="fleet_seed"):
        load_scenario("symmetric").with_unit("u", fleet_seed=-1)


@pytest.mark.parametrize("unit_id", ["", ".hidden", "a/b", "x" * 65, "sp ace", 7], ids=repr)
def test_a_bad_unit_id_is_refused_in_one_line(unit_id):
    with pytest.raises(ScenarioError, match="unit_id") as info:
        load_scenario("symmetric").with_unit(unit_id)
    assert "\n" not in str(info.value)
    with pytest.raises(ParameterError):
        scatter.deviations("u", -1)


@pytest.mark.slow
def test_the_unit_command_prints_the_unit_against_nominal():
    r = cli_process.run(
        [sys.executable, "-m", "brake_sim_ros.cli", "unit", "VIN-0042", "--fleet-seed", "11"],
        capture_output=True, text=True, cwd=ROOT, timeout=600,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    scenario = load_scenario("symmetric").with_unit("VIN-0042", fleet_seed=11)
    mu = scenario.setup.params.friction.coefficient
    line = next(x for x in r.stdout.splitlines() if "friction.coefficient" in x)
    assert f"{mu:.6g}" in line and f"{100 * (mu / 0.285 - 1):+.3f} %" in line
    assert "+-15 %" in line
    bad = cli_process.run(
        [sys.executable, "-m", "brake_sim_ros.cli", "unit", "a b"],
        capture_output=True, text=True, cwd=ROOT, timeout=600,
    )  # fmt: skip
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "unit_id" in bad.stderr


def test_ground_truth_and_recording_carry_the_unit(tmp_path):
    """The unit's id and parameters reach DefectState, the MCAP metadata (read back by the
    mcap reader, the DefectState by rosbags alone) and the Parquet file's metadata."""
    pytest.importorskip("rclpy")
    from mcap.reader import make_reader

    from brake_sim_ros import stream
    from brake_sim_ros.recording import metadata
    from brake_sim_ros.recording.record import record_offline
    from tests.bag_helpers import rosbags_decoded

    scenario = load_scenario("symmetric").with_unit("VIN-0042", seed=11, fleet_seed=3)
    path = tmp_path / "unit.mcap"
    record_offline(scenario, path, duration_s=0.05)
    with open(path, "rb") as f:
        records = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
    unit = records[metadata.UNIT]
    assert (unit["unit_id"], unit["seed"], unit["fleet_seed"]) == ("VIN-0042", "11", "3")
    values = json.loads(unit["unit_parameters"])
    assert values == [v.as_dict() for v in scenario.unit_values()]
    friction = next(v for v in values if v["key"] == "friction.coefficient")
    assert friction["nominal"] == 0.285 != friction["value"]
    assert friction["value"] == scenario.setup.params.friction.coefficient
    params, _ = metadata.model_from_record(records[metadata.MODEL])
    assert params == scenario.setup.params  # the model record is the unit's brake
    assert records[metadata.ROSBAG2]["serialized_metadata"].count("VIN-0042") == 1

    truths = rosbags_decoded(path)[stream.DEFECTS.name]
    assert [(t.unit_id, t.seed) for t in truths] == [("VIN-0042", 11)]


@pytest.mark.slow
def test_simulate_writes_the_unit_into_the_parquet_metadata(tmp_path):
    pq = pytest.importorskip("pyarrow.parquet")
    source = tmp_path / "unit.toml"
    source.write_text('name = "fleet"\nunit_id = "VIN-0042"\nseed = 11\nfleet_seed = 3\n')
    out = tmp_path / "run.parquet"
    r = cli_process.run(
        [sys.executable, "-m", "brake_sim_ros.cli", "simulate", str(source), "--duration",
         "0.05", "--out", str(out), "--quiet"],
        capture_output=True, text=True, cwd=ROOT, timeout=600,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    meta = json.loads(pq.read_schema(out).metadata[b"brake_sim"])
    expected = load_scenario(source).unit_values()
    assert meta["unit_id"] == "VIN-0042" and meta["seed"] == 11
    assert meta["unit_parameters"] == [v.as_dict() for v in expected]
    assert any(v["value"] != v["nominal"] for v in meta["unit_parameters"])


# --- the spread of a fleet ----------------------------------------------------------------
# A short stop (from 40 rad/s, about 2.6 s) at the fast preset: a unit costs about 0.1 s.
SHORT_STOP = """
name = "short_stop"
duration_s = 4.0
[parameters.driveline]
initial_speed_rad_s = 40.0
[solver]
preset = "fast"
"""


@pytest.mark.slow
@pytest.mark.parametrize("brake", ["study", "service"])
def test_fifty_units_spread_stop_time_and_first_impact_as_the_scatter_predicts(brake):
    """The spread across 50 units against a linear model of the scatter, derived before
    the fleet is run: each parameter moved one sigma alone gives its effect on a figure,
    the predicted standard deviation is the root sum of squares of the effects times each
    truncated distribution's std/sigma (``studies/units.linear_spread``).

    Bounds: the sample standard deviation of 50 draws has a relative standard error of
    about 1/sqrt(2 x 49) = 10 %, so 0.6-1.4 of the prediction is four standard errors;
    0.2 more above allows for what the linear model leaves out (a peak force and a stop
    time are smooth but not linear over +-3 sigma). Spread must be nonzero, and the stop
    time must fall with the friction coefficient (the braking torque rises with it). On
    either brake (each its own scatter table).
    """
    text = ("" if brake == "study" else 'brake = "service"\n') + SHORT_STOP
    scenario = parse_scenario(text).with_unit(scatter.NOMINAL_UNIT, fleet_seed=2)
    assert scenario.setup.params.brake == brake
    predicted, parts = fleet_study.linear_spread(scenario, duration_s=4.0)
    ids = fleet_study.fleet_unit_ids(50)
    rows = fleet_study.fleet(scenario, ids, duration_s=4.0)
    stop = np.array([r.stop_time_s for r in rows])
    peak = np.array([r.first_impact_n for r in rows])
    assert np.all(np.isfinite(stop)) and np.all(np.isfinite(peak))
    assert np.std(stop) > 0 and np.std(peak) > 0
    assert 0.6 <= np.std(stop, ddof=1) / predicted.stop_time_s <= 1.6
    assert 0.6 <= np.std(peak, ddof=1) / predicted.first_impact_n <= 1.6
    mu = np.array([scatter.deviations(u, 2)["friction.coefficient"] for u in ids])
    assert parts["friction.coefficient"].stop_time_s < 0
    assert np.corrcoef(mu, stop)[0, 1] < -0.5


def test_bench_units_refuses_an_unknown_brake_in_one_line(capsys):
    with pytest.raises(SystemExit) as exc:
        fleet_study.main(["--brake", "disc", "--units", "2"])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "--brake: invalid choice: 'disc'" in err and "'service'" in err
