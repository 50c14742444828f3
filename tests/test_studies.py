"""The studies (work-precision, fidelity) and the tests share one energy balance and one
set of metric comparisons; each is checked here against its definition."""

from __future__ import annotations

import dataclasses
import math

import pytest

from brake_sim_ros.analysis.energy import ENERGY_COLUMNS, energy_balance
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.solvers import fidelity_study
from brake_sim_ros.solvers.run import RunResult
from brake_sim_ros.solvers.work_precision import compare


def test_energy_books_read_their_columns_by_name(symmetric_run: RunResult):
    """A block that keeps only the balance's columns, in another order, has the same books
    as the full layout, and a run from t = 0 starts with the initial kinetic energy."""
    params = load_scenario("symmetric").setup.params
    full = energy_balance(symmetric_run.samples, params)
    assert set(ENERGY_COLUMNS) < set(symmetric_run.samples.columns)
    kept = symmetric_run.samples.select(("time_s", *reversed(ENERGY_COLUMNS)))
    assert energy_balance(kept, params) == full
    d = params.driveline
    e0 = 0.5 * (d.flywheel_inertia_kg_m2 + d.drum_inertia_kg_m2) * d.initial_speed_rad_s**2
    assert full.stored_start_j == pytest.approx(e0, rel=1e-15)
    assert full.relative_residual == abs(full.residual_j) / full.stored_start_j < 1e-6
    with pytest.raises(KeyError, match="lock_loss_j"):
        energy_balance(kept.select(ENERGY_COLUMNS[:-1]), params)


def test_studies_report_the_one_energy_residual(symmetric_run: RunResult):
    scenario = load_scenario("symmetric")
    books = energy_balance(symmetric_run.samples, scenario.setup.params)
    assert fidelity_study.energy_residual(symmetric_run, scenario) == books.relative_residual
    m = symmetric_run.metrics
    row = compare("s", "x", symmetric_run.samples, m, m, scenario, 1.0, 1.0)
    assert row.energy_residual == books.relative_residual
    # a level that did not keep the balance's columns has no residual
    partial = dataclasses.replace(
        symmetric_run, samples=symmetric_run.samples.select(ENERGY_COLUMNS[:-1])
    )
    assert math.isnan(fidelity_study.energy_residual(partial, scenario))
