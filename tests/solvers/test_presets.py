"""Presets: the stated error bounds hold on the symmetric event at the default sample rate;
a preset chooses the scheme and the largest step, never the sample rate."""

from __future__ import annotations

import math

import pytest

from brake_sim_ros.analysis.impacts import event_metrics
from brake_sim_ros.errors import ParameterError, ScenarioError
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.scenarios.types import DEFAULT_SAMPLE_RATE_HZ
from brake_sim_ros.solvers.presets import DEFAULT_PRESET, PRESETS, get_preset
from brake_sim_ros.stream.build import stepper_for
from brake_sim_ros.studies.work_precision import compare


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_preset_meets_its_stated_error_bounds(name, symmetric_reference):
    preset = PRESETS[name]
    scenario = load_scenario("symmetric").with_solver(preset=name)
    stepper = stepper_for(scenario)
    assert stepper.scheme == preset.scheme
    assert stepper.sample_period_s == 1 / DEFAULT_SAMPLE_RATE_HZ
    assert stepper.physics_step_s <= preset.max_step_s
    samples = stepper.run(scenario.duration_s)
    metrics = event_metrics(samples, stop_time_s=stepper.stop_time_s)
    row = compare(
        preset.scheme, name, samples, metrics, symmetric_reference.metrics, scenario, 1.0, 1.0
    )
    assert row.err_first_peak <= preset.max_err_first_peak
    assert row.err_period <= preset.max_err_period
    assert row.err_stop_time <= preset.max_err_stop_time
    assert row.err_contact_force <= preset.max_err_contact_force
    assert row.impact_count_diff <= preset.max_impact_count_diff


def test_balanced_preset_meets_the_issue_targets():
    b = PRESETS["balanced"]
    assert DEFAULT_PRESET == "balanced"
    assert b.max_err_first_peak <= 0.01 and b.max_err_period <= 0.01
    assert b.max_err_stop_time <= 0.001


def test_default_solver_is_the_balanced_preset():
    scenario = parse_scenario('name = "x"')
    solver = scenario.solver
    assert (solver.method, solver.max_step_s, solver.preset) == (
        PRESETS["balanced"].scheme,
        PRESETS["balanced"].max_step_s,
        "balanced",
    )
    assert scenario.sample_rate_hz == DEFAULT_SAMPLE_RATE_HZ == 25_600.0


def test_explicit_step_bound_and_method_override_the_preset():
    solver = parse_scenario(
        'name = "x"\n[solver]\npreset = "accurate"\nmethod = "rk4"\nmax_step_s = 3e-5'
    ).solver
    assert (solver.method, solver.max_step_s, solver.preset) == ("rk4", 3e-5, "accurate")


def test_unknown_preset_is_refused_with_the_allowed_names():
    with pytest.raises(ScenarioError, match=r"solver.preset.*'turbo'.*fast.*balanced.*accurate"):
        parse_scenario('name = "x"\n[solver]\npreset = "turbo"')
    with pytest.raises(ParameterError, match="allowed one of"):
        get_preset("turbo")
    with pytest.raises(ScenarioError, match="allowed one of"):
        load_scenario("symmetric").with_solver(preset="turbo")


def test_a_preset_never_sets_the_sample_rate_nor_is_refused_for_the_step_limit():
    """Whatever a defect does to the step limit (case 2's leading pivot 3 % inward here),
    every preset runs it at the scenario's sample rate, with as many substeps as it needs."""
    text = 'name = "x"\nsample_rate_hz = 20000\n[defects.left]\npivot_radius_change_pct = -3.0'
    for name, preset in PRESETS.items():
        scenario = parse_scenario(text).with_solver(preset=name)
        stepper = stepper_for(scenario)
        assert stepper.sample_period_s == 1 / 20_000
        assert stepper.physics_step_s <= min(stepper.limit.max_step_s, preset.max_step_s)
        assert stepper.substeps == math.ceil(
            5e-5 / min(stepper.limit.max_step_s, preset.max_step_s)
        )


def test_the_retired_dt_s_key_is_refused_with_what_replaced_it():
    with pytest.raises(ScenarioError, match=r"solver.dt_s.*sample_rate_hz.*max_step_s"):
        parse_scenario('name = "x"\n[solver]\ndt_s = 4e-5')
