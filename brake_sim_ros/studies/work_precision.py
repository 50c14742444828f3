"""``brake-sim bench accuracy``: work-precision study of every stepper against a tight reference.

For each scheme and step (fixed-step schemes) or tolerance (scipy adaptive solvers, run with
the contact switches and the lock located as events), the symmetric braking event is run
once for its samples and, for fixed-step schemes, ``repeats`` times for the best CPU time
of the stepping itself (process CPU, one core, recording every sample). Its metrics are
compared with a DOP853 run at ``rtol = 1e-11`` (:data:`REFERENCE_RTOL`):

* ``err_stop_time``, ``err_first_peak``, ``err_period``, ``err_contact_force``: relative
  errors (fractions) of the stop time, and the worse shoe's first-impact peak pivot force,
  first impact period and contact-regime mean pivot force (metrics of
  ``analysis.impacts``, errors as ``analysis.comparison`` defines them);
* ``impact_count_diff``: impacts missed or added, summed over the shoes
  (``analysis.comparison.impact_count_diff``);
* ``energy_residual``: |energy supplied - spent - left| / initial kinetic energy at the end
  of the run itself (``analysis.energy``; a conservation check, not a comparison).

Each metric is taken from the samples a user of that scheme gets (the uniform grid of a
fixed step, the reference's sample times for an adaptive solver), so output sampling is part
of the error. Separately, the order of convergence of each fixed-step scheme is measured on
the state (shoe angles and speeds, drum speed) at :data:`ORDER_TIME_S` s, after the first
impacts, against a reference at ``rtol = 1e-12``.

Caps (so the whole study takes a few minutes on one core): adaptive solvers are swept over
:data:`ADAPTIVE_RTOLS` and each run is abandoned after :data:`ADAPTIVE_BUDGET_S` s of CPU.
"""

from __future__ import annotations

import csv
import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from brake_sim_ros.analysis.comparison import metric_errors
from brake_sim_ros.analysis.energy import energy_balance
from brake_sim_ros.analysis.impacts import EventMetrics, event_metrics
from brake_sim_ros.command_line import Parser
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.scenarios.types import Scenario
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.solvers.reference import run_reference

REFERENCE_RTOL = 1e-11
FIXED_STEPS_S: dict[str, tuple[float, ...]] = {
    "rk4": (1e-5, 2e-5, 3e-5, 4e-5, 5e-5, 6e-5),
    "rk4-located": (1e-5, 2e-5, 3e-5, 4e-5, 5e-5, 6e-5),
    "semi-implicit-euler": (2.5e-6, 5e-6, 1e-5, 2e-5, 4e-5),
}
QUICK_FIXED_STEPS_S: dict[str, tuple[float, ...]] = {
    "rk4": (2e-5, 6e-5),
    "rk4-located": (2e-5, 6e-5),
    "semi-implicit-euler": (1e-5, 4e-5),
}
ADAPTIVE_METHODS = ("RK45", "DOP853", "Radau", "BDF", "LSODA")
ADAPTIVE_RTOLS = (1e-3, 1e-5, 1e-7, 1e-9)
QUICK_ADAPTIVE_RTOLS = (1e-5,)
ADAPTIVE_BUDGET_S = 30.0
ORDER_TIME_S = 0.3
ORDER_STEPS_S = (4e-5, 2e-5, 1e-5, 5e-6)
# scales of the state components in the convergence error: rad, rad/s, rad, rad/s, rad/s
_ORDER_COLUMNS = (
    ("left_angle_rad", 1e-3),
    ("left_speed_rad_s", 1.0),
    ("right_angle_rad", 1e-3),
    ("right_speed_rad_s", 1.0),
    ("drum_speed_rad_s", 100.0),
)


@dataclass(frozen=True)
class WorkPrecisionRow:
    """One scheme at one setting. Relative errors are fractions; NaN where not applicable."""

    scheme: str
    setting: str
    cpu_s_per_sim_s: float
    x_real_time: float
    err_stop_time: float
    err_first_peak: float
    err_period: float
    impact_count_diff: int
    err_contact_force: float
    energy_residual: float

    def as_dict(self) -> dict[str, str | float | int]:
        return asdict(self)


@dataclass(frozen=True)
class Failure:
    """A scheme and setting that did not give a result, and why."""

    scheme: str
    setting: str
    reason: str


@dataclass(frozen=True)
class Convergence:
    """State error at ``ORDER_TIME_S`` against the reference, per step, and the fitted order."""

    scheme: str
    steps_s: tuple[float, ...]
    errors: tuple[float, ...]
    order: float


@dataclass
class StudyResult:
    scenario: str
    duration_s: float
    reference_cpu_s: float
    rows: list[WorkPrecisionRow] = field(default_factory=list)
    failures: list[Failure] = field(default_factory=list)
    convergence: list[Convergence] = field(default_factory=list)


def compare(
    scheme: str,
    setting: str,
    samples: SampleBlock,
    metrics: EventMetrics,
    reference: EventMetrics,
    scenario: Scenario,
    cpu_s: float,
    duration_s: float,
) -> WorkPrecisionRow:
    """Row of the study for one run (``cpu_s`` for ``duration_s`` simulated seconds)."""
    books = energy_balance(samples, scenario.setup.params)
    errors = metric_errors(metrics, reference)
    return WorkPrecisionRow(
        scheme=scheme,
        setting=setting,
        cpu_s_per_sim_s=cpu_s / duration_s,
        x_real_time=duration_s / cpu_s if cpu_s > 0 else math.inf,
        err_stop_time=errors.stop_time,
        err_first_peak=errors.first_peak,
        err_period=errors.period,
        impact_count_diff=errors.impact_count_diff,
        err_contact_force=errors.contact_force,
        energy_residual=books.relative_residual,
    )


def run_fixed(
    scenario: Scenario, scheme: str, dt_s: float, repeats: int, duration_s: float
) -> tuple[SampleBlock, EventMetrics, float]:
    """Samples, metrics and best CPU time (s) of ``repeats`` runs of a fixed-step scheme.

    The step limit is not enforced here (the study shows what happens near and past it);
    building the stepper (and its step-limit analysis) is outside the timed region.
    """
    best = math.inf
    samples = None
    stop = None
    for _ in range(repeats):
        stepper = FixedStepStepper(scenario.setup, dt_s, scheme=scheme, check_step=False)
        start = time.process_time()
        samples = stepper.run(duration_s)
        best = min(best, time.process_time() - start)
        stop = stepper.stop_time_s
    return samples, event_metrics(samples, stop_time_s=stop), best


def convergence(
    scenario: Scenario, scheme: str, steps_s: tuple[float, ...] = ORDER_STEPS_S
) -> Convergence:
    """State error at :data:`ORDER_TIME_S` s per step and the least-squares order."""
    times = np.array([ORDER_TIME_S])
    names = [name for name, _ in _ORDER_COLUMNS]
    scale = np.array([s for _, s in _ORDER_COLUMNS])
    ref_block = run_reference(
        scenario.setup, ORDER_TIME_S + 1e-3, sample_times=times, rtol=1e-12
    ).samples
    ref = np.array([ref_block[n][0] for n in names])
    errors = []
    for dt in steps_s:
        stepper = FixedStepStepper(scenario.setup, dt, scheme=scheme, check_step=False)
        block = stepper.run(ORDER_TIME_S + 2 * dt)
        at = round(ORDER_TIME_S / dt)
        state = np.array([block[n][at] for n in names])
        errors.append(float(np.max(np.abs(state - ref) / scale)))
    order = float(np.polyfit(np.log(steps_s), np.log(errors), 1)[0])
    return Convergence(scheme, tuple(steps_s), tuple(errors), order)


def study(
    scenario: Scenario,
    *,
    quick: bool = False,
    repeats: int = 3,
    log: Callable[[str], None] = print,
) -> StudyResult:
    """Run the whole study on ``scenario``."""
    duration = scenario.duration_s
    log(f"reference: DOP853 rtol {REFERENCE_RTOL:g}, events located ...")
    start = time.process_time()
    ref = run_reference(scenario.setup, duration, rtol=REFERENCE_RTOL)
    result = StudyResult(scenario.name, duration, time.process_time() - start)
    ref_metrics = event_metrics(ref.samples, stop_time_s=ref.stop_time_s)
    sweeps = QUICK_FIXED_STEPS_S if quick else FIXED_STEPS_S
    for scheme, steps in sweeps.items():
        # compile, or load the compiled kernel from the cache, outside the timed runs
        FixedStepStepper(scenario.setup, 1e-4, scheme=scheme, check_step=False).advance(10)
        for dt in steps:
            setting = f"dt {dt * 1e6:g} us"
            try:
                samples, metrics, cpu = run_fixed(
                    scenario, scheme, dt, 1 if quick else repeats, duration
                )
            except BrakeSimError as exc:
                result.failures.append(Failure(scheme, setting, str(exc)))
                log(f"  {scheme} {setting}: failed: {exc}")
                continue
            row = compare(scheme, setting, samples, metrics, ref_metrics, scenario, cpu, duration)
            result.rows.append(row)
            log(_summary(row))
    rtols = QUICK_ADAPTIVE_RTOLS if quick else ADAPTIVE_RTOLS
    for method in ADAPTIVE_METHODS:
        scheme = f"{method} (scipy, events)"
        for rtol in rtols:
            setting = f"rtol {rtol:g}"
            start = time.process_time()
            try:
                run = run_reference(
                    scenario.setup,
                    duration,
                    rtol=rtol,
                    method=method,
                    cpu_budget_s=ADAPTIVE_BUDGET_S,
                )
            except BrakeSimError as exc:
                result.failures.append(Failure(scheme, setting, str(exc)))
                log(f"  {scheme} {setting}: failed: {exc}")
                continue
            cpu = time.process_time() - start
            metrics = event_metrics(run.samples, stop_time_s=run.stop_time_s)
            row = compare(
                scheme, setting, run.samples, metrics, ref_metrics, scenario, cpu, duration
            )
            result.rows.append(row)
            log(_summary(row))
    if not quick:
        for scheme in sweeps:
            conv = convergence(scenario, scheme)
            result.convergence.append(conv)
            log(f"  order of {scheme}: {conv.order:.2f} (state error at {ORDER_TIME_S:g} s)")
    return result


def _summary(row: WorkPrecisionRow) -> str:
    return (
        f"  {row.scheme} {row.setting}: {row.x_real_time:.0f}x real time, errors peak"
        f" {100 * row.err_first_peak:.3g} %, period {100 * row.err_period:.3g} %, stop"
        f" {100 * row.err_stop_time:.3g} %, contact {100 * row.err_contact_force:.3g} %,"
        f" impacts {row.impact_count_diff:+d}, energy {row.energy_residual:.1e}"
    )


def _pct(x: float) -> str:
    return "-" if math.isnan(x) else f"{100 * x:.2g}"


def markdown_table(rows: list[WorkPrecisionRow]) -> str:
    """The study's table (errors in %), one row per scheme and setting."""
    lines = [
        "| scheme | setting | CPU s per sim s | x real time | stop time err % |"
        " first peak err % | period err % | impact count diff | contact force err % |"
        " energy residual |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r.scheme} | {r.setting} | {r.cpu_s_per_sim_s:.3g} | {r.x_real_time:.0f} |"
            f" {_pct(r.err_stop_time)} | {_pct(r.err_first_peak)} | {_pct(r.err_period)} |"
            f" {r.impact_count_diff} | {_pct(r.err_contact_force)} | {r.energy_residual:.1e} |"
        )
    return "\n".join(lines)


def write_study(result: StudyResult, out_dir: Path) -> list[Path]:
    """Write ``work_precision.csv``, ``work_precision.md`` and ``work_precision.png``."""
    from brake_sim_ros.studies.work_precision_plot import plot_work_precision

    out_dir.mkdir(parents=True, exist_ok=True)
    csv_path = out_dir / "work_precision.csv"
    with csv_path.open("w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=list(WorkPrecisionRow.__dataclass_fields__))
        writer.writeheader()
        for row in result.rows:
            writer.writerow(row.as_dict())
    md = [
        f"# Work-precision study: scenario `{result.scenario}`, {result.duration_s:g} s event",
        "",
        "Generated by `brake-sim bench accuracy`. Reference: DOP853 with events at rtol"
        f" {REFERENCE_RTOL:g} ({result.reference_cpu_s:.2f} s CPU). CPU time is process time"
        " on one core (best of the repeats for fixed-step schemes, recording every sample).",
        "Errors are relative, in %, the worse of the two shoes; `-` means not applicable.",
        "",
        markdown_table(result.rows),
        "",
    ]
    if result.failures:
        md += ["Runs without a result:", ""]
        md += [f"* {f.scheme} {f.setting}: {f.reason}" for f in result.failures]
        md.append("")
    if result.convergence:
        md += [
            f"Order of convergence (state error at {ORDER_TIME_S:g} s, after the first"
            " impacts, least-squares slope of log error against log step):",
            "",
            "| scheme | " + " | ".join(f"{dt * 1e6:g} us" for dt in ORDER_STEPS_S) + " | order |",
            "|---|" + "---|" * (len(ORDER_STEPS_S) + 1),
        ]
        for c in result.convergence:
            errs = " | ".join(f"{e:.2e}" for e in c.errors)
            md.append(f"| {c.scheme} | {errs} | {c.order:.2f} |")
        md.append("")
    md_path = out_dir / "work_precision.md"
    md_path.write_text("\n".join(md), encoding="utf-8")
    png_path = plot_work_precision(result.rows, out_dir / "work_precision.png")
    return [csv_path, md_path, png_path]


def main(argv: list[str] | None = None) -> int:
    parser = Parser(prog="brake-sim bench accuracy", description=__doc__)
    parser.add_argument("--out", default="out/accuracy", help="directory for the table and plot")
    parser.add_argument("--scenario", default="symmetric")
    parser.add_argument(
        "--quick", action="store_true", help="two steps per fixed-step scheme, one tolerance"
    )
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per fixed step")
    args = parser.parse_args(argv)
    scenario = load_scenario(args.scenario)
    result = study(scenario, quick=args.quick, repeats=args.repeats)
    paths = write_study(result, Path(args.out))
    print(markdown_table(result.rows))
    print("written: " + ", ".join(str(p) for p in paths))
    return 0
