"""Operating conditions drawn per run (fleet/conditions.py, a scenario's [conditions])."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import stats

from brake_sim_ros.errors import ScenarioError
from brake_sim_ros.fleet import conditions
from brake_sim_ros.model.actuation import NOMINAL_PEAK_ACTUATION_N
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.scenarios import load_scenario, parse_scenario
from brake_sim_ros.stream.run import run_scenario

RANGES = """
[conditions]
initial_speed_rad_s = [60.0, 120.0]
load_factor = [1.0, 1.4]
peak_force_n = [900.0, 2000.0]
"""


def _scenario(seed: int = 3, extra: str = RANGES):
    return parse_scenario(f'name = "cond"\nseed = {seed}\n{extra}', "cond.toml")


def test_without_conditions_a_scenario_is_as_before():
    scenario = load_scenario("symmetric")
    assert scenario.conditions == () and not scenario.drawn
    assert scenario.setup.params == BrakeParameters()
    assert max(scenario.setup.actuation.left.forces_n) == NOMINAL_PEAK_ACTUATION_N


def test_each_run_draws_its_conditions_within_range_and_applies_them():
    nominal = BrakeParameters().driveline
    ramp = load_scenario("symmetric").setup.actuation.left
    for seed in range(20):
        s = _scenario(seed)
        drawn = dict(s.conditions)
        assert drawn == dict(_scenario(seed).conditions)  # the same bits for the same seed
        assert 60.0 <= drawn["initial_speed_rad_s"] <= 120.0
        assert 1.0 <= drawn["load_factor"] <= 1.4 and 900.0 <= drawn["peak_force_n"] <= 2000.0
        d = s.setup.params.driveline
        assert d.initial_speed_rad_s == drawn["initial_speed_rad_s"]
        assert d.flywheel_inertia_kg_m2 == nominal.flywheel_inertia_kg_m2 * drawn["load_factor"]
        for profile in (s.setup.actuation.left, s.setup.actuation.right):
            assert max(profile.forces_n) == pytest.approx(drawn["peak_force_n"], rel=1e-15)
            assert profile.times_s == ramp.times_s  # the ramp's timing kept
    assert _scenario(1).conditions != _scenario(2).conditions


def test_a_redraw_starts_from_the_scenarios_values_not_the_last_draw():
    s = _scenario(3)
    again = s.with_unit(seed=4).with_unit(seed=3)
    assert again.setup == s.setup and again.conditions == s.conditions


def test_draws_are_uniform_and_each_conditions_own():
    speeds = np.array(
        [conditions.draw({"initial_speed_rad_s": (0.0, 1.0)}, seed)["initial_speed_rad_s"]
         for seed in range(2000)]
    )  # fmt: skip
    assert stats.kstest(speeds, stats.uniform(0.0, 1.0).cdf).pvalue > 1e-3
    alone = conditions.draw({"load_factor": (1.0, 1.4)}, 9)
    together = conditions.draw({"load_factor": (1.0, 1.4), "peak_force_n": (1.0, 2.0)}, 9)
    assert alone["load_factor"] == together["load_factor"]


@pytest.mark.parametrize(
    "table",
    [
        "[conditions]\nload_factor = [1.4, 1.0]",
        "[conditions]\nload_factor = 1.2",
        "[conditions]\nload_factor = [1.0, 1.2, 1.4]",
        "[conditions]\nambient_temperature_c = [0, 60]",
        "[conditions]\nbrake_temperature_c = [-50, 100]",
        "[conditions]\ncabin_temperature_c = [0, 40]",
        "[conditions]\ninitial_speed_rad_s = [0, 500]",
        "[conditions]\npeak_force_n = [1000, 2000]\n[actuation]\npeak_force_n = 0.0",
    ],
)
def test_bad_conditions_are_refused_in_one_line(table):
    with pytest.raises(ScenarioError) as info:
        _scenario(0, table)
    message = str(info.value)
    assert message.startswith("cond.toml: ") and "\n" not in message
    assert "condition" in message


# A short stop (from 40 rad/s) at the fast preset, with fixed conditions (low = high).
def _run(load: float, peak: float):
    text = (
        f'name = "stop"\nduration_s = 6.0\n[solver]\npreset = "fast"\n[conditions]\n'
        f"initial_speed_rad_s = [40.0, 40.0]\nload_factor = [{load}, {load}]\n"
        f"peak_force_n = [{peak}, {peak}]\n"
    )
    result = run_scenario(parse_scenario(text))
    assert result.stop_time_s is not None
    return result


def test_load_moves_the_stop_as_momentum_says_and_the_peak_force_reaches_the_shoes():
    """After the ramp the friction torque tau is constant (Coulomb friction at a held
    force, the same force in both runs), so the angular momentum (I_f + I_d) w0 is removed
    by tau (T - 0.45 s): the ramp from 0.2 to 0.7 s gives the impulse of 0.25 s at full
    torque. Hence T - 0.45 s grows as the inertia (load factor); the lock at the smoothing
    speed and the coupling's twist at the lock move the ratio by far less than 2 %. A
    larger peak force is the force the shoes get and stops the drum sooner (not in
    proportion: the braking torque is not linear in the force, and the coupling's twist
    at the drum's lock grows with it)."""
    base = _run(1.0, 1300.0)
    heavy = _run(1.3, 1300.0)
    strong = _run(1.0, 2600.0)
    i_f, i_d = 17.1, 0.041
    ratio = (heavy.stop_time_s - 0.45) / (base.stop_time_s - 0.45)
    assert ratio == pytest.approx((1.3 * i_f + i_d) / (i_f + i_d), rel=0.02)
    for run, peak in ((base, 1300.0), (strong, 2600.0)):
        for side in ("left", "right"):
            assert run.samples[f"{side}_actuation_force_n"].max() == pytest.approx(peak, rel=1e-12)
    assert strong.stop_time_s < base.stop_time_s


def test_the_fade_law_is_one_up_to_its_onset_then_falls_linearly_to_half():
    fade = conditions.FADE
    assert [fade.ratio(t) for t in (-40.0, 20.0, 250.0)] == [1.0, 1.0, 1.0]
    assert fade.ratio(300.0) == pytest.approx(0.75, rel=1e-15)
    assert fade.ratio(350.0) == fade.ratio(600.0) == 0.5


def _stop(temperatures: str, friction: str = ""):
    text = (
        f'name = "hot"\nduration_s = 6.0\n[solver]\npreset = "fast"\n{friction}[conditions]\n'
        f"initial_speed_rad_s = [40.0, 40.0]\n{temperatures}"
    )
    return parse_scenario(text)


def test_a_hot_brake_brakes_with_faded_linings_and_a_cold_one_as_it_is():
    cool = _stop("ambient_temperature_c = [-20.0, 40.0]")
    assert cool.setup.params == _stop("").setup.params  # ambient alone: no physics changed
    assert dict(cool.conditions)["ambient_temperature_c"] != 0.0  # but it is ground truth
    hot = _stop("brake_temperature_c = [300.0, 300.0]\nambient_temperature_c = [20.0, 20.0]")
    mu = BrakeParameters().friction.coefficient
    assert hot.setup.params.friction.coefficient == mu * 0.75
    same = _stop("", f"[parameters.friction]\ncoefficient = {mu * 0.75!r}\n")
    hot_run, same_run = run_scenario(hot), run_scenario(same)
    assert hot_run.stop_time_s == same_run.stop_time_s  # the same brake, bit for bit
    for i, name in enumerate(hot_run.samples.columns):
        if name != "brake_temperature_c":
            np.testing.assert_array_equal(hot_run.samples.data[:, i], same_run.samples.data[:, i])
    # a brake without a thermal state is recorded at the temperature it is held at
    assert np.all(hot_run.samples["brake_temperature_c"] == 300.0)
    assert np.all(same_run.samples["brake_temperature_c"] == 20.0)
    assert hot_run.stop_time_s > run_scenario(cool).stop_time_s  # less friction, longer stop
    record = hot.conditions_record()
    assert record["brake_temperature_c"] == {
        "value": 300.0,
        "unit": "degC",
        "range": [300.0, 300.0],
    }


def test_the_drawn_conditions_are_ground_truth(tmp_path):
    pytest.importorskip("rclpy")
    from mcap.reader import make_reader

    from brake_sim_ros.datasets.parquet import history_table
    from brake_sim_ros.recording import metadata
    from brake_sim_ros.recording.record import record_offline

    scenario = _scenario(5)
    path = tmp_path / "cond.mcap"
    record_offline(scenario, path, duration_s=0.02)
    with open(path, "rb") as f:
        records = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
    truth = json.loads(records[metadata.UNIT]["conditions"])
    drawn = dict(scenario.conditions)
    assert {k: v["value"] for k, v in truth.items()} == drawn
    assert truth["load_factor"] == {"value": drawn["load_factor"], "unit": "1", "range": [1.0, 1.4]}
    params, _ = metadata.model_from_record(records[metadata.MODEL])
    assert params.driveline.initial_speed_rad_s == drawn["initial_speed_rad_s"]
    run = run_scenario(scenario, duration_s=0.01)
    table = history_table(
        run.samples,
        None,
        scenario.setup.defects,
        {},
        unit_id=scenario.unit_id,
        unit_values=scenario.unit_values(),
        conditions=scenario.conditions_record(),
    )
    meta = json.loads(table.schema.metadata[b"brake_sim"])
    assert meta["conditions"] == truth


def test_the_unit_command_shows_the_drawn_conditions(tmp_path):
    from brake_sim_ros.cli.scenarios import unit_text

    text = unit_text(_scenario(5))
    drawn = dict(_scenario(5).conditions)
    line = next(x for x in text.splitlines() if "condition load_factor" in x)
    assert f"{drawn['load_factor']:.6g} 1 (drawn from [1, 1.4] with seed 5)" in line
