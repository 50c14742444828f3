"""Fixed-step stepper: step limits, live actuation, refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest

from brake_sim_ros.errors import ParameterError, StepSizeError
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.trajectory import BrakeSetup
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.solvers.stability import rk4_stable_step, step_limit


def test_rk4_stability_interval_on_the_real_axis():
    assert rk4_stable_step(-1.0 + 0j) == pytest.approx(2.785293563, rel=1e-6)


def test_step_above_the_limit_is_refused_with_limit_and_reason():
    setup = BrakeSetup()
    limit = step_limit(setup, 1300.0)
    with pytest.raises(StepSizeError) as info:
        FixedStepStepper(setup, 1.5 * limit.max_step_s)
    message = str(info.value)
    assert f"{limit.max_step_s:.3g}" in message and "friction" in message


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
    s = load_scenario("symmetric")
    stepper = FixedStepStepper(s.setup, s.solver.dt_s)
    stepper.advance(100)
    before = stepper.state
    with pytest.raises(ParameterError, match="actuation force"):
        stepper.advance(10, actuation_n=(bad, 100.0))
    assert np.array_equal(stepper.state, before) and stepper.step_index == 100


def test_live_actuation_takes_effect_between_calls():
    s = load_scenario("symmetric")
    stepper = FixedStepStepper(s.setup, s.solver.dt_s)
    stepper.advance(6000)  # 0.24 s, shoes impacting
    block = stepper.advance(10_000, actuation_n=(1000.0, 0.0))
    assert np.all(block["left_actuation_force_n"] == 1000.0)
    assert np.all(block["right_actuation_force_n"] == 0.0)
    assert block["right_normal_force_n"][-1] == 0.0 and block["left_normal_force_n"][-1] > 1000


def test_replace_setup_validates_and_keeps_state_on_error():
    s = load_scenario("symmetric")
    stepper = FixedStepStepper(s.setup, s.solver.dt_s)
    stepper.advance(100)
    with pytest.raises(ParameterError, match="inside the drum"):
        stepper.replace_setup(BrakeSetup(defects=Defects(left=ShoeDefect(initial_angle_deg=3.0))))
    assert stepper.setup is s.setup
    stepper.replace_setup(BrakeSetup(defects=Defects(left=ShoeDefect(pivot_radius_change_pct=1.0))))
    assert stepper.step_index == 100


@pytest.mark.parametrize("dt", [0.0, -1e-5, math.nan, math.inf])
def test_nonsense_step_is_refused(dt):
    with pytest.raises(StepSizeError, match="allowed a finite step > 0"):
        FixedStepStepper(BrakeSetup(), dt)
