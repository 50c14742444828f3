"""``brake-sim simulate``: run a scenario offline, summarise it and write its outputs (the
time history, the node's stream as MCAP and Rerun), every option and output checked
before the run."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from brake_sim_ros.cli.common import Command, progress
from brake_sim_ros.errors import BrakeSimError

if TYPE_CHECKING:  # the numerics are imported when the command runs
    from brake_sim_ros.analysis.impacts import ShoeMetrics
    from brake_sim_ros.scenarios.types import Scenario
    from brake_sim_ros.stream.run import RunResult
    from brake_sim_ros.viz.targets import RerunTarget

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

    report = None if job.quiet else progress(f"simulating {job.scenario.name}")
    return run_scenario(job.scenario, duration_s=job.duration_s, progress=report)


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
    import numpy as np

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
    with contextlib.ExitStack() as stack:
        mcap = stack.enter_context(job.atomic("--mcap")) if "--mcap" in job.outputs else None
        targets = [
            dataclasses.replace(
                t, arg=str(stack.enter_context(job.atomic("--rerun save", Path(t.arg))))
            )
            if t.kind == "save"
            else t
            for t in job.rerun
        ]
        lines = _stream(job, mcap, targets)
    return lines


def _stream(job: SimulateJob, mcap: Path | None, targets: list[RerunTarget]) -> list[str]:
    scenario, lines = job.scenario, []
    sinks: list = []
    if targets:  # rerun is imported only for a run that writes to it (1.3 s of CPU)
        from brake_sim_ros.viz.commands import open_simulation_sinks

        sinks = open_simulation_sinks(scenario, targets)
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
        from brake_sim_ros.viz.commands import finish_simulation_sinks

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
    from brake_sim_ros.model.layout import SIDES
    from brake_sim_ros.solvers.methods import METHODS

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


def simulate_options(p: argparse.ArgumentParser) -> None:
    """``simulate``'s description and options."""
    from brake_sim_ros.solvers.methods import SOLVER_METHODS
    from brake_sim_ros.solvers.presets import PRESETS

    p.description = (
        "Run a scenario offline and summarise it. Everything is checked before"
        " the run: outputs go to new files in existing directories (--overwrite replaces a"
        " file; never a link, never the scenario file), each written whole or not at all."
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


SIMULATE = Command("simulate", "run a scenario offline and summarise it", simulate_options)
