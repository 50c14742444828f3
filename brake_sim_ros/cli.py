"""One entry point: ``brake-sim <command>``.

Every command exits 0 on success and non-zero with a one-line reason on failure.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import math
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

import numpy as np

from brake_sim_ros import __version__
from brake_sim_ros.detection.registry import help_text as detector_help
from brake_sim_ros.detection.registry import names as detector_names
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.identifiers import IDENTIFIER_RULE
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.solvers.methods import METHODS, SOLVER_METHODS
from brake_sim_ros.solvers.presets import PRESETS
from brake_sim_ros.studies import BENCHMARKS

if TYPE_CHECKING:  # the CLI imports the numerics only when a command needs them
    from brake_sim_ros.analysis.impacts import ShoeMetrics
    from brake_sim_ros.detection.detector import Detector
    from brake_sim_ros.scenarios.types import Scenario
    from brake_sim_ros.stream.run import RunResult
    from brake_sim_ros.viz.targets import RerunTarget

EXIT_ERROR = 2
EXIT_BROKEN_PIPE = 141  # 128 + SIGPIPE, what a shell reports for a pipe its reader closed


def _progress(label: str):
    """Progress callback printing a fraction to stderr, at most a few times a second."""
    last = [0.0]

    def report(fraction: float) -> None:
        now = time.monotonic()
        if now - last[0] > 0.5 or fraction >= 1.0:
            last[0] = now
            end = "\n" if fraction >= 1.0 else "\r"
            print(f"{label}: {100 * fraction:5.1f} %", end=end, file=sys.stderr, flush=True)

    return report


# --- simulate ---------------------------------------------------------------------------------
# The longest run ``simulate`` takes, s (the node and ``brake-sim live`` stream longer ones).
MAX_SIMULATE_DURATION_S = 3600.0
# The history ``simulate`` may keep in memory (samples x kept columns x 8 bytes): 2 GiB,
# e.g. 276 s of the full model at the default 25.6 kHz. The whole run is kept to be
# analysed and written, so this, not the duration, is what a long or fast-sampled run meets.
MAX_HISTORY_BYTES = 2 * 1024**3
# --out formats: suffix -> what it is
HISTORY_FORMATS = {
    ".npz": "numpy, the Parquet table's columns; pandas via pd.DataFrame(dict(np.load(f)))",
    ".csv": "comma-separated with a header line",
    ".parquet": "Apache Parquet: samples and the scenario's measured sensor channels",
}


@dataclass(frozen=True)
class SimulateJob:
    """A ``simulate`` command line, checked: what to run and where to write it."""

    scenario: Scenario  # with the command line's solver and sample-rate overrides
    duration_s: float
    inputs: tuple[Path, ...]  # the files read (the scenario file): never an output
    outputs: dict[str, Path]  # "--out", "--mcap" -> its path (--rerun save: in ``rerun``)
    rerun: tuple[RerunTarget, ...]
    overwrite: bool
    quiet: bool
    mcap_compression: str

    def atomic(self, option: str, path: Path | None = None):
        """The output of ``option`` (or its ``path``), written whole or not at all."""
        from brake_sim_ros.recording.output import atomic_output

        return atomic_output(
            self.outputs[option] if path is None else path,
            inputs=self.inputs,
            overwrite=self.overwrite,
            option=option,
            make_parents=False,
        )


def load_simulation(args: argparse.Namespace) -> SimulateJob:
    """Step 1 of ``simulate``: the scenario, every option and every output checked before
    anything runs or is written (a refusal is a BrakeSimError of one line)."""
    from brake_sim_ros.scenarios import load_scenario

    if args.dt is not None:
        raise BrakeSimError(
            "--dt is gone: the output sample rate belongs to the scenario (--sample-rate HZ,"
            " default 25600) and the physics step is chosen below the step limit (--max-step S"
            " bounds it)"
        )
    scenario = load_scenario(args.scenario)
    # the overrides go into the scenario once: every output below runs the same stepper
    for option, key, value in (
        ("--preset", "preset", args.preset),
        ("--method", "method", args.method),
        ("--max-step", "max_step_s", args.max_step),
        ("--sample-rate", "sample_rate_hz", args.sample_rate),
    ):
        if value is not None:
            try:
                scenario = scenario.with_solver(**{key: value})
            except BrakeSimError as exc:
                raise BrakeSimError(f"{option}: {exc}") from None
    if args.method == "reference" and (args.mcap or args.rerun):
        raise BrakeSimError(
            "--mcap and --rerun take the node's fixed-step stream: drop --method reference"
        )
    rerun = tuple(_rerun_targets(args))
    inputs = (Path(args.scenario),) if os.path.lexists(args.scenario) else ()
    return SimulateJob(
        scenario=scenario,
        duration_s=_simulated_duration(args.duration, scenario),
        inputs=inputs,
        outputs=_checked_outputs(args, rerun, inputs),
        rerun=rerun,
        overwrite=args.overwrite,
        quiet=args.quiet,
        mcap_compression=args.mcap_compression,
    )


def _simulated_duration(duration: float | None, scenario: Scenario) -> float:
    """The run's duration, s (``--duration`` or the scenario's): finite, > 0, at most
    MAX_SIMULATE_DURATION_S, one sample or more, a history within MAX_HISTORY_BYTES."""
    from brake_sim_ros.model.fidelity import plan
    from brake_sim_ros.solvers.contact_regime import macro_step
    from brake_sim_ros.stream.run import planned_setup

    where = "--duration" if duration is not None else f"{scenario.source}: duration_s"
    value = scenario.duration_s if duration is None else duration
    if not (math.isfinite(value) and 0.0 < value <= MAX_SIMULATE_DURATION_S):
        raise BrakeSimError(
            f"{where} {value!r} s: allowed a time > 0 s and at most {MAX_SIMULATE_DURATION_S:g} s"
            " (simulate keeps the whole run in memory; brake-sim live streams longer runs)"
        )
    chosen = plan(scenario.needs, model_shoes=scenario.setup.options.shoes)
    if chosen.level.quasi_static_shoes:  # the contact-regime levels sample their macro step
        period = macro_step(planned_setup(scenario.setup, chosen), chosen.accuracy)
    else:
        period = scenario.sample_period_s
    samples = round(value / period)
    if samples < 1:
        raise BrakeSimError(
            f"{where} {value:g} s is shorter than one sample: allowed at least {period:.3g} s"
        )
    size = samples * len(chosen.columns) * 8
    if size > MAX_HISTORY_BYTES:
        raise BrakeSimError(
            f"{where} {value:g} s keeps {samples} samples x {len(chosen.columns)} columns"
            f" ({size / 1e9:.1f} GB) in memory: allowed at most {MAX_HISTORY_BYTES / 1e9:.1f}"
            " GB; shorten the run, lower --sample-rate, ask for fewer outputs ([needs]) or"
            " stream it with brake-sim live"
        )
    return value


def _checked_outputs(
    args: argparse.Namespace, rerun: tuple[RerunTarget, ...], inputs: tuple[Path, ...]
) -> dict[str, Path]:
    """The --out and --mcap paths, by option. Every output (--rerun save too) is refused
    unless it names its own file, has an allowed suffix, and
    :func:`~brake_sim_ros.recording.output.probe_output`'s rules hold (not the scenario
    file, not a link, not an existing file without --overwrite, nor a non-regular one; an
    existing directory that takes a new file)."""
    from brake_sim_ros.recording.output import check_outputs

    named = [("--out", args.out, HISTORY_FORMATS), ("--mcap", args.mcap, {".mcap": ""})]
    named += [("--rerun save", t.arg, {".rrd": ""}) for t in rerun if t.kind == "save"]
    checked = check_outputs(
        [(option, path, suffixes) for option, path, suffixes in named if path is not None],
        inputs=inputs,
        overwrite=args.overwrite,
    )
    checked.pop("--rerun save", None)  # the path is the target's
    return checked


def _rerun_targets(args: argparse.Namespace) -> list[RerunTarget]:
    """``simulate --rerun ...`` targets, checked before the run (empty without the option)."""
    if not args.rerun:
        return []
    from brake_sim_ros.viz.commands import parse_targets

    return parse_targets(args.rerun)


def run_simulation(job: SimulateJob) -> RunResult:
    """Step 2 of ``simulate``: integrate the scenario and analyse the run."""
    from brake_sim_ros.stream.run import run_scenario

    progress = None if job.quiet else _progress(f"simulating {job.scenario.name}")
    return run_scenario(job.scenario, duration_s=job.duration_s, progress=progress)


def write_simulation(job: SimulateJob, result: RunResult) -> list[str]:
    """Step 3 of ``simulate``: the history (--out) and the node's stream (--mcap, --rerun),
    each file written whole or not at all. Returns a line per output written."""
    lines = []
    if "--out" in job.outputs:
        _write_history(job, result)
        lines.append(
            f"time history: {job.outputs['--out']} ({len(result.samples)} samples x"
            f" {result.samples.data.shape[1]} columns)"
        )
    if "--mcap" in job.outputs or job.rerun:
        lines += _write_stream(job)
    return lines


def _write_history(job: SimulateJob, result: RunResult) -> None:
    from brake_sim_ros.recording.mcap_format import describe_path
    from brake_sim_ros.recording.output import OutputError

    path, scenario = job.outputs["--out"], job.scenario
    columns = result.samples.as_dict()
    with job.atomic("--out") as partial:
        try:
            if path.suffix in (".parquet", ".npz"):
                from brake_sim_ros.datasets import parquet

                table = parquet.run_table(scenario, result, job.duration_s)
                if path.suffix == ".parquet":
                    parquet.write_history(partial, table)
                else:  # the same columns; the metadata as JSON text
                    arrays = parquet.history_arrays(table)
                    meta_json = table.schema.metadata[parquet.METADATA_KEY].decode()
                    with open(partial, "wb") as f:
                        np.savez_compressed(f, **arrays, metadata=np.array(meta_json))
            else:
                names = list(columns)
                data = np.column_stack([columns[n] for n in names])
                np.savetxt(
                    partial, data, delimiter=",", header=",".join(names), comments="", fmt="%.10g"
                )
        except OSError as exc:
            raise OutputError(
                f"--out {describe_path(path)}: cannot write it ({exc.strerror or exc})"
            ) from None


def _write_stream(job: SimulateJob) -> list[str]:
    """The node's stream, produced offline once, into the MCAP file and the Rerun targets;
    the files are written under temporary names and renamed when complete."""
    from brake_sim_ros.viz.targets import RerunTarget

    with contextlib.ExitStack() as stack:
        mcap = stack.enter_context(job.atomic("--mcap")) if "--mcap" in job.outputs else None
        targets = [
            RerunTarget("save", str(stack.enter_context(job.atomic("--rerun save", Path(t.arg)))))
            if t.kind == "save"
            else t
            for t in job.rerun
        ]
        lines = _stream(job, mcap, targets)
    return lines


def _stream(job: SimulateJob, mcap: Path | None, targets: list[RerunTarget]) -> list[str]:
    from brake_sim_ros.viz.commands import finish_simulation_sinks, open_simulation_sinks

    scenario, lines = job.scenario, []
    sinks = open_simulation_sinks(scenario, targets) if targets else []
    try:
        if mcap is not None:
            from brake_sim_ros.recording.record import record_offline
            from brake_sim_ros.recording.writer import RecordingOptions

            options = RecordingOptions(compression=job.mcap_compression, durable=False)
            recording = record_offline(
                scenario, mcap, duration_s=job.duration_s, options=options, also=sinks
            )
            lines.append(dataclasses.replace(recording, path=str(job.outputs["--mcap"])).describe())
        else:
            from brake_sim_ros.stream.offline import offline_messages
            from brake_sim_ros.stream.samples import deliver

            deliver(offline_messages(scenario, duration_s=job.duration_s), sinks)
    except BaseException:
        for sink in sinks:
            sink.close()
        raise
    if sinks:
        lines.append(finish_simulation_sinks(sinks, list(job.rerun)))
    return lines


def cmd_simulate(args: argparse.Namespace) -> int:
    """``brake-sim simulate``: load and check, run, summarise, write."""
    job = load_simulation(args)
    result = run_simulation(job)
    print(simulate_summary(result, job.scenario))
    for line in write_simulation(job, result):
        print(line)
    return 0


def _shoe_summary(shoe: ShoeMetrics) -> str:
    """One shoe's figures; a figure the run has no value for is "none" with the reason."""
    parts = []
    if shoe.impacts_analysed:
        n = shoe.n_impacts
        if n == 0:
            parts.append("no impacts within the run")
        else:
            if n == 1:
                period = "period T none (a single impact)"
            else:
                period = f"period T {1e3 * shoe.period_s:.2f} ms"
            parts.append(
                f"{n} impact{'s' if n > 1 else ''}, first at {shoe.onsets_s[0]:.4f} s"
                f" ({shoe.first_impact_actuation_n:.1f} N actuation), first-impact peak"
                f" |F_pivot| {shoe.first_impact_peak_n:.0f} N, {period}"
            )
    if shoe.no_contact_regime_reason:
        parts.append(f"contact-regime |F_pivot| none: {shoe.no_contact_regime_reason}")
    else:
        digits = 0 if shoe.impacts_analysed else 1
        parts.append(f"contact-regime |F_pivot| {shoe.contact_regime_force_n:.{digits}f} N")
    return ", ".join(parts)


def simulate_summary(result: RunResult, scenario: Scenario) -> str:
    """What ``brake-sim simulate`` prints about a finished run: the level, the stop and cost,
    and one line per shoe. No figure is printed as nan: it says "none" and why."""
    m = result.metrics
    chosen = result.plan
    sim_s = result.samples.time_s[-1] if len(result.samples) else 0.0
    rtf = sim_s / result.cpu_s if result.cpu_s > 0 else float("inf")
    if m.stop_time_s is not None:
        stop = f"{m.stop_time_s:.4f} s"
    elif "stop_time" in chosen.level.outputs and chosen.shoes == scenario.setup.options.shoes:
        stop = "not stopped"
    else:
        stop = "not delivered by this level"
    unit = METHODS[result.method].counts
    lines = [
        f"level {chosen.level.name} ({chosen.level.description}; shoes"
        f" {', '.join(chosen.shoes)}): {chosen.reason}",
        f"scenario {scenario.name} ({result.method}): drum stop {stop};"
        f" cost {result.cpu_s:.3f} s CPU for {sim_s:.3f} s simulated"
        f" ({rtf:.0f}x real time, {result.n_steps} {unit}); kept"
        f" {len(result.samples.columns)} columns, {result.memory_bytes / 1e6:.2f} MB",
    ]
    if result.step_note:
        lines.append(f"preset {scenario.solver.preset}: {result.step_note}")
    for side in SIDES:
        if not any(c.startswith(f"{side}_") for c in result.samples.columns):
            lines.append(f"  {side:5s}: not asked for")
            continue
        lines.append(f"  {side:5s}: {_shoe_summary(m.shoe(side))}")
    return "\n".join(lines)


# --- recover ---------------------------------------------------------------------------------
def cmd_recover(args: argparse.Namespace) -> int:
    from brake_sim_ros.recording.recover import recover

    print(recover(args.broken, args.fixed, overwrite=args.overwrite).describe())
    return 0


def cmd_resim(args: argparse.Namespace) -> int:
    from brake_sim_ros.app.resim import resimulate

    done = resimulate(
        args.recording,
        args.out,
        preset=args.preset,
        measured=args.measured,
        overwrite=args.overwrite,
        compression=args.compression,
    )
    print(f"brake-sim resim: {done.describe()}")
    return 0


def cmd_view(args: argparse.Namespace) -> int:
    from brake_sim_ros.viz.commands import cmd_view as view

    return view(args)


# --- validate ------------------------------------------------------------------------------------
def cmd_validate(args: argparse.Namespace) -> int:
    from brake_sim_ros.studies.validation import write_report

    out = Path(args.out)
    _fig, check_list = write_report(
        out,
        Path(args.json) if args.json else None,
        progress=lambda name: print(f"running {name}", file=sys.stderr),
    )
    passed = sum(c.passed for c in check_list)
    limits = sum(bool(c.model_limit) for c in check_list)
    for c in check_list:
        why = f" [beyond the model: {c.model_limit}]" if c.model_limit else ""
        print(
            f"{'ok  ' if c.passed else 'MISS'} {c.what}: published {c.published},"
            f" model {c.model} ({c.difference}){why}"
        )
    print(
        f"{passed}/{len(check_list)} checks within their bands"
        + (f", {limits} beyond the model (see the report's notes)" if limits else "")
        + f"; report: {out / 'report.md'}"
    )
    return 0


# --- scenarios ---------------------------------------------------------------------------------
def cmd_scenarios(args: argparse.Namespace) -> int:
    from brake_sim_ros.scenarios import builtin_names, load_scenario

    if args.channels is not None:
        print(channels_text(load_scenario(args.channels)))
        return 0
    for name in builtin_names():
        print(f"{name:24s} {load_scenario(name).description}")
    return 0


def channels_text(scenario: Scenario) -> str:
    """The measured series of ``scenario``'s sensors: name, unit, rate, what and where,
    the transducer class and any sensor faults, a line each; one line saying why there
    are none when its fidelity plan builds no sensors."""
    from brake_sim_ros.stream.build import measures

    if not measures(scenario):
        return (
            f"scenario {scenario.name}: no measured channels: its [needs] do not ask"
            " 'measured_signals', so its fidelity plan builds no sensors (no structure);"
            " add it to [needs] outputs to measure"
        )
    rate = scenario.sample_rate_hz
    lines = [f"scenario {scenario.name}: sensors at {rate:g} Hz samples (unit, rate, kind)"]
    for c in scenario.sensors.channels:
        where = f"{c.location} {c.axis}".strip()
        faults = ", ".join(f"{f.kind} from {f.onset_s:g} s" for f in c.faults) or "no faults"
        for name in c.output_names:
            lines.append(
                f"  {name:28s} {c.unit:6s} {rate / c.decimation(rate):9g} Hz  {c.kind} at"
                f" {where}, {c.transducer.name}; {faults}"
            )
    return "\n".join(lines)


def run_severity(argv: list[str]) -> int:
    """``brake-sim severity ...``: the study parses its own options."""
    from brake_sim_ros.studies import severity

    try:
        return severity.main(argv)
    except BrakeSimError as exc:
        print(f"brake-sim: error: {exc}", file=sys.stderr)
        return EXIT_ERROR


def cmd_defects(args: argparse.Namespace) -> int:
    from brake_sim_ros.scenarios.defect_help import catalogue_text

    print(catalogue_text())
    return 0


# --- sweep and dataset -----------------------------------------------------------------------
def cmd_sweep(args: argparse.Namespace) -> int:
    """``brake-sim sweep CAMPAIGN --out DIR``: the campaign checked and planned before the
    directory is made; then every run, resuming a sweep of the same campaign there."""
    from brake_sim_ros.campaigns import load_campaign
    from brake_sim_ros.datasets.sweep import sweep

    if args.workers is not None and not 1 <= args.workers <= 1024:
        raise BrakeSimError(f"--workers {args.workers}: allowed 1 to 1024 worker processes")
    campaign = load_campaign(args.campaign)
    summary, outcomes = sweep(
        campaign, Path(args.out), workers=args.workers, scheduler=args.scheduler, quiet=args.quiet
    )
    print(summary.describe(Path(args.out)))
    if summary.failed:
        first = next(o for o in outcomes.values() if o.status == "failed")
        print(
            f"brake-sim: error: {summary.failed} run(s) failed (errors in the manifest), the"
            f" first: {first.run_id}: {first.error}",
            file=sys.stderr,
        )
        return 1
    return 0


def cmd_dataset(args: argparse.Namespace) -> int:
    """``brake-sim dataset info DIR``: class balance per split, after the leakage and
    damage checks (non-zero exit with one line on either)."""
    from brake_sim_ros.datasets.reader import info_text, open_dataset

    print(info_text(open_dataset(args.directory)))
    return 0


def _figure(value: float | None) -> str:
    return "undefined" if value is None else f"{value:.3f}"


def _model_where(path: str) -> str:
    """How a --model file is named in messages."""
    from brake_sim_ros.recording.mcap_format import describe_path

    return f"--model {describe_path(path)}"


def _load_model(path: str, name: str | None) -> Detector:
    """The detector saved in ``path`` (``--model``): a built-in, or a user's whose class
    ``name`` names (``module:Class`` or ``path/to/file.py:Class``; the file never does)."""
    from brake_sim_ros.detection import saved
    from brake_sim_ros.detection.registry import BUILTIN, make_detector

    user = make_detector(name) if name is not None and name not in BUILTIN else None
    return saved.load(path, None if user else name, where=_model_where(path), user=user)


def cmd_fit(args: argparse.Namespace) -> int:
    """``brake-sim fit DIR --detector NAME --out MODEL.json``: fit a detector on one split
    and save it (``detection.saved``), for ``score --model`` and ``monitor --model``."""
    from brake_sim_ros.datasets.reader import open_dataset
    from brake_sim_ros.detection import evaluate, saved
    from brake_sim_ros.detection.registry import make_detector
    from brake_sim_ros.recording.output import atomic_output, probe_output

    dataset = open_dataset(args.directory)
    root = Path(args.directory)
    inputs = [root / "manifest.parquet", root / "campaign.lock"]
    samples = os.path.realpath(root / "samples")
    if os.path.commonpath([samples, os.path.realpath(Path(args.out).parent)]) == samples:
        # a file there would be read as one of the dataset's samples
        raise BrakeSimError(f"--out {args.out}: inside the dataset's samples; allowed elsewhere")
    probe_output(args.out, inputs=inputs, overwrite=args.overwrite, option="--out")
    try:
        detector = make_detector(args.detector)
        saved.check_savable(detector)  # before the work
        windows = evaluate.fit(detector, dataset, args.fit_split)
    except BrakeSimError:
        raise  # one line already (a user detector's keeps its traceback for --debug)
    except (ValueError, RuntimeError) as exc:
        raise BrakeSimError(" ".join(str(exc).split())) from None
    fitted_on = {"dataset": str(args.directory), "split": args.fit_split, "windows": windows}
    text = saved.dumps(detector, fitted_on=fitted_on)
    with atomic_output(args.out, inputs=inputs, overwrite=args.overwrite, option="--out") as tmp:
        tmp.write_text(text, encoding="utf-8")
    print(f"detector {detector.name} fitted on {args.fit_split} ({windows} windows): {args.out}")
    return 0


def cmd_score(args: argparse.Namespace) -> int:
    """``brake-sim score DIR --detector NAME [--detector NAME ...]``: fit each detector on
    one split (or load it: ``--model``), score it on another, print the headline figures
    and write the JSON (``detection.evaluate``) and, with ``--report``, the report
    (``detection.report``)."""
    import json

    from brake_sim_ros.datasets.reader import open_dataset
    from brake_sim_ros.detection import evaluate
    from brake_sim_ros.detection.registry import make_detector
    from brake_sim_ros.recording.output import check_output, replace_output

    dataset = open_dataset(args.directory)
    if not (args.hold_s >= 0.0 and args.hold_s <= 3600.0):
        raise BrakeSimError(f"--hold {args.hold_s!r}: allowed 0 to 3600 s")
    # without --detector: the saved detector the file holds, or rms
    names: list[str | None] = args.detector or ([None] if args.model else ["rms"])
    if args.out and len(names) > 1:
        raise BrakeSimError("--out with several --detector: allowed one detector (or --report)")
    if args.windows and len(names) > 1:
        raise BrakeSimError("--windows with several --detector: allowed one detector")
    if args.windows and not args.windows.endswith(".parquet"):
        raise BrakeSimError(f"--windows {args.windows!r}: allowed a FILE.parquet path")
    if args.model and len(names) > 1:
        raise BrakeSimError("--model with several --detector: allowed one detector")
    if args.model and args.fit_split is not None:
        raise BrakeSimError("--fit-split with --model: the saved detector is fitted already")
    inputs = [args.model] if args.model else []
    if args.out:
        check_output(args.out, inputs=inputs, overwrite=True, option="--out")  # before the work
    if args.windows:
        samples = os.path.realpath(Path(args.directory) / "samples")
        if os.path.commonpath([samples, os.path.realpath(Path(args.windows).parent)]) == samples:
            raise BrakeSimError(f"--windows {args.windows}: inside the dataset's samples")
        check_output(args.windows, inputs=inputs, overwrite=True, option="--windows")
    window_rows: list[dict] = []
    if args.report:
        _check_report_directory(args.report)
    scores = []
    for name in names:
        try:
            if args.model:
                detector = _load_model(args.model, name)
                fitted = f"loaded from {args.model}"
            else:
                detector = make_detector(name or "rms")
                fit_split = args.fit_split or "train"
                windows = evaluate.fit(detector, dataset, fit_split)
                fitted = f"fitted on {fit_split} ({windows} windows)"
            score = evaluate.score(
                detector, dataset, args.split, hold_s=args.hold_s, windows=window_rows
            )
        except BrakeSimError:
            raise
        except (ValueError, RuntimeError) as exc:  # the detector's, or the dataset's, one line
            raise BrakeSimError(" ".join(str(exc).split())) from None
        scores.append(score)
        d, fa, hi = score["detection"], score["false_alarms"], score["health_index"]
        median = d["median_delay_s"]
        delay = "" if median is None else f" (median delay {median:.3f} s)"
        sev = score["severity"]
        severity = "" if sev is None else f"; severity rmse {sev['rmse']:.4g} (mixed units)"
        print(
            f"detector {score['detector']} {fitted},"
            f" scored on {args.split}: {score['runs']} runs; detected {d['detected']} of"
            f" {d['defective_runs']} defective runs{delay};"
            f" {fa['count']} false alarms in {fa['healthy_hours'] * 3600:.1f} s of healthy"
            f" operation; AUROC {_figure(hi['auroc'])}, AUPRC {_figure(hi['auprc'])}{severity}"
        )
        for label, figures in ({} if sev is None else sev["per_class"]).items():
            print(
                f"  severity {label}: rmse {figures['rmse']:.4g} {figures['unit']}"
                f" ({100 * figures['rmse_of_service_limit']:.0f} % of the service limit),"
                f" mean error {figures['mean_error']:+.4g} over {figures['windows']} windows"
            )
        forecast = score["forecast"]
        if forecast is not None:
            print(
                f"  remaining useful life: rmse {forecast['rmse_s']:.4g} s, mean error"
                f" {forecast['mean_error_s']:+.4g} s, asymmetric score"
                f" {forecast['rul_score']:.4g} over {forecast['windows']} windows"
            )
    if args.out:
        text = json.dumps(scores[0], indent=1, sort_keys=True)
        replace_output(args.out, lambda tmp: tmp.write_text(text + "\n"))
        print(f"JSON: {args.out}")
    if args.windows:
        _write_windows(args.windows, window_rows)
    if args.report:
        from brake_sim_ros.detection.report import report_files

        files = report_files(scores)
        for name in files:  # every file's rules before the first is written
            check_output(Path(args.report) / name, inputs=inputs, overwrite=True, option="--report")
        for name, content in files.items():
            replace_output(
                Path(args.report) / name,
                lambda tmp, c=content: tmp.write_bytes(c),
                option="--report",
            )
        print(f"report: {', '.join(files)} in {args.report}")
    return 0


def _write_windows(path: str, rows: list[dict]) -> None:
    """``score --windows``: every assessed window as Parquet, written whole."""
    import pyarrow.parquet as pq

    from brake_sim_ros.detection.windows import windows_table
    from brake_sim_ros.recording.output import replace_output

    table = windows_table(rows)
    replace_output(path, lambda tmp: pq.write_table(table, tmp), option="--windows")
    print(f"windows: {table.num_rows} in {path}")


def _check_report_directory(directory: str) -> None:
    """Refuse a report directory that is a link or not a directory, before any work."""
    from brake_sim_ros.recording.mcap_format import describe_path

    out = Path(directory)
    if out.is_symlink():
        raise BrakeSimError(f"--report {describe_path(out)}: a link; allowed a directory path")
    if out.exists() and not out.is_dir():
        raise BrakeSimError(f"--report {describe_path(out)}: not a directory")


def cmd_plot(args: argparse.Namespace) -> int:
    """``brake-sim plot SOURCE --out FILE.png``: one run drawn headless
    (:mod:`brake_sim_ros.detection.plot`)."""
    from brake_sim_ros.detection import plot
    from brake_sim_ros.recording.output import atomic_output, probe_output

    if not args.out.endswith(".png"):
        raise BrakeSimError(f"--out {args.out!r}: allowed a FILE.png path")
    probe_output(args.out, inputs=[args.source], overwrite=args.overwrite, option="--out")
    try:
        columns, name = plot.read_run(args.source, args.run)
        windows = None if args.windows is None else plot.read_windows(args.windows, name)
        with atomic_output(args.out, overwrite=args.overwrite, option="--out") as tmp:
            plot.draw(columns, tmp, title=name, windows=windows)
    except ValueError as exc:
        raise BrakeSimError(" ".join(str(exc).split())) from None
    print(f"plot: {args.out}")
    return 0


# --- unit ----------------------------------------------------------------------------
def cmd_unit(args: argparse.Namespace) -> int:
    from brake_sim_ros.scenarios import load_scenario

    for flag, value in (("--seed", args.seed), ("--fleet-seed", args.fleet_seed)):
        if value is not None and not 0 <= value < 2**63:
            raise BrakeSimError(f"{flag} {value}: allowed an integer from 0 to 2^63 - 1")
    scenario = load_scenario(args.scenario).with_unit(
        args.unit_id, seed=args.seed, fleet_seed=args.fleet_seed
    )
    print(unit_text(scenario, sources=args.sources))
    return 0


def _shown(value: float, unit: str) -> tuple[float, str]:
    """A value in the unit a table shows it in (m as mm, Pa as GPa)."""
    scale = {"m": (1e3, "mm"), "Pa": (1e-9, "GPa")}.get(unit)
    return (value * scale[0], scale[1]) if scale else (value, unit)


def unit_text(scenario: Scenario, *, sources: bool = False) -> str:
    """A scenario's brake unit against the scenario's own values: per scattered parameter
    its nominal value, the unit's, the change and the tolerance, with units; with
    ``sources``, where each distribution comes from."""
    from brake_sim_ros.fleet.scatter import NOMINAL_UNIT

    values = scenario.unit_values()
    lines = [
        f"unit {scenario.unit_id} (fleet seed {scenario.fleet_seed}) of scenario {scenario.name}:"
        " manufacturing scatter, each a normal truncated at its tolerance"
        + (
            " (the nominal unit: the scenario's brake itself)"
            if scenario.unit_id == NOMINAL_UNIT
            else ""
        ),
        f"  {'parameter':46s} {'nominal':>12s} {'this unit':>12s} {'change':>10s}"
        f"  {'in':9s}  tolerance",
    ]
    for v in values:
        nominal, shown = _shown(v.nominal, v.unit)
        value, _ = _shown(v.value, v.unit)
        if v.scatter.mode == "relative":
            change = f"{100 * (v.value / v.nominal - 1):+.3f} %" if v.nominal else "-"
        else:
            change = f"{value - nominal:+.4g}"
        lines.append(
            f"  {v.key:46s} {nominal:12.6g} {value:12.6g} {change:>10s}  {shown:9s}"
            f"  {v.scatter.describe(v.unit)}"
        )
        if sources:
            lines.append(f"      {v.scatter.source}")
    if not sources:
        lines.append("  (where each distribution comes from: --sources)")
    for name, truth in scenario.conditions_record().items():
        low, high = truth["range"]
        lines.append(
            f"  condition {name} = {truth['value']:.6g} {truth['unit']} (drawn from"
            f" [{low:g}, {high:g}] with seed {scenario.seed})"
        )
    return "\n".join(lines)


# --- bench ---------------------------------------------------------------------------
def cmd_bench(args: argparse.Namespace) -> int:
    return int(BENCHMARKS[args.what].run(args.rest) or 0)


def run_node(argv: list[str]) -> int:
    """``brake-sim node ...``: the node parses its own options and ``--ros-args``."""
    from brake_sim_ros.app.node import main as node_main

    return node_main(["brake-sim node", *argv]) or 0


LIVE_OUT_DIR = Path("bags/live")


def run_live(argv: list[str]) -> int:
    """``brake-sim live [SCENARIO]``: the main job. The node streams the scenario in real time
    over ROS 2, records what it publishes to MCAP and writes a Rerun recording beside it
    (and opens a viewer where a display exists); then it says where both are."""
    from brake_sim_ros.app.node import main as node_main
    from brake_sim_ros.viz.targets import has_display

    parser = argparse.ArgumentParser(
        prog="brake-sim live",
        description="Stream a scenario through the ROS 2 node in real time, recording it to"
        " MCAP and Rerun. Other options (--ros-args ...) go to the node.",
    )
    parser.add_argument("scenario", nargs="?", default="symmetric", help="default: symmetric")
    parser.add_argument(
        "--out-dir", type=Path, default=LIVE_OUT_DIR, help=f"default: {LIVE_OUT_DIR}/"
    )
    parser.add_argument("--no-viewer", action="store_true", help="do not open a Rerun viewer")
    parser.add_argument("--duration", metavar="S", help="simulated seconds (node option)")
    args, node_args = parser.parse_known_args(argv)
    if args.duration is not None:
        node_args = ["--duration", args.duration, *node_args]
    stem = Path(args.scenario).stem if args.scenario.endswith(".toml") else args.scenario
    base = args.out_dir / f"{stem}-{time.strftime('%Y%m%d-%H%M%S')}"
    mcap, rrd = base.with_suffix(".mcap"), base.with_suffix(".rrd")
    args.out_dir.mkdir(parents=True, exist_ok=True)
    options = ["--scenario", args.scenario, "--exit-at-end", "--record", str(mcap)]
    options += ["--rerun", "save", str(rrd)]
    viewer = has_display() and not args.no_viewer
    if viewer:
        options += ["--rerun", "spawn"]
    code = node_main(["brake-sim live", *options, *node_args]) or 0
    written = [f for f in (mcap, rrd) if f.is_file()]
    for f in written:
        print(f"wrote {f} ({f.stat().st_size / 1e6:.1f} MB)")
    if mcap in written:
        print(
            f"  replay on ROS 2:   .venv/bin/brake-sim replay {mcap}\n"
            f"  view in Rerun:     .venv/bin/brake-sim view {mcap}\n"
            f"  Foxglove / ros2 bag: open {mcap} in Foxglove, or `ros2 bag info` where a"
            " ROS 2 install has rosbag2 (the set-up does not install it)"
        )
    if rrd in written:
        print(f"  open the Rerun recording: .venv/bin/rerun {rrd}")
    if not viewer:
        print("  (no display here, so no viewer was opened)" if not args.no_viewer else "")
    return code


def run_replay(argv: list[str]) -> int:
    """``brake-sim replay FILE.mcap ...``: publishes a recording on ROS 2 (own options)."""
    from brake_sim_ros.app.replay import main as replay_main

    return replay_main(["brake-sim replay", *argv]) or 0


# --- monitor ------------------------------------------------------------------------
def _monitor_parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="brake-sim monitor",
        description="Run a detector as a ROS 2 node on a brake's measured channels"
        " (<simulator>/measured, MeasuredChunk: the simulator, a replay, or a real brake's"
        " driver) and publish its health index (/brake_monitor/health), diagnoses"
        " (/brake_monitor/diagnoses) and /diagnostics status. ROS options go after"
        " --ros-args.",
    )
    p.add_argument("--detector", required=True, help=detector_help())
    p.add_argument(
        "--simulator",
        metavar="NODE",
        help="node whose NODE/measured and NODE/defects are read (default /brake_sim)",
    )
    p.add_argument("--measured-topic", metavar="TOPIC", help="default NODE/measured")
    p.add_argument(
        "--unit-id", metavar="ID", help="unit id in the outputs (default: DefectState's)"
    )
    p.add_argument(
        "--fit",
        metavar="DIR",
        help="fit the detector on a sweep's dataset first (brake-sim sweep ... --out DIR)",
    )
    p.add_argument("--fit-split", default="train", help="split to fit on (default train)")
    p.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    p.add_argument(
        "--model",
        metavar="MODEL.json",
        help="load the fitted detector from this file (brake-sim fit) instead of --fit",
    )
    return p


def _topic_name(parser: argparse.ArgumentParser, option: str, name: str) -> str:
    """``name`` if ROS accepts it as an absolute topic name; else a one-line error."""
    from rclpy.exceptions import InvalidTopicNameException
    from rclpy.validate_full_topic_name import validate_full_topic_name

    try:
        validate_full_topic_name(name)
    except InvalidTopicNameException:
        shown = "".join(c if c.isprintable() else "?" for c in name[:80])
        parser.error(f"{option} {shown!r}: allowed an absolute ROS name such as /brake_sim")
    return name


def run_monitor(argv: list[str]) -> int:
    """``brake-sim monitor --detector NAME ...``: build (and fit) the detector here, then run
    the node (:mod:`brake_sim_ros.app.monitor`) until interrupted. Bad options (--ros-args
    parameters too), a detector that cannot be made or fitted: one line, exit 2."""
    from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
    from rclpy.utilities import remove_ros_args

    from brake_sim_ros.detection.detector import chunk_from_measured

    parser = _monitor_parser()
    try:
        own = remove_ros_args(["brake-sim monitor", *argv])[1:]
    except _rclpy.RCLInvalidROSArgsError as exc:  # rcl's message ends with its source lines
        parser.error(f"--ros-args: {str(exc).split(', at /')[0]}")
    args = parser.parse_args(own)
    overrides: list[tuple[str, object]] = []  # they override --ros-args -p values
    if args.simulator is not None:
        overrides.append(("simulator", _topic_name(parser, "--simulator", args.simulator)))
    if args.measured_topic is not None:
        topic = _topic_name(parser, "--measured-topic", args.measured_topic)
        overrides.append(("measured_topic", topic))
    if args.unit_id is not None:
        overrides.append(("unit_id", args.unit_id))
    detector = _monitor_detector(parser, args)
    from brake_sim_ros.app.monitor import run

    return run(["brake-sim monitor", *argv], detector, chunk_from_measured, overrides=overrides)


def _monitor_detector(parser: argparse.ArgumentParser, args: argparse.Namespace) -> Detector:
    """The monitor's detector: loaded (``--model``), or made and fitted (``--fit``)."""
    from brake_sim_ros.detection.registry import REGISTRY, make_detector

    if args.model is not None:
        if args.fit is not None:
            parser.error("--model and --fit: allowed one (a saved detector, or a dataset)")
        try:
            detector = _load_model(args.model, args.detector)
        except ValueError as exc:  # ModelFileError too
            parser.error(str(exc))
        print(f"brake-sim monitor: {detector.name} loaded from {args.model}")
        return detector
    try:
        detector = make_detector(args.detector)
    except ValueError as exc:
        parser.error(str(exc))
    # a built-in that learns cannot assess unfitted; a user's class may come ready-made
    entry = REGISTRY.get(args.detector)
    if entry is not None and entry.learns and args.fit is None:
        parser.error(
            f"detector {detector.name} learns from data: give --fit DIR, a sweep's dataset"
            " (brake-sim sweep) to fit it on, or --model MODEL.json (brake-sim fit)"
        )
    if args.fit is not None:
        from brake_sim_ros.datasets.reader import open_dataset
        from brake_sim_ros.detection import evaluate

        try:
            windows = evaluate.fit(detector, open_dataset(args.fit), args.fit_split)
        except (BrakeSimError, ValueError, RuntimeError) as exc:
            parser.error(f"--fit {args.fit}: {exc}")
        print(f"brake-sim monitor: {detector.name} fitted on {windows} windows of {args.fit_split}")
    return detector


class _Parser(argparse.ArgumentParser):
    """argparse, but a bad command line is one line on stderr (exit 2), not the usage."""

    def error(self, message: str) -> NoReturn:
        text = " ".join(message.split())
        text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
        if len(text) > 500:
            text = text[:400] + " ... " + text[-60:]
        self.exit(EXIT_ERROR, f"{self.prog}: error: {text} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """Every command's parser (but node, live, monitor, replay and severity: their own)."""
    parser = _Parser(prog="brake-sim", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"brake-sim-ros {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser(
        "simulate",
        help="run a scenario offline and summarise it",
        description="Run a scenario offline and summarise it. Everything is checked before"
        " the run: outputs go to new files in existing directories (--overwrite replaces a"
        " file; never a link, never the scenario file), each written whole or not at all.",
    )
    p.add_argument("scenario", help="built-in scenario name or path to a .toml file")
    p.add_argument(
        "--out",
        help="write the full time history (.npz, .csv, or .parquet with the measured sensor"
        " channels)",
    )
    p.add_argument(
        "--duration",
        type=float,
        metavar="S",
        help=f"simulated seconds, > 0 and at most {MAX_SIMULATE_DURATION_S:g} (default: the"
        f" scenario's); the kept history may take at most {MAX_HISTORY_BYTES / 1e9:.1f} GB",
    )
    p.add_argument(
        "--preset",
        choices=tuple(PRESETS),
        help="solver preset (scheme and largest physics step); replaces the scenario's solver",
    )
    p.add_argument("--method", choices=SOLVER_METHODS, help="override the solver method")
    p.add_argument(
        "--max-step", type=float, metavar="S", help="override the largest physics step, s"
    )
    p.add_argument(
        "--sample-rate",
        type=float,
        metavar="HZ",
        help="override the scenario's output sample rate (default 25600 Hz)",
    )
    # retired: a one-line pointer, whatever follows it
    p.add_argument("--dt", nargs="?", const="", help=argparse.SUPPRESS)
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.add_argument(
        "--rerun",
        action="append",
        nargs="+",
        metavar="TARGET",
        help="also log the node's stream to Rerun: spawn | connect [URL] | serve |"
        " save FILE.rrd (repeatable)",
    )
    p.add_argument("--mcap", help="also write the node's message stream to this MCAP file")
    p.add_argument("--mcap-compression", choices=("zstd", "none"), default="zstd")
    p.add_argument(
        "--overwrite", action="store_true", help="replace existing output files (never a link)"
    )
    p.set_defaults(func=cmd_simulate)

    p = sub.add_parser("view", help="show an MCAP recording in Rerun, or convert it to .rrd")
    p.add_argument("recording", help="MCAP file recorded from the simulator")
    p.add_argument("--save", metavar="FILE.rrd", help="write a Rerun file instead of a viewer")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --save file")
    p.set_defaults(func=cmd_view)

    p = sub.add_parser(
        "recover", help="keep every intact chunk of a cut-short or damaged MCAP recording"
    )
    p.add_argument("broken", help="the damaged .mcap file (only read)")
    p.add_argument("fixed", help="the .mcap file to write (not the input, not a link)")
    p.add_argument("--overwrite", action="store_true", help="replace FIXED if it exists")
    p.set_defaults(func=cmd_recover)

    p = sub.add_parser(
        "resim",
        help="re-simulate a recorded run offline, its commands at their recorded samples",
        description="Re-simulate the run a brake-sim recording holds (brake-sim node --record,"
        " live, simulate --mcap) from the recording alone: its scenario text, unit, seed,"
        " model and settings, and every actuation and drive command at the sample it took"
        " effect at. Writes the node's stream to a new MCAP file (never the input, never"
        " through a link, whole or not at all) and says whether the samples equal the"
        " recording's bit for bit (they do with the same preset and sensors).",
    )
    p.add_argument("recording", help="the .mcap file recorded (only read)")
    p.add_argument("--out", required=True, metavar="NEW.mcap", help="the .mcap file to write")
    p.add_argument(
        "--preset",
        choices=tuple(PRESETS),
        help="another solver preset (default: the recorded scenario's)",
    )
    p.add_argument(
        "--measured",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="run the scenario's sensors and record ~/measured, or not (default: as the run)",
    )
    p.add_argument("--compression", choices=("zstd", "none"), default="zstd")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    p.set_defaults(func=cmd_resim)

    p = sub.add_parser("validate", help="run the study's cases and write the validation report")
    p.add_argument("--out", default="out/validation", help="report directory")
    p.add_argument("--json", help="also write the figures as JSON to this file")
    p.set_defaults(func=cmd_validate)

    p = sub.add_parser("scenarios", help="list the built-in scenarios")
    p.add_argument(
        "--channels",
        metavar="NAME",
        help="list the measured sensor channels of scenario NAME (built-in or .toml), with"
        " units and rates",
    )
    p.set_defaults(func=cmd_scenarios)

    p = sub.add_parser(
        "defects", help="list the defect catalogue: kinds, locations, units, valid ranges"
    )
    p.set_defaults(func=cmd_defects)

    p = sub.add_parser(
        "unit",
        help="a brake unit's manufacturing scatter: its parameters against the scenario's",
        description="Print brake unit UNIT_ID's parameters against the scenario's own"
        " (nominal) values, with units and each distribution's tolerance. A unit is drawn"
        " from its id and the fleet seed (the same brake in every run); 'nominal' is the"
        " scenario's brake itself. The run's seed draws the scenario's [conditions].",
    )
    p.add_argument("unit_id", help=f"the unit's id: {IDENTIFIER_RULE}; or nominal")
    p.add_argument(
        "--fleet-seed",
        type=int,
        help="the fleet's seed, which draws units (default: the scenario's)",
    )
    p.add_argument(
        "--seed", type=int, help="the run's seed: its [conditions] (default: the scenario's)"
    )
    p.add_argument(
        "--scenario", default="symmetric", help="built-in name or .toml path (default symmetric)"
    )
    p.add_argument("--sources", action="store_true", help="say where each distribution comes from")
    p.set_defaults(func=cmd_unit)

    sub.add_parser(  # parsed by the study (main() hands it the arguments)
        "severity",
        help="sweep each defect from healthy to its service limit and report how signal"
        " features move: brake-sim severity [--out DIR] [--duration S]",
    )

    p = sub.add_parser(
        "sweep",
        help="run a campaign (built-in name or .toml) into a labelled, leak-free Parquet"
        " dataset: brake-sim sweep demo --out DIR",
        description="Run every run of a campaign into DIR: manifest.parquet, samples/run=*/"
        " (Parquet, hive-partitioned), campaign.lock. Running it again resumes: finished runs"
        " whose files check out are skipped. DIR must be new, empty, or this campaign's.",
    )
    p.add_argument("campaign", help="built-in campaign name (demo, reference) or .toml path")
    p.add_argument("--out", required=True, metavar="DIR", help="output directory")
    p.add_argument(
        "--workers", type=int, metavar="N", help="local worker processes (default: every core)"
    )
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on an existing Dask cluster (tcp://host:8786) whose workers share DIR",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_sweep)

    p = sub.add_parser("dataset", help="inspect a sweep's dataset: brake-sim dataset info DIR")
    dataset_sub = p.add_subparsers(dest="dataset_command", required=True)
    q = dataset_sub.add_parser(
        "info", help="runs, units and class balance per split; checks leakage and damage"
    )
    q.add_argument("directory", help="a sweep's output directory")
    q.set_defaults(func=cmd_dataset)

    p = sub.add_parser(
        "score",
        help="fit a detector on a dataset's train split and score it on test",
        description="Fit a detector on one split of a sweep's dataset and score it on"
        " another: detection delay, false alarms per healthy hour, AUROC/AUPRC of its"
        " health index (brake_sim_ros.detection.evaluate documents the JSON).",
    )
    p.add_argument("directory", help="a sweep's output directory")
    p.add_argument(
        "--detector",
        action="append",
        help=detector_help() + " (default rms); repeat it to score several",
    )
    p.add_argument("--split", default="test", help="split to score (default test)")
    p.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    p.add_argument("--fit-split", help="split to fit on (default train; not with --model)")
    p.add_argument(
        "--hold", dest="hold_s", type=float, default=0.2, help="alarm hold, s (default 0.2)"
    )
    p.add_argument("--out", help="write the score as JSON here (one detector)")
    p.add_argument(
        "--windows",
        metavar="FILE.parquet",
        help="write every assessed window (run, time, health index, alarm, diagnosis, truth,"
        " class) here, to compute any metric (one detector)",
    )
    p.add_argument(
        "--model",
        metavar="MODEL.json",
        help="load the fitted detector from this file (brake-sim fit) instead of fitting it;"
        " --detector, if given, must name the file's",
    )
    p.add_argument(
        "--report",
        metavar="DIR",
        help="write each detector's JSON and the figures (ROC, delays, isolation) here",
    )
    p.set_defaults(func=cmd_score)

    p = sub.add_parser(
        "fit",
        help="fit a detector on a dataset's train split and save it as JSON",
        description="Fit a detector on one split of a sweep's dataset and save it, fitted,"
        " as a JSON file (brake_sim_ros.detection.saved documents it) that score --model"
        " and monitor --model load instead of refitting. Saved forms: "
        + ", ".join(detector_names(saved_only=True))
        + ", and your Detector's with saved_state and load_state.",
    )
    p.add_argument("directory", help="a sweep's output directory")
    p.add_argument("--detector", required=True, help=detector_help(saved_only=True))
    p.add_argument("--fit-split", default="train", help="split to fit on (default train)")
    p.add_argument("--out", required=True, metavar="MODEL.json", help="the file to write")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    p.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    p.set_defaults(func=cmd_fit)

    p = sub.add_parser(
        "plot",
        help="draw one run to a PNG: measured channels with defect labels and drive phases,"
        " a spectrogram, the tone ring's orders, a detector's health index",
    )
    p.add_argument("source", help="a simulate --out file (.parquet, .npz) or a dataset directory")
    p.add_argument("--run", metavar="RUN_ID", help="the dataset's run to draw")
    p.add_argument(
        "--windows", metavar="FILE.parquet", help="a score --windows file: draw its health index"
    )
    p.add_argument("--out", required=True, metavar="FILE.png", help="the PNG to write")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    p.set_defaults(func=cmd_plot)

    p = sub.add_parser(
        "bench",
        help="benchmarks that print figures: "
        + "; ".join(f"{s.name}: {s.measures}" for s in BENCHMARKS.values()),
    )
    p.add_argument("what", choices=tuple(BENCHMARKS))
    p.add_argument("rest", nargs=argparse.REMAINDER)
    p.set_defaults(func=cmd_bench)

    # handled before parsing (see main), listed here for --help
    sub.add_parser(
        "node",
        help="run the ROS 2 node: brake-sim node [--scenario S] [--duration S]"
        " [--exit-at-end] [--ros-args ...]",
    )
    sub.add_parser(
        "live",
        help="the main job: stream a scenario through the node in real time, recording MCAP"
        " and Rerun under bags/live/: brake-sim live [SCENARIO] [--duration S] [--no-viewer]",
    )
    sub.add_parser(
        "monitor",
        help="run a detector as a ROS 2 node on the measured channels and publish its health"
        " index, diagnoses and /diagnostics: brake-sim monitor --detector NAME"
        " [--simulator /brake_sim] [--fit DIR | --model MODEL.json] [--ros-args ...]",
    )
    sub.add_parser(
        "replay",
        help="publish an MCAP recording on ROS 2 with its original timing: brake-sim replay"
        " FILE.mcap [--rate R] [--start-offset S] [--loop] [--topics T ...] [--ros-args ...]",
    )
    return parser


DEBUG_HELP = "on a user detector's error, show its traceback too"
# commands that run the physics kernels (compiled on first use)
PHYSICS_COMMANDS = (
    "node", "live", "simulate", "resim", "validate", "bench", "severity", "sweep",
)  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    """``brake-sim ...``: the exit status (0, or a one-line error's)."""
    try:
        return _main(argv)
    except BrokenPipeError:
        # the reader of stdout went away (`brake-sim defects | head`): no traceback, and no
        # second error when Python flushes stdout at exit
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return EXIT_BROKEN_PIPE


def _main(argv: list[str] | None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] and argv[0] in PHYSICS_COMMANDS and not {"-h", "--help"} & set(argv):
        from brake_sim_ros.solvers.warmup import ensure_compiled

        ensure_compiled()  # says so, once per installed version, instead of a silent pause
    if argv[:1] == ["node"]:
        return run_node(argv[1:])
    if argv[:1] == ["replay"]:
        return run_replay(argv[1:])
    if argv[:1] == ["monitor"]:
        try:
            return run_monitor(argv[1:])
        except BrakeSimError as exc:
            _debug_traceback(exc, "--debug" in argv)
            print(f"brake-sim monitor: error: {exc}", file=sys.stderr)
            return EXIT_ERROR
    if argv[:1] == ["live"]:
        return run_live(argv[1:])
    if argv[:1] == ["severity"]:
        return run_severity(argv[1:])
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except BrakeSimError as exc:
        _debug_traceback(exc, getattr(args, "debug", False))
        print(f"brake-sim: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        print("brake-sim: interrupted", file=sys.stderr)
        return 130


def _debug_traceback(exc: BaseException, debug: bool) -> None:
    """With ``--debug``, the traceback of a user detector's error before its one line."""
    text = getattr(exc, "traceback_text", "")
    if debug and text:
        print(text.rstrip(), file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())
