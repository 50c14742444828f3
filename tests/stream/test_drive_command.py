"""Live drive commands in the stepper (model/cycle.py LiveDrive, FixedStepStepper.drive):
the cycle's speed controller reached live, a constant torque, coasting, the books, the
bits, and what is refused."""

from __future__ import annotations

import math

import numpy as np
import pytest

from brake_sim_ros.analysis.energy import energy_balance
from brake_sim_ros.errors import BrakeSimError, ParameterError
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.cycle import (
    DEFAULT_MAX_DRIVE_TORQUE_N_M,
    DEFAULT_SPEED_TIME_CONSTANT_S,
    SPEED_TOLERANCE,
    LiveDrive,
)
from brake_sim_ros.model.vehicle import road_load_torque
from brake_sim_ros.scenarios import load_scenario, parse_scenario
from brake_sim_ros.stream import parameters as ros_params
from brake_sim_ros.stream.build import stepper_for

RATE = 2560  # samples per second of the rig below
# A test rig's scenario: a vehicle at rest, no cycle, no brake until commanded.
RIG = """
name = "rig"
duration_s = 30.0
sample_rate_hz = 2560.0
[parameters.driveline]
initial_speed_rad_s = 0.0
[vehicle]
[actuation]
peak_force_n = 0.0
"""
# The same vehicle driven by a cycle to 18 km/h (5 m/s) with the default controller.
CYCLE_TO_5_M_S = """
name = "cycle_to_5"
duration_s = 30.0
sample_rate_hz = 2560.0
[parameters.driveline]
initial_speed_rad_s = 0.0
[vehicle]
[cycle]
[[cycle.segments]]
kind = "accelerate"
kmh = 18.0
[[cycle.segments]]
kind = "cruise"
duration_s = 100.0
"""


@pytest.fixture(scope="module")
def rig():
    return parse_scenario(RIG)


def _m_s(block, scenario) -> np.ndarray:
    return block["flywheel_speed_rad_s"] * scenario.setup.vehicle.wheel_radius_m


def test_a_live_target_speed_is_the_cycles_speed_controller_bit_for_bit(rig):
    """Target 5 m/s live, from rest, against a [cycle] accelerating to 18 km/h and cruising
    there (the same controller, the same default settings): every column but the phase
    label is equal, bit for bit, over 8 s; the speed is within the controller's tolerance
    of the target at the end, and every drive torque is the controller's law evaluated on
    the recorded state (first-order approach plus the road load, clamped to 0..120 N m)."""
    live = stepper_for(rig)
    live.drive(LiveDrive("target_speed", target_speed_m_s=5.0))
    cycled = stepper_for(parse_scenario(CYCLE_TO_5_M_S))
    assert live.substeps == cycled.substeps
    a = live.advance(8 * RATE)
    b = cycled.advance(8 * RATE)
    others = [c for c in range(L.N_COLUMNS) if c != L.C_PHASE]
    np.testing.assert_array_equal(a.data[:, others], b.data[:, others])
    assert set(np.unique(b["cycle_segment"])) == {0.0, 1.0}  # it did reach the cruise
    speed = _m_s(a, rig)
    assert abs(speed[-1] - 5.0) <= SPEED_TOLERANCE * 5.0
    w = a["flywheel_speed_rad_s"]
    p = live.packed_parameters
    r = rig.setup.vehicle.wheel_radius_m
    inertia = rig.setup.params.driveline.flywheel_inertia_kg_m2
    road = np.array([road_load_torque.py_func(p, x) for x in w])
    law = np.clip(inertia * (5.0 / r - w) / DEFAULT_SPEED_TIME_CONSTANT_S + road, 0.0, 120.0)
    np.testing.assert_allclose(a["drive_torque_n_m"], law, rtol=1e-12, atol=1e-9)
    assert a["drive_torque_n_m"][0] == DEFAULT_MAX_DRIVE_TORQUE_N_M  # from rest: full drive


def test_target_speed_then_brake_then_coast_and_the_books_close(rig):
    """A stop driven live: 5 m/s, then coast with the brake rising to 1500 N per shoe until
    the drum holds, release, then a constant 60 N m. The speed follows each command; drive
    work in = losses + road load + stored energy, to 1e-6 of the drive work. (The brake
    rises over 0.2 s, as a hydraulic brake does: a 0-to-1500 N step in one sample leaves
    0.1 J, 2.5e-5 of the drive work, in the books, a matter of live actuation steps.)"""
    stepper = stepper_for(rig)
    stepper.drive(LiveDrive("target_speed", target_speed_m_s=5.0))
    blocks = [stepper.advance(7 * RATE, record_every=8)]
    assert abs(_m_s(blocks[-1], rig)[-1] - 5.0) <= SPEED_TOLERANCE * 5.0
    stepper.drive(LiveDrive("coast"))
    # the brake commanded live as a hydraulic rise: 0 to 1500 N per shoe over 0.2 s
    for force in np.linspace(0.0, 1500.0, 64):
        blocks.append(stepper.advance(8, actuation_n=(force, force), record_every=8))
    blocks.append(stepper.advance(4 * RATE, actuation_n=(1500.0, 1500.0), record_every=8))
    braked = blocks[-1]
    assert np.all(braked["drive_torque_n_m"] == 0.0)
    # stopped by the model's stop rule (model/standstill.py) within the braking, the drum
    # held by static friction at its end (the flywheel swings on the coupling, under 1 km/h
    # as the cycles' stops)
    assert stepper.stop_time_s is not None and 7.2 < stepper.stop_time_s < 11.2
    assert braked["drum_sticking"][-1] == 1.0 and braked["drum_speed_rad_s"][-1] == 0.0
    assert abs(_m_s(braked, rig)[-1]) < 1.0 / 3.6
    blocks.append(stepper.advance(RATE, actuation_n=(0.0, 0.0), record_every=8))
    stepper.drive(LiveDrive("torque", drive_torque_n_m=60.0))
    blocks.append(stepper.advance(2 * RATE, record_every=8))
    pushed = blocks[-1]
    assert np.all(pushed["drive_torque_n_m"] == 60.0)
    assert _m_s(pushed, rig)[-1] > 1.0  # rolling again
    whole = type(blocks[0]).concatenate(blocks)
    books = energy_balance(whole, rig.setup.params)
    drive = whole["drive_work_j"][-1]
    assert drive > 3_000.0 and whole["friction_work_j"][-1] > 2_000.0
    assert abs(books.residual_j) <= 1e-6 * drive


def test_the_same_commands_at_the_same_samples_give_the_same_bits_however_cut(rig):
    plan = {
        0: LiveDrive("torque", drive_torque_n_m=100.0),
        3000: LiveDrive("target_speed", target_speed_m_s=2.0),
        7000: LiveDrive("coast"),
    }
    total = 9000

    def run(chunk: int) -> np.ndarray:
        stepper = stepper_for(rig)
        out = []
        while stepper.sample_index < total:
            if stepper.sample_index in plan:
                stepper.drive(plan[stepper.sample_index])
            upto = min([k for k in plan if k > stepper.sample_index] + [total])
            out.append(stepper.advance(min(chunk, upto - stepper.sample_index)).data)
        return np.concatenate(out)

    whole = run(total)
    assert whole[-1, L.COL["drive_torque_n_m"]] == 0.0 and whole[5000, L.COL["drive_work_j"]] > 0
    for chunk in (1, 333):
        np.testing.assert_array_equal(run(chunk), whole)


def test_coast_is_the_start_and_a_reset_returns_to_it(rig):
    stepper = stepper_for(rig)
    assert stepper.live_drive == LiveDrive()
    coasting = stepper.advance(500)
    assert np.all(coasting["drive_torque_n_m"] == 0.0)
    stepper.drive(LiveDrive("torque", drive_torque_n_m=50.0))
    assert np.all(stepper.advance(500)["drive_torque_n_m"] == 50.0)
    stepper.reset()
    assert stepper.live_drive == LiveDrive()
    np.testing.assert_array_equal(stepper.advance(500).data, coasting.data)


@pytest.mark.parametrize(
    ("scenario", "says"),
    [
        ("symmetric", "has no vehicle"),
        ("urban", "drive cycle drives the vehicle"),
    ],
)
def test_runs_that_take_no_drive_refuse_it_and_change_nothing(scenario, says):
    stepper = stepper_for(load_scenario(scenario))
    before = stepper.packed_parameters
    with pytest.raises(ParameterError, match=says):
        stepper.drive(LiveDrive("torque", drive_torque_n_m=10.0))
    np.testing.assert_array_equal(stepper.packed_parameters, before)
    assert stepper.live_drive == LiveDrive()


@pytest.mark.parametrize(
    ("kwargs", "says"),
    [
        ({"mode": "reverse"}, "drive mode 'reverse'"),
        ({"mode": "torque", "drive_torque_n_m": math.nan}, "drive_torque_n_m=nan"),
        ({"mode": "torque", "drive_torque_n_m": math.inf}, "drive_torque_n_m=inf"),
        ({"mode": "torque", "drive_torque_n_m": -1.0}, "never brakes"),
        ({"mode": "torque", "drive_torque_n_m": 10_000.5}, "drive_torque_n_m=10000.5"),
        ({"mode": "target_speed", "target_speed_m_s": -0.1}, "target_speed_m_s=-0.1"),
        ({"mode": "target_speed", "target_speed_m_s": 70.0}, "from 0 to 69.44 m/s"),
        ({"mode": "target_speed", "target_speed_m_s": -math.inf}, "target_speed_m_s=-inf"),
    ],
)
def test_bad_drive_commands_are_refused_in_one_line(kwargs, says):
    with pytest.raises(BrakeSimError) as info:
        LiveDrive(**kwargs)
    assert says in str(info.value) and "\n" not in str(info.value)


def test_a_field_the_mode_does_not_use_is_not_read():
    assert LiveDrive("coast", drive_torque_n_m=math.nan, target_speed_m_s=-5.0).mode == "coast"
    assert LiveDrive("torque", drive_torque_n_m=120.0, target_speed_m_s=math.inf)


def test_the_built_in_rig_is_a_vehicle_at_rest_that_takes_drive_commands():
    scenario = load_scenario("rig")
    assert scenario.setup.vehicle is not None and scenario.setup.cycle is None
    assert scenario.setup.peak_force_n == 0.0
    stepper = stepper_for(scenario)
    assert stepper.drive_refusal() is None
    stepper.drive(LiveDrive("target_speed", target_speed_m_s=2.0))
    block = stepper.advance(25600)
    assert block["drive_torque_n_m"][-1] > 0.0 and block["flywheel_speed_rad_s"][-1] > 0.0


# -- the live drive's settings: [vehicle] keys and the node's parameters -----------------------
def _rig_with(vehicle: str) -> str:
    return RIG.replace("[vehicle]\n", f"[vehicle]\n{vehicle}\n")


def _time_to(scenario, speed_m_s: float, seconds: int) -> float:
    """Seconds a live target of 5 m/s takes from rest to ``speed_m_s`` (first sample)."""
    stepper = stepper_for(scenario)
    stepper.drive(LiveDrive("target_speed", target_speed_m_s=5.0))
    speed = _m_s(stepper.advance(seconds * RATE), scenario)
    return int(np.argmax(speed >= speed_m_s)) / RATE if speed.max() >= speed_m_s else math.inf


def test_a_larger_torque_limit_approaches_a_target_speed_faster(rig):
    """The [vehicle]'s max_drive_torque_n_m clamps the speed controller: from rest the
    drive is the limit (the controller asks far more), so 4 m/s comes sooner with 300 N m
    than with the default 120 and later with 60; the drive never exceeds the limit."""
    strong = parse_scenario(_rig_with("max_drive_torque_n_m = 300.0"))
    weak = parse_scenario(_rig_with("max_drive_torque_n_m = 60.0"))
    assert strong.setup.vehicle.max_drive_torque_n_m == 300.0
    times = [_time_to(s, 4.0, 12) for s in (weak, rig, strong)]
    assert times[0] > times[1] > times[2] and math.isfinite(times[0])
    stepper = stepper_for(weak)
    stepper.drive(LiveDrive("target_speed", target_speed_m_s=5.0))
    torque = stepper.advance(2 * RATE)["drive_torque_n_m"]
    assert torque.max() == 60.0 and torque[0] == 60.0


def test_a_shorter_time_constant_settles_on_the_target_sooner(rig):
    """speed_time_constant_s sets the controller's approach: near the target (past the
    torque limit's reach) 4.9 m/s comes sooner with 0.25 s than with the default 1 s."""
    quick = parse_scenario(_rig_with("speed_time_constant_s = 0.25"))
    assert _time_to(quick, 4.9, 12) < _time_to(rig, 4.9, 12)


def test_a_torque_command_above_the_vehicles_limit_is_refused_naming_it():
    scenario = parse_scenario(_rig_with("max_drive_torque_n_m = 80.0"))
    stepper = stepper_for(scenario)
    assert stepper.drive_refusal(LiveDrive("torque", drive_torque_n_m=80.0)) is None
    before = stepper.packed_parameters
    with pytest.raises(ParameterError) as info:
        stepper.drive(LiveDrive("torque", drive_torque_n_m=80.5))
    says = str(info.value)
    assert "max_drive_torque_n_m = 80 N m" in says and "80.5" in says and "\n" not in says
    np.testing.assert_array_equal(stepper.packed_parameters, before)
    assert stepper.live_drive == LiveDrive()
    stepper.drive(LiveDrive("torque", drive_torque_n_m=80.0))  # at the limit: taken
    assert np.all(stepper.advance(64)["drive_torque_n_m"] == 80.0)


@pytest.mark.parametrize(
    ("line", "says"),
    [
        ("max_drive_torque_n_m = -1.0", "'vehicle.max_drive_torque_n_m' = -1.0 is invalid"),
        ("max_drive_torque_n_m = 10001.0", "allowed"),
        ('max_drive_torque_n_m = "lots"', "'vehicle.max_drive_torque_n_m'"),
        ("speed_time_constant_s = 0.0", "'vehicle.speed_time_constant_s' = 0.0 is invalid"),
        ("speed_time_constant_s = nan", "'vehicle.speed_time_constant_s'"),
        ("speed_time_constant_s = 101.0", "'vehicle.speed_time_constant_s'"),
    ],
)
def test_bad_drive_settings_in_the_scenario_are_refused_in_one_line(line, says):
    with pytest.raises(BrakeSimError) as info:
        parse_scenario(_rig_with(line))
    assert says in str(info.value) and "\n" not in str(info.value)


def test_a_cycle_takes_its_settings_in_its_own_table_not_the_vehicles():
    text = CYCLE_TO_5_M_S.replace("[vehicle]\n", "[vehicle]\nmax_drive_torque_n_m = 200.0\n")
    with pytest.raises(BrakeSimError) as info:
        parse_scenario(text)
    says = str(info.value)
    assert "vehicle.max_drive_torque_n_m" in says and "[cycle] max_drive_torque_n_m" in says
    assert "\n" not in says


def test_the_nodes_overrides_replace_the_scenarios_settings_where_given(rig):
    """ros_params.with_drive_limits (the node's parameters): > 0 replaces, 0 keeps the
    scenario's; a run that takes no live drive is left as it is; bad values refused."""
    setup = ros_params.with_drive_limits(
        rig.setup, {"max_drive_torque_n_m": 250.0, "speed_time_constant_s": 0.0}
    )
    assert setup.vehicle.max_drive_torque_n_m == 250.0
    assert setup.vehicle.speed_time_constant_s == DEFAULT_SPEED_TIME_CONSTANT_S
    urban = load_scenario("urban").setup
    assert ros_params.with_drive_limits(urban, {"max_drive_torque_n_m": 250.0}) is urban
    for name, value in (("max_drive_torque_n_m", -3.0), ("speed_time_constant_s", 0.001)):
        for setup in (rig.setup, urban):  # checked even where unused: a ~/reset may use it
            with pytest.raises(ParameterError) as info:
                ros_params.with_drive_limits(setup, {name: value})
            assert f"vehicle {name} {value!r}" in str(info.value)
