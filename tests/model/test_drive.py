"""Drive between stops: road load and drive on the flywheel, drive cycles, their books."""

from __future__ import annotations

import math

import numpy as np
import pyarrow.parquet as pq
import pytest

from brake_sim_ros.analysis.energy import energy_balance
from brake_sim_ros.datasets.parquet import history_table, write_history
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.cycle import KMH_PER_M_S, SPEED_TOLERANCE
from brake_sim_ros.model.fidelity import DRIVEN_COLUMNS, plan
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.model.vehicle import GRAVITY_M_S2, Vehicle, road_load_torque
from brake_sim_ros.scenarios import load_scenario, parse_scenario
from brake_sim_ros.scenarios.tables import force_from_pressure_n
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.stream.build import stepper_for

DECIMATION = 8  # the cycle runs record every 8th sample (the books are integrated states)
PROBE_EVERY = 4096  # samples between two probes of the urban run (0.16 s)


@pytest.fixture(scope="module")
def urban():
    """The built-in urban cycle as it ships (the service brake): every 8th sample, and a
    probe every 0.16 s: the tyre's deflection (a state, not a column) and every sample of
    the next eight."""
    scenario = load_scenario("urban")
    stepper = stepper_for(scenario)
    total = round(scenario.duration_s / stepper.sample_period_s)
    blocks, probes = [], []
    while stepper.sample_index < total:
        n = min(PROBE_EVERY, total - stepper.sample_index)
        blocks.append(stepper.advance(n, record_every=DECIMATION))
        if stepper.sample_index + DECIMATION <= total:
            deflection = float(stepper.state[L.Y_TYRE_DEFLECTION])
            rows = stepper.advance(DECIMATION)
            probes.append((deflection, rows))
            blocks.append(SampleBlock(rows.data[:1], rows.first_index, blocks[0].sample_period_s))
    return scenario, SampleBlock.concatenate(blocks), probes, stepper


def _kmh(block, scenario) -> np.ndarray:
    return block["flywheel_speed_rad_s"] * scenario.setup.vehicle.wheel_radius_m * KMH_PER_M_S


def _segments(block):
    """(segment index, first row, last row) of each segment in the run, in order."""
    seg = block["cycle_segment"]
    starts = np.flatnonzero(np.diff(seg, prepend=-2.0))
    ends = [*(starts[1:] - 1), len(seg) - 1]
    return [(int(seg[a]), int(a), int(b)) for a, b in zip(starts, ends, strict=True)]


def test_road_load_closed_form():
    """The road load at 20 m/s and at rest against the formula written out by hand."""
    vehicle = Vehicle(grade_pct=5.0)
    p = np.zeros(L.N_PARAMS)
    p[L.P_FLYWHEEL_INERTIA] = 17.1
    from brake_sim_ros.model.vehicle import pack_vehicle

    pack_vehicle(p, vehicle)
    r = vehicle.wheel_radius_m
    mass = 17.1 / r**2
    a = math.atan(0.05)
    v = 20.0
    expected = r * (
        mass * GRAVITY_M_S2 * (0.010 * math.cos(a) * math.tanh(v / 0.01) + math.sin(a))
        + 0.25 * 0.5 * 1.225 * 0.66 * v * v
    )
    assert road_load_torque.py_func(p, v / r) == pytest.approx(expected, rel=1e-12)
    # at rest only the grade pulls: rolling resistance does not push a stopped vehicle
    assert road_load_torque.py_func(p, 0.0) == pytest.approx(r * mass * GRAVITY_M_S2 * math.sin(a))
    flat = np.zeros(L.N_PARAMS)
    flat[L.P_FLYWHEEL_INERTIA] = 17.1
    pack_vehicle(flat, Vehicle())
    assert road_load_torque.py_func(flat, -30.0) == -road_load_torque.py_func(flat, 30.0)


@pytest.mark.slow  # the urban cycle's 50 s on the service brake
def test_energy_books_close_over_the_urban_cycle(urban):
    """Drive and cylinder work in = friction + tyre + contact + lock losses + road-load work
    + change of stored (kinetic, elastic, springs and stops, line) energy, to 1e-6 of the
    drive work over three stops on the service brake."""
    scenario, block, _, stepper = urban
    p = stepper.packed_parameters
    books = energy_balance(block, scenario.setup.params, packed=p)
    drive = block["drive_work_j"][-1]
    road = block["road_load_work_j"][-1]
    friction = block["friction_work_j"][-1]
    # every term works: the drive gives the vehicle the kinetic energy of its three peaks,
    # I_f / 2 (w40^2 + w50^2 + w30^2) = 45.9 kJ, and more (against the road load); the
    # brakes take it but the road load's part in the stops (< 36 N over < 30 m each) and
    # the tyre's small slip
    peaks = sum((kmh / KMH_PER_M_S / p[L.P_WHEEL_RADIUS]) ** 2 for kmh in (40.0, 50.0, 30.0))
    kinetic = 0.5 * p[L.P_FLYWHEEL_INERTIA] * peaks
    assert kinetic == pytest.approx(45_930.0, rel=0.01)
    assert drive > kinetic and road > 5_000.0 and friction > 0.8 * kinetic
    # at rest the shoes press their stops by (P - F_r) / k_st and the line holds its
    # residual pressure F_r / A: stored (P - F_r)^2 / k_st + C (F_r / A)^2 / 2, 2.0 mJ
    service = scenario.setup.params.service
    residual = service.residual_force_n
    stops = (service.return_spring_preload_n - residual) ** 2 / service.stop_stiffness_n_per_m
    area = math.pi * service.wheel_cylinder_bore_m**2 / 4.0
    line = 0.5 * service.line_compliance_m3_per_pa * (residual / area) ** 2
    assert books.stored_start_j == pytest.approx(stops + line, rel=1e-9)
    assert abs(books.residual_j) <= 1e-6 * drive
    # the road-load quadrature against its recorded torque times the speed (trapezoid)
    power = block["road_load_torque_n_m"] * block["flywheel_speed_rad_s"]
    trapezoid = float(np.sum(0.5 * (power[1:] + power[:-1])) * block.sample_period_s)
    assert trapezoid == pytest.approx(road, rel=1e-3)


def _tyre_force_n(p: np.ndarray, inertia: float, deflection: float, slip: float) -> float:
    """The tyre's LuGre force along the slip speed ``slip`` (m/s), N, written out from
    model/tyre.py's docstring: ``F_z (sigma0 z + sigma1 dz/dt + sigma2 v_r)``."""
    sliding, peak = p[L.P_TYRE_SLIDING], p[L.P_TYRE_PEAK]
    curve = abs(slip / p[L.P_TYRE_STRIBECK_SPEED]) ** p[L.P_TYRE_STRIBECK_EXPONENT]
    g = sliding + (peak - sliding) * math.exp(-curve)
    rate = slip - p[L.P_TYRE_STIFFNESS] * abs(slip) * deflection / g
    load = inertia / p[L.P_WHEEL_RADIUS] ** 2 * GRAVITY_M_S2
    stiffness, damping = p[L.P_TYRE_STIFFNESS], p[L.P_TYRE_DAMPING]
    return load * (stiffness * deflection + damping * rate + p[L.P_TYRE_VISCOUS] * slip)


@pytest.mark.slow  # the urban cycle's 50 s on the service brake
def test_the_flywheel_moves_by_drive_road_load_and_tyre_through_the_stops(urban):
    """The vehicle's equation on the service brake's urban cycle, ``I_f dw_f/dt = T_drive -
    T_road + R F``, at a probe every 0.16 s of the 50 s: accelerating, cruising, braking
    (impacts on the drum), the drum held at standstill and released. ``F`` is the tyre's
    force from its deflection, ``dw_f/dt`` a second-order one-sided difference of three
    samples (its error is dt^2 / 3 times the speed's third derivative). Without the tyre's
    term it fails."""
    scenario, _, probes, stepper = urban
    p = stepper.packed_parameters
    radius = p[L.P_WHEEL_RADIUS]
    kinds = [s.kind for s in scenario.setup.cycle.segments] + ["end"]
    residuals, tyre_torques, without, seen = [], [], [], set()
    for deflection, rows in probes:
        segment = rows["cycle_segment"][:3]
        if np.ptp(segment) != 0.0:  # the controller changed segment within the difference
            continue
        w = rows["flywheel_speed_rad_s"]
        accel = (-3.0 * w[0] + 4.0 * w[1] - w[2]) / (2.0 * rows.sample_period_s)
        inertia = rows["flywheel_inertia_kg_m2"][0]
        slip = radius * (rows["drum_speed_rad_s"][0] - w[0])
        tyre = radius * _tyre_force_n(p, inertia, deflection, slip)
        driving = rows["drive_torque_n_m"][0] - rows["road_load_torque_n_m"][0]
        residuals.append(inertia * accel - (driving + tyre))
        without.append(inertia * accel - driving)
        tyre_torques.append(tyre)
        kind = kinds[int(segment[0])]
        if rows["drum_sticking"][0] == 1.0:
            kind += " held"
        if rows["left_normal_force_n"][0] > 0.0:
            kind += " in contact"
        seen.add(kind)
    assert {"accelerate", "cruise", "brake in contact", "hold held in contact", "release"} <= seen
    assert len(residuals) > 250
    scale = np.max(np.abs(tyre_torques))  # N m: the largest tyre torque, braking
    assert scale > 100.0
    assert np.max(np.abs(residuals)) < 1e-3 * scale
    assert np.max(np.abs(without)) > 0.5 * scale  # braking, the tyre carries the brake


@pytest.mark.slow  # the urban cycle's 50 s on the service brake
def test_cycle_segments_reach_their_targets(urban):
    """Each acceleration ends within 1 % of its target, each cruise holds it within 1 %,
    each stop ends at rest with the drum held and the line near its pressure, each hold
    and release lasts its time, a hold ends with the line settled at its pressure."""
    scenario, block, _, _ = urban
    kmh = _kmh(block, scenario)
    segments = scenario.setup.cycle.segments
    period = block.sample_period_s
    seen = _segments(block)
    assert [s for s, _, _ in seen] == list(range(len(segments) + 1))  # all, in order, end
    target = brake = 0.0
    for index, first, last in seen[:-1]:
        segment = segments[index]
        # the segment's end: the first sample of the next
        end = kmh[last + 1]
        duration = (last + 1 - first) * period
        if segment.kind == "accelerate":
            target = segment.speed_kmh
            assert target * (1 - SPEED_TOLERANCE) <= end <= target * 1.01
        elif segment.kind == "cruise":
            assert abs(end - target) <= 0.01 * target
            assert duration == pytest.approx(segment.duration_s, abs=period)
        elif segment.kind == "brake":
            assert abs(end) < 1.0
            assert block["drum_sticking"][last + 1] == 1.0
            # the pistons push with the line pressure, which follows the commanded source
            # through the line (R C = 30 ms) and moves as the shoes push fluid
            force = block["left_actuation_force_n"][last]
            assert force == pytest.approx(segment.force_n, rel=0.01)
            brake = segment.force_n
        elif segment.kind == "hold":
            assert duration == pytest.approx(segment.duration_s, abs=period)
            # held 1.5-2 s (50 R C and more) with the drum and the shoes at rest: settled
            force = block["left_actuation_force_n"][last]
            assert force == pytest.approx(segment.force_n or brake, rel=1e-6)  # or the last
        else:  # release
            assert duration == pytest.approx(segment.duration_s, abs=period)


def test_downhill_drag_holds_the_speed_with_the_brake():
    scenario = load_scenario("downhill")
    block = stepper_for(scenario).run(21.0, record_every=DECIMATION)
    kmh = _kmh(block, scenario)
    late = (block.time_s > 10.0) & (block.time_s < 20.0)
    assert np.all(np.abs(kmh[late] - 60.0) < 0.6)  # within 1 %
    assert np.all(block["drive_torque_n_m"] == 0.0)  # the brake alone
    assert block["left_actuation_force_n"][late].min() > 50.0  # and it does brake
    assert block["friction_work_j"][-1] > 0.5 * -block["road_load_work_j"][-1]


CHUNKED = """
name = "chunks"
duration_s = 4.0
sample_rate_hz = 5120.0
[parameters.driveline]
initial_speed_rad_s = 0.0
[vehicle]
grade_pct = 2.0
[cycle]
max_drive_torque_n_m = 300.0
speed_time_constant_s = 0.2
[[cycle.segments]]
kind = "accelerate"
kmh = 12.0
[[cycle.segments]]
kind = "brake"
pressure_bar = 30.0
until_kmh = 0.0
[[cycle.segments]]
kind = "hold"
duration_s = 0.3
[[cycle.segments]]
kind = "release"
duration_s = 0.4
"""


def test_the_cycle_gives_the_same_bits_however_the_run_is_cut():
    scenario = parse_scenario(CHUNKED)
    whole = stepper_for(scenario).run(scenario.duration_s)
    assert set(np.unique(whole["cycle_segment"])) == {0.0, 1.0, 2.0, 3.0, 4.0}  # passes all
    for chunk in (1, 7, 1000):
        stepper = stepper_for(scenario)
        total = len(whole)
        blocks = []
        while stepper.sample_index < total:
            blocks.append(stepper.advance(min(chunk, total - stepper.sample_index)))
        np.testing.assert_array_equal(np.concatenate([b.data for b in blocks]), whole.data)


HILL = """
name = "hill"
duration_s = 4.0
sample_rate_hz = 5120.0
[parameters.driveline]
initial_speed_rad_s = 0.0
[vehicle]
grade_pct = -12.0
[cycle]
[[cycle.segments]]
kind = "hold"
force_n = {force}
duration_s = 4.0
"""


def test_a_held_brake_carries_the_grade():
    """On a 12 % descent, a brake held at 1000 N per shoe holds the vehicle: the drum stuck,
    the flywheel at rest, the coupling carries the grade's torque to the brake. At 60 N
    (below the first contact) the vehicle rolls away."""
    scenario = parse_scenario(HILL.format(force=1000.0))
    block = stepper_for(scenario).run(scenario.duration_s, record_every=16)
    vehicle = scenario.setup.vehicle
    driveline = scenario.setup.params.driveline
    grade = (
        vehicle.wheel_radius_m
        * vehicle.mass_on_flywheel_kg(driveline.flywheel_inertia_kg_m2)
        * GRAVITY_M_S2
        * math.sin(vehicle.grade_rad)
    )
    assert grade < -50.0  # pulls forward, about a third of what 1000 N per shoe holds
    last = block.data[-1]
    twist = last[L.COL["flywheel_angle_rad"]] - last[L.COL["drum_angle_rad"]]
    coupling = (
        driveline.coupling_stiffness_n_m_per_rad * twist
        + driveline.coupling_damping_n_m_s_per_rad * last[L.COL["flywheel_speed_rad_s"]]
    )
    assert last[L.COL["drum_sticking"]] == 1.0
    assert abs(last[L.COL["flywheel_speed_rad_s"]]) < 1e-3
    assert coupling == pytest.approx(-grade, rel=0.01)
    loose = parse_scenario(HILL.format(force=60.0))
    rolled = stepper_for(loose).run(loose.duration_s, record_every=16)
    assert rolled["flywheel_speed_rad_s"][-1] > 1.5  # about g sin(a) t / r away


def test_without_a_vehicle_nothing_changes_in_the_books():
    block = stepper_for(load_scenario("symmetric")).advance(2000)
    for name in ("drive_torque_n_m", "road_load_torque_n_m", "drive_work_j", "road_load_work_j"):
        assert np.all(block[name] == 0.0)
    assert np.all(block["cycle_segment"] == -1.0)


def test_phase_label_column_in_parquet(tmp_path):
    scenario = parse_scenario(CHUNKED)
    block = stepper_for(scenario).run(scenario.duration_s, record_every=4)
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
    path = tmp_path / "run.parquet"
    write_history(path, table)
    read = pq.read_table(path)
    phase = read["phase"].to_pylist()
    assert phase[0] == "0:accelerate" and phase[-1] == "4:end"
    segment = read["cycle_segment"].to_numpy()
    kinds = ["accelerate", "brake", "hold", "release", "end"]
    assert phase == [f"{int(s)}:{kinds[int(s)]}" for s in segment]


def test_pressure_is_force_on_the_default_piston():
    assert force_from_pressure_n(46.0) == pytest.approx(1311.2, abs=0.1)  # MODEL: ~1300 N


@pytest.mark.parametrize(
    ("extra", "says"),
    [
        ("[vehicle]\ngrade_pct = 45.0", "vehicle.grade_pct"),
        ("[vehicle]\nmass_share = 0.0", "vehicle.mass_share"),
        ("[vehicle]\ncolour = 1.0", "unknown key"),
        ("[cycle]\nsegments = []", "cycle.segments"),
        ('[[cycle.segments]]\nkind = "fly"', "cycle.segments[0].kind"),
        ('[[cycle.segments]]\nkind = "brake"', "pressure_bar or force_n"),
        ('[[cycle.segments]]\nkind = "cruise"', "duration_s"),
        ('[[cycle.segments]]\nkind = "accelerate"\nkmh = -5.0', "kmh"),
        (
            '[[cycle.segments]]\nkind = "hold"\nduration_s = 1.0\npressure_bar = 2.0\n'
            "force_n = 3.0",
            "not both",
        ),
        (
            '[actuation]\npeak_force_n = 5.0\n[[cycle.segments]]\nkind = "release"\n'
            "duration_s = 1.0",
            "no [actuation] with a [cycle]",
        ),
        (
            '[model]\nrigid_coupling = true\n[[cycle.segments]]\nkind = "release"\n'
            "duration_s = 1.0",
            "rigid_coupling = false",
        ),
        ('[cycle]\nrepeat = "yes"\n[[cycle.segments]]\nkind = "release"', "true or false"),
        (
            '[defects.left]\nactuation_delay_ms = 5.0\n[[cycle.segments]]\nkind = "release"\n'
            "duration_s = 1.0",
            "not represented",
        ),
        (
            '[needs]\noutputs = ["stop_time"]\nlevel = "contact_regime"\n[vehicle]\n',
            "cannot represent the vehicle",
        ),
    ],
)
def test_bad_vehicle_and_cycle_tables_are_refused_in_one_line(extra, says):
    with pytest.raises(BrakeSimError) as info:
        parse_scenario(f'name = "bad"\n{extra}\n', "bad.toml")
    message = str(info.value)
    assert says in message and "\n" not in message


def test_a_repeating_cycle_starts_again_at_its_first_segment():
    """The CHUNKED cycle (12 km/h, stop, hold, release: about 2.5 s a lap) with repeat:
    over 8 s it runs its segments in order lap after lap, never ends, and reaches its
    speed in every lap; without repeat it ends after one lap."""
    text = CHUNKED.replace("duration_s = 4.0", "duration_s = 8.0")
    once = stepper_for(parse_scenario(text)).run(8.0, record_every=DECIMATION)
    assert [s for s, _, _ in _segments(once)] == [0, 1, 2, 3, 4]  # 4: ended
    looped = parse_scenario(text.replace("[cycle]\n", "[cycle]\nrepeat = true\n"))
    assert looped.setup.cycle.repeat
    block = stepper_for(looped).run(8.0, record_every=DECIMATION)
    order = [s for s, _, _ in _segments(block)]
    assert 4 not in order and order[:5] == [0, 1, 2, 3, 0]
    assert order == [k % 4 for k in range(len(order))] and len(order) >= 9  # two laps and more
    kmh = _kmh(block, looped)
    for seg, first, _last in _segments(block):
        if seg == 1:  # each stop starts from the speed its lap reached
            assert kmh[first] == pytest.approx(12.0, rel=2 * SPEED_TOLERANCE)


def test_stepper_refuses_live_actuation_during_a_cycle():
    stepper = stepper_for(parse_scenario(CHUNKED))
    with pytest.raises(BrakeSimError, match="drive cycle commands the brake"):
        stepper.advance(10, actuation_n=(100.0, 100.0))
    assert isinstance(stepper, FixedStepStepper)


def test_a_driven_run_keeps_the_vehicles_columns_whatever_its_needs_ask():
    """[needs] asking only the stop time still records the vehicle's speed, drive, road load,
    their work (the energy books) and the cycle's segment (the phase label)."""
    scenario = parse_scenario(
        'name = "few"\n[needs]\noutputs = ["stop_time"]\n[vehicle]\ngrade_pct = 2.0\n'
    )
    chosen = plan(scenario.needs, model_shoes=scenario.setup.options.shoes)
    assert set(DRIVEN_COLUMNS) <= set(chosen.columns)
    assert "brake_temperature_c" not in chosen.columns  # no thermal state asked
