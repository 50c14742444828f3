"""Validation against the published study: run every case with one parameter set and report.

The published figures below are the study's results (symmetric brake and defect cases 1,
5 and 7); the acceptance bands are the project's validation criteria. Cases 2, 3, 4, 6 and
8 have no published figures and are reported as predictions of the calibrated model.

The report also sweeps the pivot location of each shoe (-3 to +3 %) and states whether the
first impact responds monotonically: opposite small displacements of one part move the
response in opposite directions with the model's tip-abutment pose. That is the project's
criterion, not a published figure (the study publishes no sweep; the notes on case 1 show
poses with an even response).

Last, it measures the first 0.6 s of every case with the default sensor set (backing-plate
accelerometers on the modal structure, several noise seeds) and states, per case, which
feature of the measured acceleration separates it from the symmetric brake, or that none
does (:mod:`brake_sim_ros.analysis.measured_features`, shared with ``brake-sim bench
sensors``).

This module runs the cases; their figures and the checks against the bands are
:mod:`.validation_checks`, the report's text :mod:`.validation_report` and
:mod:`.validation_notes`, its plots :mod:`.validation_plots`.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

from brake_sim_ros.analysis import measured_features as mf
from brake_sim_ros.analysis.impacts import EventMetrics
from brake_sim_ros.model.assembly import pack
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.recording.output import check_output, output_directory, replace_output
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.stream.run import RunResult, run_scenario
from brake_sim_ros.studies.validation_checks import (
    CASES,
    SWEEP_DURATION_S,
    SWEEP_PCT,
    SYMMETRIC,
    CaseRun,
    Check,
    checks,
    figures,
    free_travel,
)
from brake_sim_ros.studies.validation_report import markdown


def run_all(progress: Callable[[str], None] | None = None) -> tuple[RunResult, list[CaseRun]]:
    """Run the symmetric case and cases 1-8, each with its built-in scenario."""
    if progress:
        progress(SYMMETRIC)
    base = run_scenario(load_scenario(SYMMETRIC))
    runs = []
    for case, (name, shoe) in CASES.items():
        if progress:
            progress(name)
        runs.append(CaseRun(case, name, shoe, run_scenario(load_scenario(name))))
    return base, runs


def pivot_sweep(
    base: RunResult, progress: Callable[[str], None] | None = None
) -> tuple[dict[str, dict[float, EventMetrics]], dict[str, dict[float, float]]]:
    """Metrics of the symmetric scenario with one shoe's pin moved by each of
    :data:`SWEEP_PCT` (impacting regime only), keyed by side and change (0 % is ``base``),
    and each run's :func:`.validation_checks.free_travel` of that shoe."""
    scenario = load_scenario(SYMMETRIC)
    params = scenario.setup.params
    out: dict[str, dict[float, EventMetrics]] = {}
    travel: dict[str, dict[float, float]] = {}
    for side in SIDES:
        out[side] = {0.0: base.metrics}
        travel[side] = {0.0: free_travel(pack(params, scenario.setup.defects), side)}
        for pct in SWEEP_PCT:
            if progress:
                progress(f"pivot sweep: {side} {pct:+g} %")
            defects = Defects(**{side: ShoeDefect(pivot_radius_change_pct=pct)})
            run = run_scenario(scenario.with_defects(defects), duration_s=SWEEP_DURATION_S)
            out[side][pct] = run.metrics
            travel[side][pct] = free_travel(pack(params, defects), side)
    return out, travel


def measure_cases(
    base: RunResult,
    runs: list[CaseRun],
    *,
    duration_s: float = mf.DEFAULT_DURATION_S,
    seeds: int = mf.DEFAULT_SEEDS,
) -> mf.CaseSeparation:
    """The first ``duration_s`` of every case measured by the default sensor set with
    ``seeds`` noise seeds, against the symmetric brake (keyed by scenario name)."""
    samples = {SYMMETRIC: mf.head(base.samples, duration_s)}
    samples |= {run.scenario: mf.head(run.result.samples, duration_s) for run in runs}
    rate = load_scenario(SYMMETRIC).sample_rate_hz
    return mf.measure_cases(samples, SYMMETRIC, sample_rate_hz=rate, seeds=range(seeds))


def write_report(
    out_dir: Path, json_path: Path | None = None, progress: Callable[[str], None] | None = None
) -> tuple[dict, list[Check]]:
    """Run everything and write report.md, figures.json and the plots into ``out_dir``
    (each replaced whole, never through a link: ``recording.output.replace_output``)."""
    out_dir = output_directory(out_dir, "--out")  # before the work: never a link
    check_output(out_dir / "report.md", overwrite=True, option="--out")
    if json_path is not None:
        check_output(json_path, overwrite=True, option="--json")
    base, runs = run_all(progress)
    sweep, travel = pivot_sweep(base, progress)
    if progress:
        progress(f"measured acceleration: {len(runs) + 1} runs x {mf.DEFAULT_SEEDS} noise seeds")
    measured = measure_cases(base, runs)
    fig = figures(base.metrics, runs, sweep, measured, travel)
    check_list = checks(fig)
    params = load_scenario(SYMMETRIC).setup.params
    report = markdown(fig, check_list, base.metrics, params, measured)
    text = json.dumps(fig, indent=2)
    replace_output(out_dir / "report.md", lambda tmp: tmp.write_text(report, encoding="utf-8"))
    replace_output(out_dir / "figures.json", lambda tmp: tmp.write_text(text, encoding="utf-8"))
    if json_path is not None:
        replace_output(json_path, lambda tmp: tmp.write_text(text, "utf-8"), option="--json")
    from brake_sim_ros.studies.validation_plots import plot_pivot_sweep, plot_validation

    plot_validation(base, runs, out_dir)
    plot_pivot_sweep(fig["pivot_sweep"], out_dir)
    return fig, check_list
