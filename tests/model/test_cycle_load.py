"""Vehicle load per stop: a drive cycle's standing holds change the load (model/cycle.py)."""

from __future__ import annotations

import math

import numpy as np
import pyarrow.parquet as pq
import pytest

from brake_sim_ros.analysis.energy import energy_balance
from brake_sim_ros.datasets.parquet import history_table, write_history
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.model.cycle import load_key
from brake_sim_ros.model.vehicle import GRAVITY_M_S2, ROLLING_SMOOTHING_SPEED_M_S
from brake_sim_ros.scenarios import load_scenario, parse_scenario
from brake_sim_ros.stream.build import stepper_for

LOW, HIGH, FIXED = 0.6, 2.5, 1.3
# A stop-and-go lap on a 4 % climb: to 12 km/h, a stop, a hold that sets the load FIXED,
# a second standing hold that draws it in [LOW, HIGH] (the next lap drives with it), a
# release; about 3.3 s a lap.
LAPS = f"""
name = "laden"
duration_s = 11.0
sample_rate_hz = 5120.0
seed = {{seed}}
[parameters.driveline]
initial_speed_rad_s = 0.0
[vehicle]
grade_pct = 4.0
[cycle]
repeat = true
max_drive_torque_n_m = 400.0
speed_time_constant_s = 0.2
[[cycle.segments]]
kind = "accelerate"
kmh = 12.0
[[cycle.segments]]
kind = "brake"
pressure_bar = 35.0
until_kmh = 0.0
[[cycle.segments]]
kind = "hold"
duration_s = 0.1
load_factor = {FIXED}
[[cycle.segments]]
kind = "hold"
duration_s = 0.2
load_factor = [{LOW}, {HIGH}]
[[cycle.segments]]
kind = "release"
duration_s = 0.3
"""
FIXED_HOLD, DRAW_HOLD = 2, 3  # the segments that set the load


def _run(seed: int, duration_s: float = 11.0):
    scenario = parse_scenario(LAPS.format(seed=seed))
    return scenario, stepper_for(scenario).run(duration_s)


@pytest.fixture(scope="module")
def laps():
    return _run(0)


def _starts(block, segment: int) -> np.ndarray:
    """Rows where the cycle enters ``segment``."""
    seg = block["cycle_segment"]
    return np.flatnonzero((seg == segment) & (np.diff(seg, prepend=-2.0) != 0.0))


def _splitmix_uniform(key: int, number: int) -> float:
    """The documented draw (cycle.load_draw) written out in Python integers."""
    mask = (1 << 64) - 1
    z = (key + (number + 1) * 0x9E3779B97F4A7C15) & mask
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & mask
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & mask
    z ^= z >> 31
    return (z >> 11) / 2.0**53


def test_each_standing_hold_draws_its_load_from_the_seed_and_the_stop_number(laps):
    """Lap after lap the drawing hold sets I_f = I_0 (low + u_k (high - low)) with u_k the
    k-th counter-based draw of the run's key (k = 1, 3, 5, ...: the fixed hold takes the even
    numbers), the fixed hold I_0 x 1.3, and the inertia holds until the next change."""
    scenario, block = laps
    i0 = scenario.setup.params.driveline.flywheel_inertia_kg_m2
    inertia = block["flywheel_inertia_kg_m2"]
    draws, fixed = _starts(block, DRAW_HOLD), _starts(block, FIXED_HOLD)
    assert len(draws) >= 3 and len(fixed) >= 3  # three laps and more
    assert np.all(inertia[: fixed[0]] == i0)  # the packed load until the first stop
    key = load_key(scenario.seed)
    for lap, row in enumerate(draws):
        factor = LOW + _splitmix_uniform(key, 2 * lap + 1) * (HIGH - LOW)
        assert inertia[row] == pytest.approx(i0 * factor, rel=1e-15)
    for row in fixed:
        assert inertia[row] == pytest.approx(i0 * FIXED, rel=1e-15)
    changes = np.flatnonzero(np.diff(inertia)) + 1
    assert set(changes) <= set(draws) | set(fixed)  # nothing else moves it
    lap_factors = inertia[draws] / i0
    assert np.all((lap_factors >= LOW) & (lap_factors <= HIGH))
    assert len(np.unique(lap_factors)) == len(draws)  # a new draw each lap


def test_same_seed_same_draws_other_seeds_other_draws():
    """Seed 0 twice: the same bits; seeds 1 and 2: other factors, within the range."""
    first = {}
    for seed in (0, 0, 1, 2):
        _, block = _run(seed, duration_s=3.5)
        row = _starts(block, DRAW_HOLD)[0]
        factor = block["flywheel_inertia_kg_m2"][row]
        if seed in first:
            assert factor == first[seed]
        first[seed] = factor
    i0 = parse_scenario(LAPS.format(seed=0)).setup.params.driveline.flywheel_inertia_kg_m2
    factors = np.array(list(first.values())) / i0
    assert len(np.unique(factors)) == 3
    assert np.all((factors >= LOW) & (factors <= HIGH))


def test_the_same_bits_however_the_run_is_cut(laps):
    """One advance against uneven chunks (1, 7, 333, 4097 samples in turn): every column."""
    scenario, whole = laps
    stepper = stepper_for(scenario)
    blocks, sizes, k = [], (1, 7, 333, 4097), 0
    while stepper.sample_index < len(whole):
        size = min(sizes[k % len(sizes)], len(whole) - stepper.sample_index)
        blocks.append(stepper.advance(size))
        k += 1
    np.testing.assert_array_equal(np.concatenate([b.data for b in blocks]), whole.data)


def test_the_flywheel_accelerates_as_one_over_the_inertia_in_force(laps):
    """Equation of motion on the recorded samples of every acceleration: I_f dw/dt (central
    difference) = drive - road load - coupling, with the inertia in force; with the packed
    inertia instead it fails wherever the load is not 1. And the road load's mass part
    (rolling, grade) scales with the load, the drag does not."""
    scenario, block = laps
    d = scenario.setup.params.driveline
    vehicle = scenario.setup.vehicle
    period = block.sample_period_s
    w = block["flywheel_speed_rad_s"]
    twist = block["flywheel_angle_rad"] - block["drum_angle_rad"]
    coupling = d.coupling_stiffness_n_m_per_rad * twist + d.coupling_damping_n_m_s_per_rad * (
        w - block["drum_speed_rad_s"]
    )
    torque = block["drive_torque_n_m"] - block["road_load_torque_n_m"] - coupling
    inertia = block["flywheel_inertia_kg_m2"]
    rows = np.flatnonzero(block["cycle_segment"] == 0)
    rows = rows[(rows > 0) & (rows < len(w) - 1)]
    rows = rows[block["cycle_segment"][rows + 1] == 0]  # both neighbours accelerate too
    rows = rows[block["cycle_segment"][rows - 1] == 0]
    laden = rows[inertia[rows] != d.flywheel_inertia_kg_m2]
    assert len(laden) > 1000 and np.ptp(inertia[laden]) > 1.0  # laps at different loads
    accel = (w[rows + 1] - w[rows - 1]) / (2 * period)
    scale = np.max(np.abs(block["drive_torque_n_m"][rows]))  # N m, the drive's
    assert np.max(np.abs(inertia[rows] * accel - torque[rows])) < 5e-4 * scale
    packed = np.abs(d.flywheel_inertia_kg_m2 * accel[np.isin(rows, laden)] - torque[laden])
    assert np.median(packed) > 0.1 * scale
    # the road load against its formula with the mass m_share = I_f / r^2 in force
    r = vehicle.wheel_radius_m
    mass = inertia / r**2
    v = w * r
    a = vehicle.grade_rad
    drag = 0.25 * 0.5 * 1.225 * 0.66 * v * np.abs(v)
    expected = r * (
        mass
        * GRAVITY_M_S2
        * (0.010 * math.cos(a) * np.tanh(v / ROLLING_SMOOTHING_SPEED_M_S) + math.sin(a))
        + drag
    )
    np.testing.assert_allclose(block["road_load_torque_n_m"], expected, rtol=1e-12, atol=1e-9)
    fast = laden[v[laden] > 2.0]
    scaled_drag = expected[fast] + r * drag[fast] * (inertia[fast] / d.flywheel_inertia_kg_m2 - 1)
    assert np.max(np.abs(scaled_drag - block["road_load_torque_n_m"][fast])) > 1e-3


def test_energy_books_close_with_load_changes(laps):
    """Over three laps of stops whose load changes, drive work in = losses + road-load work
    + change of stored energy (with the inertia in force) - the load changes' kinetic
    energy, to 1e-6 of the drive work: the existing cycle test's tolerance. Without the
    load changes' work the books would miss by far more."""
    scenario, block = laps
    books = energy_balance(block, scenario.setup.params)
    drive = block["drive_work_j"][-1]
    load = block["load_change_work_j"][-1]
    assert drive > 3_000.0
    assert abs(books.residual_j) <= 1e-6 * drive
    assert abs(load) > 100 * 1e-6 * drive  # the term is needed for the books to close


def test_a_run_without_load_changes_records_the_packed_inertia():
    scenario = load_scenario("symmetric")
    block = stepper_for(scenario).advance(500)
    assert np.all(
        block["flywheel_inertia_kg_m2"] == scenario.setup.params.driveline.flywheel_inertia_kg_m2
    )
    assert np.all(block["load_change_work_j"] == 0.0)


def test_the_load_in_force_is_a_label_column_in_parquet(laps, tmp_path):
    scenario, block = laps
    table = history_table(
        block,
        None,
        scenario.setup.defects,
        {},
        unit_id="nominal",
        unit_values=[],
        conditions={},
        cycle=scenario.setup.cycle,
    )
    write_history(tmp_path / "run.parquet", table)
    read = pq.read_table(tmp_path / "run.parquet")
    np.testing.assert_array_equal(
        read["flywheel_inertia_kg_m2"].to_numpy(), block["flywheel_inertia_kg_m2"]
    )
    phase = read["phase"].to_pylist()
    rows = _starts(block, DRAW_HOLD)
    assert all(phase[row] == f"{DRAW_HOLD}:hold" for row in rows)


_HOLD = '[[cycle.segments]]\nkind = "hold"\nduration_s = 1.0\n'
_STOP = '[[cycle.segments]]\nkind = "brake"\nforce_n = 900.0\nuntil_kmh = 0.0\n'


@pytest.mark.parametrize(
    ("segments", "says"),
    [
        (_STOP + _HOLD + 'load_factor = "heavy"\n', "a number or an array [low, high]"),
        (_STOP + _HOLD + "load_factor = true\n", "a number or an array [low, high]"),
        (_STOP + _HOLD + "load_factor = 3.5\n", "cycle.segments[1].load_factor"),
        (_STOP + _HOLD + "load_factor = nan\n", "a finite number"),
        (_STOP + _HOLD + "load_factor = [2.0, 1.0]\n", "low <= high"),
        (_STOP + _HOLD + "load_factor = [1.0, 2.0, 3.0]\n", "low <= high"),
        (_STOP + _HOLD + "load_factor = [0.4, 1.0]\n", "load_factor[0]"),
        (_STOP + _HOLD + 'load_factor = [1.0, "x"]\n', "load_factor[1]"),
        (_HOLD + "load_factor = 1.5\n", "only on a hold where the vehicle stands"),
        (
            _STOP.replace("0.0\n", "20.0\n") + _HOLD + "load_factor = 1.5\n",
            "only on a hold where the vehicle stands",
        ),
        (
            _STOP
            + '[[cycle.segments]]\nkind = "release"\nduration_s = 1.0\n'
            + _HOLD
            + "load_factor = 1.5\n",
            "only on a hold where the vehicle stands",
        ),
        (_STOP.replace("until_kmh = 0.0\n", "until_kmh = 0.0\nload_factor = 1.5\n"), "unknown key"),
        (
            _STOP + _HOLD + "load_factor = 1.5\n[conditions]\nload_factor = [0.8, 1.2]\n",
            "conditions.load_factor",
        ),
    ],
)
def test_bad_load_factors_are_refused_in_one_line(segments, says):
    text = f'name = "bad"\n[parameters.driveline]\ninitial_speed_rad_s = 0.0\n{segments}'
    with pytest.raises(BrakeSimError) as info:
        parse_scenario(text, "bad.toml")
    message = str(info.value)
    assert says in message and "\n" not in message and "load_factor" in message
