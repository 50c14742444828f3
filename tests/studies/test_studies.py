"""The studies (work-precision, fidelity) and the tests share one energy balance and one
set of metric comparisons; each is checked here against its definition."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from brake_sim_ros.analysis.comparison import (
    impact_count_diff,
    metric_errors,
    relative_error,
    worse,
)
from brake_sim_ros.analysis.energy import ENERGY_COLUMNS, energy_balance
from brake_sim_ros.analysis.impacts import EventMetrics, ShoeMetrics
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.stream.run import RunResult
from brake_sim_ros.studies import fidelity as fidelity_study
from brake_sim_ros.studies.work_precision import compare


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


def _metrics(n_left: int, n_right: int, stop: float | None = 5.0) -> EventMetrics:
    def shoe(n: int) -> ShoeMetrics:
        onsets = 0.2 + 0.01 * np.arange(n)
        peaks = np.full(n, 1000.0)
        return ShoeMetrics(onsets, onsets + 0.005, peaks, 50.0, 0.3, 700.0)

    return EventMetrics(shoe(n_left), shoe(n_right), stop)


def test_impact_count_diff_is_summed_over_the_shoes():
    """One impact missed on the left and one added on the right count 2 (the worse shoe
    would say 1): the figure is the number of impacts the run gets wrong."""
    run, ref = _metrics(8, 9), _metrics(9, 8)
    assert impact_count_diff(run, ref) == 2
    assert impact_count_diff(run, ref, ("left",)) == 1
    assert metric_errors(run, ref).impact_count_diff == 2


def test_relative_errors_and_the_worse_shoe():
    assert relative_error(1.01, 1.0) == pytest.approx(0.01)
    for value, reference in ((None, 1.0), (1.0, None), (math.nan, 1.0), (1.0, math.inf)):
        assert math.isnan(relative_error(value, reference))
    assert worse([0.1, 0.3]) == 0.3
    assert math.isnan(worse([0.1, math.nan])) and math.isnan(worse([]))
    # a shoe with one impact has no period: the worse-shoe period error is NaN, not the other's
    errors = metric_errors(_metrics(1, 9), _metrics(9, 9))
    assert math.isnan(errors.period) and errors.first_peak == 0.0
    assert math.isnan(metric_errors(_metrics(9, 9, None), _metrics(9, 9)).stop_time)


def test_both_studies_use_the_one_comparison(symmetric_run: RunResult):
    scenario = load_scenario("symmetric")
    ref = dataclasses.replace(symmetric_run, metrics=_metrics(9, 8, 6.6))
    run = dataclasses.replace(symmetric_run, metrics=_metrics(8, 9, 6.7))
    expected = metric_errors(run.metrics, ref.metrics)
    assert expected.impact_count_diff == 2
    row = compare("s", "x", run.samples, run.metrics, ref.metrics, scenario, 1.0, 1.0)
    fid = fidelity_study._row("s", "x", run, ref, 1.0, scenario)
    for got in (dataclasses.asdict(row), fid):
        assert got["impact_count_diff"] == expected.impact_count_diff
        assert got["err_stop_time"] == expected.stop_time
        assert got["err_first_peak"] == expected.first_peak
        assert got["err_period"] == expected.period
        assert got["err_contact_force"] == expected.contact_force


def _fidelity_row(scheme: str, **figures: float) -> dict:
    nan = math.nan
    row = dict.fromkeys(("err_stop_time", "err_first_peak", "err_period"), nan)
    row.update(err_contact_force=nan, energy_residual=nan, model_stop_err=nan)
    row.update(scheme=scheme, setting="symmetric", cpu_s_per_sim_s=0.01, x_real_time=100.0)
    row.update(impact_count_diff=-1, memory_bytes=1e6)
    return {**row, **figures}


def test_fidelity_table_says_not_delivered_instead_of_nan(monkeypatch, capsys):
    rows = [
        _fidelity_row(
            "level full",
            err_stop_time=0.0,
            impact_count_diff=0,
            err_contact_force=0.0,
            energy_residual=7.4e-8,
        ),
        _fidelity_row("level contact_regime", err_stop_time=1e-4, err_contact_force=1e-10),
    ]
    monkeypatch.setattr(fidelity_study, "fidelity_rows", lambda *args, **kwargs: rows)
    assert fidelity_study.main([]) == 0
    out = capsys.readouterr().out
    assert "nan" not in out.lower()
    assert "| 7.40e-08 |" in out
    assert "| 1e-08 % | - | 1.00 MB" in out
