"""Fixed-step stepper: sample rate and substeps, step limits, live actuation, refusals."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from brake_sim_ros.errors import ParameterError, StepSizeError
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.actuation import Actuation, ForceProfile
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.solvers.fixed_step import (
    MIN_PHYSICS_STEP_S,
    FixedStepStepper,
    substeps_for,
)
from brake_sim_ros.solvers.reference import run_reference
from brake_sim_ros.solvers.stability import rk4_stable_step, step_limit
from brake_sim_ros.stream.build import stepper_for

PERIOD = 1 / 25_600  # the default sample rate


def test_rk4_stability_interval_on_the_real_axis():
    assert rk4_stable_step(-1.0 + 0j) == pytest.approx(2.785293563, rel=1e-6)


def test_substeps_are_the_fewest_whole_ones_within_the_bound():
    assert substeps_for(4e-5, 4e-5) == 1  # at the bound: one step
    assert substeps_for(4e-5, 3.9999e-5) == 2
    assert substeps_for(1e-4, 1e-4 / 3) == 3  # a rounded quotient does not add a substep
    assert substeps_for(1e-4, 0.0334e-4) == 30
    assert substeps_for(1e-4, math.inf) == 1


def test_a_tiny_accuracy_bound_ends_at_once_and_is_refused():
    """A step far below the period once looped for ever (n and n - 1 gave equal quotients);
    the stepper refuses an accuracy bound below the smallest step it takes."""
    assert substeps_for(1e-3, 1e-300) >= math.ceil(1e-3 / 1e-300) - 1  # and returns
    for max_step_s in (1e-300, 0.5 * MIN_PHYSICS_STEP_S):
        with pytest.raises(StepSizeError, match="allowed a physics step of at least"):
            FixedStepStepper(BrakeSetup(), PERIOD, max_step_s=max_step_s)


def test_a_sample_period_above_the_limit_is_split_into_whole_substeps():
    """The sample period is never refused for the step limit: the physics step divides it."""
    setup = BrakeSetup()
    limit = step_limit(setup, 1300.0, scheme="rk4-located").max_step_s
    stepper = FixedStepStepper(setup, 2.5 * limit)
    assert stepper.substeps == 3 and stepper.physics_step_s <= limit
    assert stepper.physics_step_s * 3 == pytest.approx(2.5 * limit, rel=1e-15)
    block = stepper.advance(40)
    assert len(block) == 40 and block.sample_period_s == 2.5 * limit
    np.testing.assert_array_equal(block.time_s, np.arange(40) * (2.5 * limit))
    assert FixedStepStepper(setup, limit).substeps == 1  # exactly at the limit: one step


def test_a_pathological_limit_is_refused_with_the_limit_and_its_reason():
    """A drum of 1e-6 kg m^2 on the coupling: a limit of a few ns, below the smallest step
    the stepper takes, thousands of substeps per sample."""
    params = BrakeParameters().with_overrides({"driveline": {"drum_inertia_kg_m2": 1e-6}})
    setup = BrakeSetup(params=params)
    limit = step_limit(setup, 1300.0, scheme="rk4-located")
    assert limit.max_step_s < MIN_PHYSICS_STEP_S
    with pytest.raises(StepSizeError) as info:
        FixedStepStepper(setup, PERIOD)
    message = str(info.value)
    assert f"at most {limit.max_step_s:.3g} s" in message and limit.reason in message
    assert "substeps per" in message and "\n" not in message


def test_a_step_beyond_the_limit_really_gives_wrong_results():
    """The limit is not decorative: past it RK4 stays bounded but the stop time is wrong."""
    setup = BrakeSetup()
    limit = step_limit(setup, 1300.0).max_step_s
    good = FixedStepStepper(setup, 4e-5)
    good.run(7.5)
    bad = FixedStepStepper(setup, 1.6 * limit, check_step=False)
    bad.run(7.5)
    assert good.stop_time_s is not None
    assert bad.stop_time_s is None or abs(bad.stop_time_s - good.stop_time_s) > 0.01


def test_limit_shrinks_with_actuation_force():
    setup = BrakeSetup()
    assert step_limit(setup, 5000.0).max_step_s < step_limit(setup, 1300.0).max_step_s / 2


@pytest.mark.parametrize("bad", [math.nan, math.inf, -1.0, 1e6])
def test_bad_live_actuation_is_refused_and_changes_nothing(bad):
    stepper = stepper_for(load_scenario("symmetric"))
    stepper.advance(100)
    before = stepper.state
    with pytest.raises(ParameterError, match="actuation force"):
        stepper.advance(10, actuation_n=(bad, 100.0))
    assert np.array_equal(stepper.state, before) and stepper.sample_index == 100
    assert stepper.limit_force_n == 1300.0 and stepper.substeps == 1


def test_live_actuation_takes_effect_between_calls():
    stepper = stepper_for(load_scenario("symmetric"))
    stepper.advance(6144)  # 0.24 s, shoes impacting
    block = stepper.advance(10_000, actuation_n=(1000.0, 0.0))
    assert np.all(block["left_actuation_force_n"] == 1000.0)
    assert np.all(block["right_actuation_force_n"] == 0.0)
    assert block["right_normal_force_n"][-1] == 0.0 and block["left_normal_force_n"][-1] > 1000


def test_live_actuation_above_the_limit_force_takes_more_substeps_not_a_refusal():
    """5000 N on a stepper whose limit was computed for the profile's 1300 N: the limit
    is recomputed for 5000 N and the sample interval split into more substeps; the sample
    grid stays. A reset goes back to the start's substeps, and the same commands give the
    same numbers, bit for bit."""
    scenario = load_scenario("symmetric")

    def run(stepper: FixedStepStepper) -> np.ndarray:
        parts = [stepper.advance(5000).data]
        assert stepper.substeps == 1
        parts.append(stepper.advance(2000, actuation_n=(5000.0, 5000.0)).data)
        assert stepper.limit_force_n == 5000.0
        assert stepper.physics_step_s <= step_limit(stepper.setup, 5000.0).max_step_s
        assert stepper.substeps == 3  # 16.7 us limit in a 39.1 us sample
        parts.append(stepper.advance(3000).data)  # the profile again: the limit stays
        assert stepper.substeps == 3
        return np.concatenate(parts)

    stepper = stepper_for(scenario)
    first = run(stepper)
    np.testing.assert_array_equal(first[:, 0], np.arange(10_000) * PERIOD)
    assert np.all(first[5000:7000, L.COL["left_actuation_force_n"]] == 5000.0)
    stepper.reset()
    assert (stepper.substeps, stepper.limit_force_n) == (1, 1300.0)
    np.testing.assert_array_equal(run(stepper), first)
    with pytest.raises(ParameterError, match="from 0 to 50000 N"):
        stepper.advance(1, actuation_n=(50_001.0, 0.0))


def test_replace_setup_validates_and_keeps_state_on_error():
    s = load_scenario("symmetric")
    stepper = stepper_for(s)
    stepper.advance(100)
    with pytest.raises(ParameterError, match="inside the drum"):
        stepper.replace_setup(BrakeSetup(defects=Defects(left=ShoeDefect(initial_angle_deg=3.0))))
    assert stepper.setup is s.setup
    stepper.replace_setup(BrakeSetup(defects=Defects(left=ShoeDefect(pivot_radius_change_pct=1.0))))
    assert stepper.sample_index == 100
    params = BrakeParameters().with_overrides({"driveline": {"drum_inertia_kg_m2": 1e-6}})
    with pytest.raises(StepSizeError, match="smallest step"):
        stepper.replace_setup(BrakeSetup(params=params))
    assert stepper.setup.params == BrakeParameters() and stepper.substeps == 1


def test_replace_setup_with_a_model_that_needs_a_smaller_step_repicks_the_substeps():
    """Friction smoothed over 5 mm/s (a limit of about 14 us) set mid-run: accepted, with 3
    substeps per 39.1 us sample, on the same sample grid."""
    scenario = load_scenario("symmetric")
    stepper = stepper_for(scenario)
    before = stepper.advance(25_600)  # 1 s
    assert stepper.substeps == 1
    narrow = dataclasses.replace(
        scenario.setup,
        params=scenario.setup.params.with_overrides({"friction": {"smoothing_speed_m_s": 0.005}}),
    )
    stepper.replace_setup(narrow)
    assert stepper.substeps == 3 and stepper.physics_step_s <= stepper.limit.max_step_s
    assert PERIOD / 3 <= stepper.limit.max_step_s < PERIOD / 2  # the fewest whole substeps
    after = stepper.advance(2560)
    assert after.first_index == 25_600 and after.sample_period_s == before.sample_period_s
    np.testing.assert_array_equal(after.time_s, (25_600 + np.arange(2560)) * PERIOD)
    assert np.all(np.isfinite(after.data))
    # a fresh stepper with the change from the start takes the same substeps
    assert stepper_for(dataclasses.replace(scenario, setup=narrow)).substeps == 3


def test_a_substep_change_keeps_the_regime_clock_in_seconds():
    """The kernel's contact-regime bookkeeping counts physics steps since the last contact
    change: a new step rescales that count, so the settling time (50 ms) is kept."""
    scenario = load_scenario("symmetric")
    stepper = stepper_for(scenario)
    stepper.advance(6144)  # 0.24 s: impacting

    def since_s() -> list[float]:
        now = stepper.sample_index * stepper.substeps
        keys = (L.K_LEFT_LAST_CHANGE_STEP, L.K_RIGHT_LAST_CHANGE_STEP)
        return [(now - stepper._kstate[k]) * stepper.physics_step_s for k in keys]

    before = since_s()
    far = ForceProfile((0.0, 0.2, 0.7, 1e6), (0.0, 0.0, 1300.0, 5000.0))  # a 5000 N peak
    stepper.replace_setup(dataclasses.replace(scenario.setup, actuation=Actuation(far, far)))
    assert stepper.substeps == 3
    np.testing.assert_allclose(since_s(), before, atol=stepper.physics_step_s)
    stepper.replace_setup(scenario.setup)  # the limit force stays 5000 N: still 3
    assert stepper.substeps == 3


@pytest.mark.parametrize("dt", [0.0, -1e-5, math.nan, math.inf])
def test_nonsense_sample_period_or_step_bound_is_refused(dt):
    with pytest.raises(StepSizeError, match="allowed a finite step > 0"):
        FixedStepStepper(BrakeSetup(), dt)
    with pytest.raises(StepSizeError, match="max_step_s"):
        FixedStepStepper(BrakeSetup(), PERIOD, max_step_s=dt)


def test_unknown_scheme_is_refused_with_the_allowed_ones():
    with pytest.raises(ParameterError, match="rk4-located"):
        FixedStepStepper(BrakeSetup(), 4e-5, scheme="leapfrog")


@pytest.mark.parametrize("preset", ["balanced", "accurate"])  # 1 and 2 substeps per sample
def test_located_scheme_chunked_equals_one_call(preset):
    s = load_scenario("symmetric").with_solver(preset=preset)
    whole = stepper_for(s)
    assert whole.scheme == "rk4-located"
    data = whole.advance(8192).data  # to 0.32 s: several located onsets and separations
    assert whole.located_switches > 4
    chunked = stepper_for(s)
    parts = [chunked.advance(n).data for n in (1, 5536, 17, 2638)]
    assert np.array_equal(data, np.concatenate(parts))
    assert np.array_equal(stepper_for(s).run(8192 * s.sample_period_s).data, data)


def _state_error_after_impacts(scheme: str, steps: tuple[float, ...]) -> list[float]:
    s = load_scenario("symmetric")
    at = 0.3  # after five impacts of each shoe, between two of them
    ref = run_reference(s.setup, at + 1e-3, sample_times=np.array([at]), rtol=1e-12).samples
    cols = [L.COL[n] for n in ("left_angle_rad", "right_angle_rad", "drum_speed_rad_s")]
    scale = np.array([1e-3, 1e-3, 100.0])
    errors = []
    for dt in steps:
        data = FixedStepStepper(s.setup, dt, scheme=scheme).run(at + 2 * dt).data
        errors.append(np.max(np.abs(data[round(at / dt), cols] - ref.data[0, cols]) / scale))
    return errors


def test_locating_contact_switches_restores_fourth_order():
    """Plain RK4 steps across the Kelvin-Voigt jump at each onset: the local error of such a
    step is O(dt) and the global error first order at best (measured: erratic, about 0 to 1).
    Located switches leave RK4 smooth pieces and a switch instant found to 1e-10 dt, so the
    theory gives order 4; pre-asymptotic effects allow a little less, not less than 3."""
    steps = (4e-5, 2e-5, 1e-5)
    located = _state_error_after_impacts("rk4-located", steps)
    plain = _state_error_after_impacts("rk4", steps)
    order_located = np.polyfit(np.log(steps), np.log(located), 1)[0]
    order_plain = np.polyfit(np.log(steps), np.log(plain), 1)[0]
    assert order_located >= 3.0
    assert order_plain <= 2.0  # the jump is really there: this problem limits plain RK4
    assert located[-1] < plain[-1] / 100


def test_semi_implicit_euler_has_its_own_step_limit():
    setup = BrakeSetup()
    rk4 = step_limit(setup, 1300.0).max_step_s
    euler = step_limit(setup, 1300.0, scheme="semi-implicit-euler").max_step_s
    assert euler < rk4  # explicit in the damping: a smaller stable step than RK4's
    assert FixedStepStepper(setup, 0.95 * euler, scheme="semi-implicit-euler").substeps == 1
    split = FixedStepStepper(setup, 1.05 * euler, scheme="semi-implicit-euler")
    assert split.substeps == 2 and "symplectic Euler" in split.limit.reason
    assert FixedStepStepper(setup, 1.05 * euler, scheme="rk4").substeps == 1
