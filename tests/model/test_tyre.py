"""The service brake's tyre (model/tyre.py): the lumped LuGre law with the road's friction
limit, its parameters and the scenario's ``road_friction``. Each figure a test expects is
computed by hand from the documented formulas and the parameters (written out below),
never read off a run."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from numba import njit

from brake_sim_ros.analysis.energy import energy_balance
from brake_sim_ros.errors import ParameterError, ScenarioError
from brake_sim_ros.model import layout as L
from brake_sim_ros.model import tyre
from brake_sim_ros.model.assembly import ModelOptions, pack
from brake_sim_ros.model.cycle import pack_drive
from brake_sim_ros.model.defects import Defects
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.model.service_parameters import DRY_ROAD_FRICTION, TyreParameters
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.solvers.stability import step_limit
from brake_sim_ros.stream.build import stepper_for

G = 9.80665
RADIUS_M = (100.0 / 3.6) / 103.5  # the default rolling radius, 0.268384 m
LOAD_N = 17.1 / RADIUS_M**2 * G  # 237.40 kg times g: 2328.10 N
# the default tyre on the dry road: sliding 0.8, peak 1.2, Stribeck 3 m/s, exponent 1,
# sigma0 40 1/m, sigma1 2 sqrt(40 / g) = 4.03924 s/m, sigma2 0
SIGMA0 = 40.0
SIGMA1 = 2.0 * math.sqrt(40.0 / G)
DRY = (SIGMA0, SIGMA1, 0.0, 0.8, 1.2, 3.0, 1.0)


def _service_packed(road_friction: float | None = None) -> np.ndarray:
    text = 'name = "t"\nbrake = "service"\n'
    if road_friction is not None:
        text += f"road_friction = {road_friction}\n"
    setup = parse_scenario(text).setup
    return pack(setup.params, setup.defects, setup.options)


def test_the_stribeck_curve_matches_hand_values():
    curve = tyre.stribeck.py_func
    assert curve(0.0, 0.8, 1.2, 3.0, 1.0) == pytest.approx(1.2, rel=1e-15)
    # 0.8 + 0.4 / e, either sign of slip
    assert curve(-3.0, 0.8, 1.2, 3.0, 1.0) == pytest.approx(0.9471518, rel=1e-7)
    assert curve(3.0, 0.8, 1.2, 3.0, 1.0) == pytest.approx(0.9471518, rel=1e-7)
    # a locked tyre at 100 km/h: 0.8 + 0.4 exp(-9.259) = 0.8000381
    assert curve(-100.0 / 3.6, 0.8, 1.2, 3.0, 1.0) == pytest.approx(0.8000381, rel=1e-7)
    # exponent 0.5 at 12 m/s from 12.5: 0.5 + 0.4 exp(-sqrt(0.96)) = 0.6501551
    assert curve(12.0, 0.5, 0.9, 12.5, 0.5) == pytest.approx(0.6501551, rel=1e-7)


@pytest.mark.parametrize("slip", [-27.0, -3.0, -0.5, 0.2, 5.0])
def test_the_steady_slip_law_is_the_curve_and_its_deflection_rests_there(slip):
    law = tyre.law.py_func
    g = 0.8 + 0.4 * math.exp(-abs(slip) / 3.0)
    steady = math.copysign(g, slip) / SIGMA0
    ratio, rate = law(steady, slip, *DRY)
    assert rate == pytest.approx(0.0, abs=1e-12 * abs(slip))
    assert ratio == pytest.approx(math.copysign(g, slip), rel=1e-12)
    # from rest the tread deflects at the slip speed, the damper alone pushing
    ratio0, rate0 = law(0.0, slip, *DRY)
    assert rate0 == slip
    assert ratio0 == pytest.approx(SIGMA1 * slip, rel=1e-12)
    # integrated at a fixed slip, the deflection relaxes to the steady one with the rate
    # sigma0 |v| / g: z(t) = z_ss (1 - exp(-sigma0 |v| t / g))
    tau = g / (SIGMA0 * abs(slip))
    z, dt = 0.0, tau / 2000.0
    for _ in range(2000):  # RK4 on the law itself, one time constant
        k1 = law(z, slip, *DRY)[1]
        k2 = law(z + 0.5 * dt * k1, slip, *DRY)[1]
        k3 = law(z + 0.5 * dt * k2, slip, *DRY)[1]
        k4 = law(z + dt * k3, slip, *DRY)[1]
        z += dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    assert z == pytest.approx(steady * (1.0 - math.exp(-1.0)), rel=1e-9)


def test_a_held_tyre_is_a_spring_and_damper_and_holds_its_deflection():
    law = tyre.law.py_func
    for z in (-0.02, 0.0, 0.01):
        ratio, rate = law(z, 0.0, *DRY)
        assert rate == 0.0 and ratio == SIGMA0 * z
    # small slip speeds: the tread follows the slip (dz/dt ~ v) below a tenth of the peak
    ratio, rate = law(0.001, 0.01, *DRY)
    g = 0.8 + 0.4 * math.exp(-0.01 / 3.0)
    assert rate == pytest.approx(0.01 * (1.0 - SIGMA0 * 0.001 / g), rel=1e-12)
    assert rate == pytest.approx(0.00967, abs=1e-5)


def test_the_packed_tyre_couples_drum_and_flywheel_by_hand():
    p = _service_packed()
    assert tyre.wheel_load.py_func(p) == pytest.approx(LOAD_N, rel=1e-12)
    assert tyre.wheel_load.py_func(p) == pytest.approx(2328.10, abs=0.01)
    assert tyre.torsional_stiffness.py_func(p) == pytest.approx(SIGMA0 * LOAD_N * RADIUS_M**2)
    assert tyre.grip_torque.py_func(p) == pytest.approx(1.2 * LOAD_N * RADIUS_M)
    # held (equal speeds), tread 10 mm back: the road pushes the tyre forward with
    # sigma0 Fz z = -931.24 N along the slip; the drum takes -R F, no loss
    torque, power, rate = tyre.coupling.py_func(p, -0.01, 50.0, 50.0)
    assert torque == pytest.approx(RADIUS_M * SIGMA0 * LOAD_N * 0.01, rel=1e-12)
    assert torque == pytest.approx(249.93, abs=0.01)
    assert power == 0.0 and rate == 0.0
    # a locked wheel sliding at 100 km/h with its steady deflection: the drum is pushed
    # forward by R Fz g(v) (g = 0.8000381), all the power F v is lost
    v = 100.0 / 3.6
    g = 0.8 + 0.4 * math.exp(-v / 3.0)
    torque, power, rate = tyre.coupling.py_func(p, -g / SIGMA0, v / RADIUS_M, 0.0)
    assert rate == pytest.approx(0.0, abs=1e-12)
    assert torque == pytest.approx(RADIUS_M * LOAD_N * g, rel=1e-12)
    assert power == pytest.approx(LOAD_N * g * v, rel=1e-12)
    loss = tyre.loss_power.py_func(p, -g / SIGMA0, rate, power)
    assert loss == pytest.approx(LOAD_N * g * v, rel=1e-9)
    # the power the tyre takes is what the rotors lose (the drum takes torque, the
    # flywheel -torque); the tread stores sigma0 Fz z dz/dt of it, the rest is lost
    for z, wf, wd in ((-0.005, 80.0, 70.0), (0.01, 10.0, 0.0), (-0.02, 5.0, 5.5)):
        torque, power, rate = tyre.coupling.py_func(p, z, wf, wd)
        assert power == pytest.approx(-torque * wd + torque * wf, rel=1e-12, abs=1e-9)
        stored = SIGMA0 * LOAD_N * z * rate
        loss = tyre.loss_power.py_func(p, z, rate, power)
        assert loss == pytest.approx(power - stored, rel=1e-12, abs=1e-9)
        assert loss > 0.0  # sliding or rolling against its tread, the tyre loses
    # the load follows the flywheel inertia in force (a cycle's load factor)
    heavy = p.copy()
    heavy[L.P_FLYWHEEL_INERTIA] *= 2.0
    assert tyre.wheel_load.py_func(heavy) == pytest.approx(2.0 * LOAD_N, rel=1e-12)
    z = np.array([0.0, -0.01, 0.02])
    energies = tyre.stored_energy_rows(p, z, np.array([17.1, 17.1, 34.2]))
    expected = 0.5 * SIGMA0 * LOAD_N * z**2 * np.array([1.0, 1.0, 2.0])
    assert np.allclose(energies, expected, rtol=1e-12)


def test_the_defaults_are_the_dry_road_with_a_critically_damped_presliding_mode():
    t = TyreParameters()
    assert t.road_friction == DRY_ROAD_FRICTION == 0.8
    assert t.peak_friction == pytest.approx(1.2)
    assert t.presliding_damping_s_per_m == pytest.approx(4.03924, abs=1e-5)
    # the vehicle on its held tyre: m x'' + sigma1 m g x' + sigma0 m g x = 0, ratio 1
    omega = math.sqrt(t.presliding_stiffness_per_m * G)
    zeta = t.presliding_damping_s_per_m * G / (2.0 * omega)
    assert zeta == pytest.approx(1.0, rel=1e-12)
    assert BrakeParameters.of_brake("service").service.tyre == t
    assert BrakeParameters.of_brake("study").service is None


def test_the_scenario_sets_the_road_friction_and_packs_it():
    wet = _service_packed(0.5)
    assert wet[L.P_TYRE_SLIDING] == 0.5 and wet[L.P_TYRE_PEAK] == pytest.approx(0.75)
    dry = _service_packed()
    assert dry[L.P_TYRE_SLIDING] == 0.8 and dry[L.P_TYRE_PEAK] == pytest.approx(1.2)
    assert dry[L.P_WHEEL_RADIUS] == RADIUS_M
    # a vehicle's rolling radius replaces the default one
    text = 'name = "t"\nbrake = "service"\n[vehicle]\nwheel_radius_m = 0.3\n'
    setup = parse_scenario(text).setup
    p = pack(setup.params, setup.defects, setup.options)
    pack_drive(p, setup)
    assert p[L.P_WHEEL_RADIUS] == 0.3
    # the study brake packs no tyre
    study = pack(BrakeParameters(), Defects())
    assert study[L.P_TYRE_STIFFNESS] == 0.0 and study[L.P_WHEEL_RADIUS] == 0.0


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("road_friction = 0.5\n", 'only with brake = "service"'),
        ('brake = "service"\nroad_friction = 0.0\n', ">= 0.05 and <= 1.2"),
        ('brake = "service"\nroad_friction = 2.5\n', ">= 0.05 and <= 1.2"),
        ('brake = "service"\nroad_friction = "wet"\n', "a number"),
        ('brake = "service"\nroad_friction = nan\n', "road_friction"),
        ('brake = "service"\n[model]\nrigid_coupling = true\n', "rigid_coupling"),
    ],
)
def test_a_bad_road_or_a_rigid_service_coupling_is_refused_in_one_line(text, words):
    with pytest.raises(ScenarioError) as info:
        parse_scenario(f'name = "t"\n{text}')
    message = str(info.value)
    assert words in message and "\n" not in message


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("road_friction", 0.01),
        ("peak_ratio", 0.9),
        ("stribeck_speed_m_s", 0.0),
        ("presliding_stiffness_per_m", -1.0),
        ("presliding_damping_ratio", 0.0),
        ("viscous_s_per_m", math.inf),
    ],
)
def test_tyre_parameters_out_of_range_are_refused(field, value):
    with pytest.raises(ParameterError, match=field):
        TyreParameters(**{field: value})


def test_a_rigid_coupling_on_the_service_brake_is_refused_by_the_packing():
    params = BrakeParameters.of_brake("service")
    with pytest.raises(ParameterError, match="rigid_coupling"):
        pack(params, Defects(), ModelOptions(rigid_coupling=True))


# --- the tyre in the service brake's runs ------------------------------------------------

V0_M_S = 100.0 / 3.6  # the default start, 103.5 rad/s on the default rolling radius
STRIBECK_M_S = 3.0


def _run(text: str):
    scenario = parse_scenario(text)
    stepper = stepper_for(scenario)
    return scenario, stepper, stepper.run(scenario.duration_s)


def _panic(road_friction: float, duration_s: float, contact: str = "point") -> str:
    """20 kN per shoe in 50 ms from 100 km/h: far past what the tyre holds; on the service
    brake's point contact or its lining over the arc (``contact`` "arc")."""
    return (
        f'name = "panic"\nbrake = "service"\nroad_friction = {road_friction}\n'
        f"duration_s = {duration_s}\n"
        "[actuation]\npeak_force_n = 20000.0\nstart_s = 0.05\nfull_s = 0.1\n"
        + ("[parameters.service]\ndistributed_lining = true\n" if contact == "arc" else "")
    )


def _hand_slide_time_s(v_lock: float, sliding: float, peak: float) -> float:
    """Time a locked tyre takes to stop the vehicle from ``v_lock`` (m/s) on the curve
    ``g(v) = a + b exp(-v / v_s)`` (sigma2 = 0): ``dv/dt = -g(v) g0``, so
    ``t = v_s / (a g0) [ln(a exp(v_lock / v_s) + b) - ln(a + b)]``."""
    a, b, s = sliding, peak - sliding, STRIBECK_M_S
    return s / (a * G) * (math.log(a * math.exp(v_lock / s) + b) - math.log(a + b))


def _first_rest(time_s: np.ndarray, speed: np.ndarray) -> float:
    """The first instant (s) the vehicle's speed reaches 0, interpolated between samples."""
    i = int(np.argmax(speed <= 0.0))
    assert speed[i] <= 0.0 < speed[i - 1]
    return float(
        time_s[i - 1] + speed[i - 1] / (speed[i - 1] - speed[i]) * (time_s[i] - time_s[i - 1])
    )


@pytest.fixture(
    scope="module",
    params=[
        (DRY_ROAD_FRICTION, 4.2, "point"),
        (0.5, 6.6, "point"),
        (DRY_ROAD_FRICTION, 4.2, "arc"),
    ],
    ids=["dry", "wet", "dry-arc"],
)
def panic(request):
    road, duration, contact = request.param
    return road, *_run(_panic(road, duration, contact))


def test_a_locked_wheel_skids_and_the_car_decelerates_at_the_road_friction(panic):
    """The wheel locks within the application; the car then slides to rest at about mu g
    (within 10 %), in the time the Stribeck curve gives by hand (within 2 %), and at every
    sample of the developed slide the vehicle decelerates at ``g(v) g0`` (the flywheel's
    equation with its tyre term, within 1 %)."""
    road, _scenario, stepper, block = panic
    lock = stepper.wheel_lock_time_s
    assert lock is not None and lock < 0.2
    t = block.time_s
    v = block["flywheel_speed_rad_s"] * RADIUS_M
    v_lock = float(np.interp(lock, t, v))
    rest = _first_rest(t, v)
    mean = v_lock / (rest - lock)
    assert mean == pytest.approx(road * G, rel=0.10)
    assert rest - lock == pytest.approx(_hand_slide_time_s(v_lock, road, 1.5 * road), rel=0.02)
    # the developed slide: the deflection settled (0.1 s after the lock) where the curve is
    # flat (above 3 v_s; lower, the tread's deflection follows the rising curve and its
    # damper adds sigma1 dz/dt, 5 % at 1 m/s on the dry road)
    dt = block.sample_period_s
    accel = (v[2:] - v[:-2]) / (2.0 * dt)
    mid, tm = v[1:-1], t[1:-1]
    slide = (tm > lock + 0.1) & (mid > 3.0 * STRIBECK_M_S)
    expected = -G * (road + 0.5 * road * np.exp(-mid[slide] / STRIBECK_M_S))
    assert slide.sum() > 10_000
    assert np.allclose(accel[slide], expected, rtol=0.01)
    assert np.all(block["drum_speed_rad_s"][tm.searchsorted(lock + 0.01) :] == 0.0)


def test_after_the_stop_the_car_does_not_rock(panic):
    """Once at rest, the vehicle moves back only as its tread's deflection (at most the
    peak's, ``z0 = mu_s / sigma0``) relaxes through the critically damped presliding mode:
    a backward speed of at most ``z0 omega / e`` (omega = sqrt(sigma0 g) = 19.8 rad/s;
    0.22 m/s, 0.8 % of the start speed, on the dry road), and never forward again (the
    study's coupling rocks the car at up to 24 % of it after such a stop)."""
    road, _scenario, stepper, block = panic
    t = block.time_s
    v = block["flywheel_speed_rad_s"] * RADIUS_M
    after = t > _first_rest(t, v)
    z0 = 1.5 * road / SIGMA0
    bound = z0 * math.sqrt(SIGMA0 * G) / math.e
    assert v[after].min() >= -bound
    assert v[after].max() < 1e-3
    assert stepper.stop_time_s is not None and stepper.stop_time_s < t[-1] - 0.5


def test_energy_closes_through_the_tyre(panic):
    """Kinetic, contact, spring and stop energy, the cylinders' work and every loss with
    the tyre's work (what the rotors gave it) close to 1e-6 of the turnover."""
    _road, scenario, stepper, block = panic
    books = energy_balance(block, scenario.setup.params, packed=stepper.packed_parameters)
    assert abs(books.residual_j) < 1e-6 * books.turnover_j
    # the car's kinetic energy went into the tyre's slide, not the brake: the brake held
    work = block["coupling_damper_loss_j"][-1] - block["coupling_damper_loss_j"][0]
    assert work > 0.9 * books.stored_start_j


def test_a_gentle_stop_is_not_limited_by_the_tyre():
    """The symmetric scenario's force on the service brake (0.43 g): the tyre grips (its
    slip speed stays below 5 cm/s), the wheel locks only as the car comes to rest, and the
    stop takes the same time on a wet road as on a dry one (to 0.1 %); no rocking after."""
    rests = []
    for road in (DRY_ROAD_FRICTION, 0.5):
        text = f'name = "gentle"\nbrake = "service"\nroad_friction = {road}\nduration_s = 7.5\n'
        _scenario, stepper, block = _run(text)
        t = block.time_s
        v = block["flywheel_speed_rad_s"] * RADIUS_M
        rest = _first_rest(t, v)
        rolling = t < rest - 0.05
        slip = RADIUS_M * (block["drum_speed_rad_s"] - block["flywheel_speed_rad_s"])
        assert np.abs(slip[rolling]).max() < 0.05
        assert stepper.wheel_lock_time_s == pytest.approx(rest, abs=0.01)
        after = t > rest
        assert v[after].min() > -0.2 and v[after].max() < 1e-3
        rests.append(rest)
    assert rests[1] == pytest.approx(rests[0], rel=1e-3)


def test_the_step_limit_sees_the_tyres_presliding_damper():
    """A tyre damped ten times critically: the drum rolling on its tread has the stiff
    root of ``s^2 + c s / I_red + k / I_red`` with ``c = sigma1 Fz R^2`` and ``k = sigma0
    Fz R^2`` (I_red: drum and flywheel in series), 1.66e5 1/s, above every other mode;
    the step limit finds it."""
    base = BrakeParameters.of_brake("service")
    tyre_params = dataclasses.replace(base.service.tyre, presliding_damping_ratio=10.0)
    params = dataclasses.replace(base, service=dataclasses.replace(base.service, tyre=tyre_params))
    setup = BrakeSetup(params=params)
    limit = step_limit(setup, setup.peak_force_n)
    i_red = 17.1 * 0.041 / (17.1 + 0.041)
    c = tyre_params.presliding_damping_s_per_m * LOAD_N * RADIUS_M**2 / i_red
    k = SIGMA0 * LOAD_N * RADIUS_M**2 / i_red
    stiff = 0.5 * (c + math.sqrt(c * c - 4.0 * k))
    assert stiff == pytest.approx(1.656e5, rel=1e-3)
    # the drum sliding on the shoes at the lock speed adds the friction's viscous slope to
    # the tread's damper: at least the tyre's root, at most it plus the default's stiffest
    default = step_limit(BrakeSetup(params=base), setup.peak_force_n)
    assert default.stiffest_rate_per_s < stiff / 2.0
    assert stiff <= limit.stiffest_rate_per_s <= stiff + default.stiffest_rate_per_s
    assert limit.stability_step_s < 2.8 / stiff < default.stability_step_s


def test_a_run_may_draw_its_road_and_the_study_brake_refuses_one():
    """``[conditions] road_friction``: each run draws its road within the range (the
    drawn value packed as the tyre's sliding friction, its peak 1.5 times it); on the
    study brake the range is refused in one line."""
    text = 'name = "t"\nbrake = "service"\n[conditions]\nroad_friction = [0.4, 0.6]\n'
    scenario = parse_scenario(text)
    seen = set()
    for seed in range(4):
        run = scenario.with_unit(seed=seed)
        drawn = dict(run.conditions)["road_friction"]
        assert 0.4 <= drawn <= 0.6
        p = pack(run.setup.params, run.setup.defects, run.setup.options)
        assert p[L.P_TYRE_SLIDING] == drawn
        assert p[L.P_TYRE_PEAK] == pytest.approx(1.5 * drawn, rel=1e-15)
        seen.add(drawn)
    assert len(seen) == 4
    with pytest.raises(ScenarioError) as info:
        parse_scenario('name = "t"\n[conditions]\nroad_friction = [0.4, 0.6]\n')
    assert "study brake has no tyre" in str(info.value) and "\n" not in str(info.value)
    with pytest.raises(ScenarioError, match="road_friction"):
        parse_scenario('name = "t"\nbrake = "service"\n[conditions]\nroad_friction = [0.0, 2.0]\n')


@njit(error_model="numpy")
def _stribeck_rows(slips, sliding, peak, speed, exponent):
    """``tyre.stribeck`` and the curve written with the power (``|v / v_s| ** a``, as it
    was before the exponential skipped it) at each slip speed, compiled as the kernel is."""
    fast, powered = np.empty(slips.shape[0]), np.empty(slips.shape[0])
    for i in range(slips.shape[0]):
        v = slips[i]
        fast[i] = tyre.stribeck(v, sliding, peak, speed, exponent)
        shape = abs(v / speed) ** exponent
        powered[i] = sliding + (peak - sliding) * math.exp(-shape)
    return fast, powered


@njit(error_model="numpy")
def _unit_powers(xs):
    out = np.empty(xs.shape[0])
    for i in range(xs.shape[0]):
        out[i] = xs[i] ** 1.0
    return out


def test_the_exponential_stribeck_curve_skips_the_power_with_the_same_bits():
    """The default exponent 1 takes ``|v / v_s|`` itself: the compiled power returns its
    base for exponent 1 (every power of two and its neighbours, where a rounding would
    show first, and a million others), so the curve has the same bits as with the power,
    here on 200,000 slip speeds from 1e-9 to 60 m/s; another exponent still takes it."""
    powers = np.ldexp(1.0, np.arange(-1074, 1024))
    rng = np.random.default_rng(7)
    xs = np.concatenate(
        [powers, np.nextafter(powers, 0.0), np.nextafter(powers, np.inf), rng.random(10**6)]
    )
    assert _unit_powers(xs).tobytes() == xs.tobytes()
    slips = np.concatenate(
        [[0.0, -0.0], rng.choice([-1.0, 1.0], 200_000) * np.geomspace(1e-9, 60.0, 200_000)]
    )
    for exponent in (1.0, 1.5):
        fast, powered = _stribeck_rows(slips, 0.8 / 1.5, 0.8, 3.0, exponent)
        assert fast.tobytes() == powered.tobytes(), exponent
