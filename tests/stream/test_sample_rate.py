"""The output sample rate belongs to the scenario: every built-in scenario, every defect in
the documented ranges and every preset give the scenario's rate; only the physics step (the
substeps per sample) follows the step limit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.scenarios import builtin_names, load_scenario, parse_scenario
from brake_sim_ros.scenarios.types import DEFAULT_SAMPLE_RATE_HZ
from brake_sim_ros.solvers.presets import PRESETS
from brake_sim_ros.stream.build import stepper_for
from brake_sim_ros.stream.run import run_scenario

PERIOD = 1 / DEFAULT_SAMPLE_RATE_HZ

# The defects of the study's cases and around them, per shoe: pivot radius -3 to +3 %
# (each moves the step limit: 55 to 71 us), initial angle -3 to +1 deg (more lets the
# lining start inside the drum), actuation share 0.3 to 0.7.
DEFECTS = [
    *(
        Defects(**{side: ShoeDefect(pivot_radius_change_pct=pct)})
        for side in ("left", "right")
        for pct in (-3.0, -2.0, -1.0, -0.5, 1.0, 3.0)
    ),
    *(
        Defects(**{side: ShoeDefect(initial_angle_deg=deg)})
        for side in ("left", "right")
        for deg in (-3.0, -1.0, 1.0)
    ),
    *(
        Defects(left=ShoeDefect(actuation_share=s), right=ShoeDefect(actuation_share=1 - s))
        for s in (0.3, 0.45, 0.55, 0.7)
    ),
    Defects(
        left=ShoeDefect(pivot_radius_change_pct=-3.0, actuation_share=0.7),
        right=ShoeDefect(initial_angle_deg=-2.0, actuation_share=0.3),
    ),
]


def _check_rule(stepper, max_step_s: float) -> None:
    """The physics step is the largest that divides the sample interval a whole number of
    times within both the preset's largest step and the step limit."""
    assert stepper.sample_period_s == PERIOD
    bound = min(stepper.limit.max_step_s, max_step_s)
    assert stepper.physics_step_s <= bound
    assert stepper.substeps == 1 or PERIOD / (stepper.substeps - 1) > bound
    assert stepper.substeps * stepper.physics_step_s == pytest.approx(PERIOD, rel=1e-15)


@pytest.mark.parametrize("preset", sorted(PRESETS))
@pytest.mark.parametrize("name", builtin_names())
def test_every_builtin_scenario_at_every_preset_samples_the_scenarios_rate(name, preset):
    scenario = load_scenario(name).with_solver(preset=preset)
    result = run_scenario(scenario, duration_s=0.02)
    assert result.samples.sample_period_s == PERIOD
    np.testing.assert_array_equal(result.samples.time_s, np.arange(512) * PERIOD)
    stepper = stepper_for(scenario)
    _check_rule(stepper, PRESETS[preset].max_step_s)
    assert result.n_steps == 512 * stepper.substeps


@pytest.mark.parametrize("preset", sorted(PRESETS))
def test_every_defect_in_the_documented_range_samples_the_scenarios_rate(preset):
    base = load_scenario("symmetric").with_solver(preset=preset)
    limits = set()
    for defects in DEFECTS:
        stepper = stepper_for(base.with_defects(defects))
        _check_rule(stepper, PRESETS[preset].max_step_s)
        block = stepper.advance(64)
        np.testing.assert_array_equal(block.time_s, np.arange(64) * PERIOD)
        assert np.all(np.isfinite(block.data))
        limits.add(round(stepper.limit.max_step_s, 9))
    assert len(limits) > 5, "the defects span different step limits"


def test_a_model_that_needs_a_smaller_step_takes_substeps_not_another_rate():
    """Friction smoothed over 5 mm/s (4x narrower) puts the step limit at 16 us, below the
    39 us sample interval: the sample rate stays and each interval takes three steps."""
    scenario = load_scenario("symmetric")
    narrow = parse_scenario('name = "narrow"\n[parameters.friction]\nsmoothing_speed_m_s = 0.005')
    healthy, stiff = stepper_for(scenario), stepper_for(narrow)
    assert stiff.limit.max_step_s < PERIOD < healthy.limit.max_step_s
    assert (healthy.substeps, stiff.substeps) == (1, math.ceil(PERIOD / stiff.limit.max_step_s))
    assert stiff.substeps == 3 and stiff.physics_step_s == PERIOD / 3
    block = stiff.advance(256)
    np.testing.assert_array_equal(block.time_s, np.arange(256) * PERIOD)


def test_any_sample_rate_the_user_chooses_is_kept_exactly():
    for rate in (1_000.0, 10_000.0, 48_000.0, 100_000.0):
        scenario = load_scenario("case2_left_pivot_in").with_solver(sample_rate_hz=rate)
        stepper = stepper_for(scenario)
        assert stepper.sample_period_s == 1 / rate
        assert stepper.substeps == math.ceil(
            (1 / rate) / min(stepper.limit.max_step_s, scenario.solver.max_step_s)
        )
        block = stepper.advance(10)
        np.testing.assert_array_equal(block.time_s, np.arange(10) * (1 / rate))


def test_an_explicit_largest_step_bounds_the_physics_step_never_the_sample_rate():
    scenario = load_scenario("symmetric").with_solver(max_step_s=1e-5)
    stepper = stepper_for(scenario)
    assert (stepper.sample_period_s, stepper.substeps) == (PERIOD, 4)
    assert stepper.physics_step_s <= 1e-5
