"""The brake's thermal state (model/thermal.py): heat books, cooling, fade, and its inputs."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.fleet.conditions import apply as apply_conditions
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.actuation import Actuation, ForceProfile
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.model.thermal import FADE, Thermal
from brake_sim_ros.scenarios import load_scenario, parse_scenario
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.stream.build import stepper_for
from brake_sim_ros.stream.run import run_scenario

STEP = 1.0 / 25600.0
NO_COOLING = Thermal(cooling_w_k=0.0, cooling_w_k_per_m_s=0.0)


def _published(thermal: Thermal | None, seconds: float = 7.5):
    """The published stop (100 km/h, the ramp), through the lock to rest."""
    stepper = FixedStepStepper(BrakeSetup(thermal=thermal), STEP)
    return stepper, stepper.run(seconds)


def test_the_heat_the_brake_takes_is_its_friction_work_and_the_locks_loss():
    """No cooling: C (T - T0) = friction work + lock loss, through impacts, sliding, the lock
    and standstill (the lock's kinetic energy goes into the brake at the stick instant)."""
    stepper, block = _published(NO_COOLING)
    assert stepper.stop_time_s is not None and block["lock_loss_j"][-1] > 0.0
    y = stepper.state
    heat = NO_COOLING.heat_capacity_j_k * (y[L.Y_BRAKE_TEMPERATURE] - NO_COOLING.start_c)
    books = y[L.Y_FRICTION_WORK] + stepper._fstate[L.F_LOCK_LOSS]
    assert heat == pytest.approx(books, rel=1e-12)
    # and at every recorded sample before the lock, from the recorded columns
    rows = block["lock_loss_j"] == 0.0
    heat_t = NO_COOLING.heat_capacity_j_k * (block["brake_temperature_c"][rows] - 20.0)
    np.testing.assert_allclose(heat_t, block["friction_work_j"][rows], rtol=1e-11, atol=1e-9)
    # a stop of the published car heats 8 kg of cast iron by about 25 K
    assert 20.0 < y[L.Y_BRAKE_TEMPERATURE] - 20.0 < 30.0


def test_a_brake_below_the_fade_onset_moves_exactly_as_one_without_the_state():
    _, held = _published(None)
    _, hot = _published(Thermal())
    assert hot["brake_temperature_c"].max() < FADE.onset_c
    motion = [c for c in L.COLUMNS if c != "brake_temperature_c"]
    for name in motion:
        np.testing.assert_array_equal(hot[name], held[name], err_msg=name)
    assert np.all(held["brake_temperature_c"] == 20.0)


def _coasting(thermal: Thermal, speed_rad_s: float, seconds: float):
    """The brake not applied (no actuation), the rotor coasting at ``speed_rad_s``."""
    idle = ForceProfile((0.0, 1.0), (0.0, 0.0))
    setup = BrakeSetup(actuation=Actuation(idle, idle), thermal=thermal)
    params = setup.params
    driveline = dataclasses.replace(params.driveline, initial_speed_rad_s=speed_rad_s)
    setup = dataclasses.replace(setup, params=dataclasses.replace(params, driveline=driveline))
    return FixedStepStepper(setup, STEP).run(seconds, record_every=256)


@pytest.mark.parametrize("speed_rad_s", [0.0, 80.0])
def test_a_brake_not_applied_cools_exponentially_to_the_air(speed_rad_s):
    """T(t) = T_air + (T0 - T_air) exp(-(h0 + hv v) t / C), v the vehicle speed."""
    thermal = Thermal(
        heat_capacity_j_k=8.0,
        cooling_w_k=5.0,
        cooling_w_k_per_m_s=0.5,
        ambient_c=10.0,
        initial_c=300.0,
    )
    block = _coasting(thermal, speed_rad_s, 2.0)
    assert block["friction_work_j"][-1] == 0.0
    v = speed_rad_s * (100.0 / 3.6 / 103.5)  # the published wheel radius
    rate = (5.0 + 0.5 * v) / 8.0
    expected = 10.0 + 290.0 * np.exp(-rate * block.time_s)
    np.testing.assert_allclose(block["brake_temperature_c"], expected, rtol=1e-10)
    assert block["brake_temperature_c"][-1] < 300.0 * math.exp(-1.0)  # it did cool, a lot


def test_the_shoes_friction_follows_the_fade_law_at_the_recorded_temperature():
    """While sliding, Ff / (Fn tanh(v / v_s)) = mu x fade(T), T the sample's temperature:
    a hot brake that cools through the fade band (full fade, the linear part, none)."""
    thermal = Thermal(heat_capacity_j_k=1000.0, cooling_w_k=1500.0, initial_c=600.0)
    stepper, block = _published(thermal, 1.5)
    mu = stepper.setup.params.friction.coefficient
    vs = stepper.setup.params.friction.smoothing_speed_m_s
    temperature = block["brake_temperature_c"]
    assert temperature.max() > FADE.full_c and temperature.min() < FADE.onset_c
    for side in ("left", "right"):
        fn = block[f"{side}_normal_force_n"]
        sliding = (fn > 10.0) & (block[f"{side}_sliding_speed_m_s"] > 1.0)
        assert sliding.sum() > 1000
        felt = block[f"{side}_friction_force_n"][sliding] / (
            fn[sliding] * np.tanh(block[f"{side}_sliding_speed_m_s"][sliding] / vs)
        )
        law = mu * np.array([FADE.ratio(t) for t in temperature[sliding]])
        np.testing.assert_allclose(felt, law, rtol=1e-12)
        assert law.min() == mu * FADE.full_ratio and law.max() == mu


def test_a_brake_held_above_full_fade_equals_the_held_hot_brake_bit_for_bit():
    """A thermal state that stays above full fade brakes as the per-run hot brake of the
    conditions does (both at half friction): the motion is the same, bit for bit."""
    heavy = Thermal(heat_capacity_j_k=1.0e6, initial_c=500.0)
    _, hot = _published(heavy, 4.0)
    assert hot["brake_temperature_c"].min() > FADE.full_c
    held = apply_conditions(BrakeSetup(), {"brake_temperature_c": 500.0})
    block = FixedStepStepper(held, STEP).run(4.0)
    assert np.all(block["brake_temperature_c"] == 500.0)  # the held temperature is recorded
    for name in (c for c in L.COLUMNS if c != "brake_temperature_c"):
        np.testing.assert_array_equal(hot[name], block[name], err_msg=name)


def test_conditions_set_the_thermal_states_start_and_air():
    setup = BrakeSetup(thermal=Thermal(ambient_c=15.0))
    drawn = apply_conditions(setup, {"brake_temperature_c": 120.0, "ambient_temperature_c": -5.0})
    assert drawn.thermal == Thermal(ambient_c=-5.0, initial_c=120.0)
    assert drawn.params == setup.params  # the state fades the friction, not the draw
    cold = apply_conditions(setup, {"ambient_temperature_c": 30.0})
    assert cold.thermal.start_c == 30.0  # a brake drawn no temperature starts at the air's


FADING_DESCENT = """
name = "fading"
duration_s = 14.0
sample_rate_hz = 5120.0
[parameters.driveline]
initial_speed_rad_s = 72.45
[vehicle]
grade_pct = -10.0
[thermal]
heat_capacity_j_k = 400.0
initial_c = 235.0
[cycle]
max_force_n = 3000.0
[[cycle.segments]]
kind = "drag"
kmh = 70.0
duration_s = 20.0
"""


def test_on_a_descent_the_brake_heats_and_the_drag_force_rises_as_the_linings_fade():
    scenario = parse_scenario(FADING_DESCENT)
    block = stepper_for(scenario).run(scenario.duration_s, record_every=64)
    t, temperature = block.time_s, block["brake_temperature_c"]
    force = block["left_actuation_force_n"]
    steady = t > 4.0  # the controller has settled on the speed
    assert np.all(np.diff(temperature[steady]) > 0.0)  # friction heats faster than air cools
    onset = t[np.argmax(temperature > FADE.onset_c)]
    assert 4.0 < onset < 10.0
    before = force[(t > onset - 1.0) & (t < onset)].mean()
    after = force[t > t[-1] - 1.0].mean()
    ratio = FADE.ratio(temperature[-1])
    assert ratio < 0.85
    # the torque to hold the speed is the same, the friction lower: the force rises, by
    # about the fade (the self-servo of the leading shoe makes it a little less)
    assert 0.8 / ratio < after / before < 1.0 / ratio


def test_the_built_in_descent_starts_hot_and_carries_the_state():
    scenario = load_scenario("downhill_fade")
    assert scenario.setup.thermal is not None and scenario.setup.thermal.start_c == 240.0
    block = stepper_for(scenario).run(0.01)
    assert block["brake_temperature_c"][0] == 240.0


@pytest.mark.parametrize(
    "extra, says",
    [
        ("[thermal]\nheat_capacity_j_k = 0.0", "thermal.heat_capacity_j_k"),
        ("[thermal]\ninitial_c = 2000.0", "thermal.initial_c"),
        ('[thermal]\nambient_c = "warm"', "a number"),
        ("[thermal]\nemissivity = 0.8", "emissivity"),
        ("thermal = 3", "thermal"),
        (
            '[thermal]\n[needs]\noutputs = ["stop_time"]\nlevel = "contact_regime"',
            "thermal state",
        ),
        ('duration_s = 0.01\n[thermal]\n[solver]\nmethod = "reference"', "no thermal state"),
    ],
)
def test_bad_thermal_tables_are_refused_in_one_line(extra, says):
    with pytest.raises(BrakeSimError) as info:
        run_scenario(parse_scenario(f'name = "bad"\n{extra}\n', "bad.toml"))
    message = str(info.value)
    assert says in message and "\n" not in message
