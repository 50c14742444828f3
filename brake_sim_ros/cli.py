"""One entry point: ``brake-sim <command>``.

Every command exits 0 on success and non-zero with a one-line reason on failure.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from brake_sim_ros import __version__
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.scenarios.loader import SOLVER_METHODS
from brake_sim_ros.solvers.presets import PRESETS

if TYPE_CHECKING:  # the CLI imports the numerics only when a command needs them
    from brake_sim_ros.analysis.impacts import ShoeMetrics
    from brake_sim_ros.scenarios.loader import Scenario
    from brake_sim_ros.solvers.run import RunResult

EXIT_ERROR = 2


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
def _write_history(path: Path, result, scenario) -> None:
    columns = result.samples.as_dict()
    meta = {
        "scenario": scenario.name,
        "source": scenario.source,
        "method": result.method,
        "stop_time_s": result.stop_time_s,
        "version": __version__,
        "sample_period_s": result.samples.sample_period_s,
        "sample_rate_hz": scenario.sample_rate_hz,
        "preset": scenario.solver.preset,
        "step": result.step_note,
        "scenario_toml": scenario.text,
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix == ".npz":
        np.savez_compressed(path, **columns, metadata=np.array(json.dumps(meta)))
    elif path.suffix == ".csv":
        names = list(columns)
        data = np.column_stack([columns[n] for n in names])
        np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.10g")
    else:
        raise BrakeSimError(
            f"output file {path}: allowed suffixes .npz (numpy; pandas via"
            " pd.DataFrame(dict(np.load(f)))) or .csv"
        )


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
    unit = {"reference": "f-evals", "contact_regime": "RK4 steps"}.get(
        result.method, "physics steps"
    )
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
    for side in ("left", "right"):
        if not any(c.startswith(f"{side}_") for c in result.samples.columns):
            lines.append(f"  {side:5s}: not asked for")
            continue
        lines.append(f"  {side:5s}: {_shoe_summary(m.shoe(side))}")
    return "\n".join(lines)


def cmd_simulate(args: argparse.Namespace) -> int:
    from brake_sim_ros.scenarios import load_scenario
    from brake_sim_ros.solvers.run import run_scenario

    if args.dt is not None:
        raise BrakeSimError(
            "--dt is gone: the output sample rate belongs to the scenario (--sample-rate HZ,"
            " default 25600) and the physics step is chosen below the step limit (--max-step S"
            " bounds it)"
        )
    # the overrides go into the scenario once: every output below runs the same stepper
    scenario = load_scenario(args.scenario).with_solver(
        preset=args.preset,
        method=args.method,
        max_step_s=args.max_step,
        sample_rate_hz=args.sample_rate,
    )
    rerun_targets = _rerun_targets(args)
    progress = _progress(f"simulating {scenario.name}") if not args.quiet else None
    result = run_scenario(scenario, duration_s=args.duration, progress=progress)
    print(simulate_summary(result, scenario))
    if args.out:
        _write_history(Path(args.out), result, scenario)
        print(
            f"time history: {args.out} ({len(result.samples)} samples x"
            f" {result.samples.data.shape[1]} columns)"
        )
    if args.mcap or rerun_targets:
        _write_stream(args, scenario, rerun_targets)
    return 0


def _write_stream(args: argparse.Namespace, scenario, rerun_targets: list) -> None:
    """The node's stream, produced offline once, into the MCAP file and the Rerun targets
    (``scenario`` carries the command line's solver and sample-rate overrides)."""
    if not args.mcap:
        from brake_sim_ros.viz.commands import simulate_to_rerun

        print(simulate_to_rerun(scenario, rerun_targets, duration_s=args.duration))
        return
    from brake_sim_ros.recording.record import record_offline
    from brake_sim_ros.recording.writer import RecordingOptions

    if args.method == "reference":
        raise BrakeSimError("--mcap records the node's fixed-step stream: drop --method reference")
    sinks = []
    if rerun_targets:
        from brake_sim_ros.viz.commands import finish_simulation_sinks, open_simulation_sinks

        sinks = open_simulation_sinks(scenario, rerun_targets)
    options = RecordingOptions(compression=args.mcap_compression, durable=False)
    try:
        recording = record_offline(
            scenario, args.mcap, duration_s=args.duration, options=options, also=sinks
        )
    except BaseException:
        for sink in sinks:
            sink.close()
        raise
    print(recording.describe())
    if sinks:
        print(finish_simulation_sinks(sinks, rerun_targets))


# --- recover ---------------------------------------------------------------------------------
def cmd_recover(args: argparse.Namespace) -> int:
    from brake_sim_ros.recording.recover import recover

    print(recover(args.broken, args.fixed, overwrite=args.overwrite).describe())
    return 0


def _rerun_targets(args: argparse.Namespace) -> list:
    """``simulate --rerun ...`` targets, checked before the run (empty without the option)."""
    if not args.rerun:
        return []
    if args.method == "reference":
        raise BrakeSimError(
            "--rerun logs the fixed-step stream the node publishes: it cannot be combined"
            " with --method reference"
        )
    from brake_sim_ros.viz.commands import parse_targets

    return parse_targets(args.rerun)


def cmd_view(args: argparse.Namespace) -> int:
    from brake_sim_ros.viz.commands import cmd_view as view

    return view(args)


# --- validate ------------------------------------------------------------------------------------
def cmd_validate(args: argparse.Namespace) -> int:
    from brake_sim_ros.analysis.validation import write_report

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

    for name in builtin_names():
        print(f"{name:24s} {load_scenario(name).description}")
    return 0


# --- bench ---------------------------------------------------------------------------
# benchmark name -> (module with main(argv), what it measures); imported only when run
BENCHMARKS = {
    "core": ("brake_sim_ros.solvers.benchmark", "cost and accuracy of the fixed-step stepper"),
    "accuracy": (
        "brake_sim_ros.solvers.work_precision",
        "work-precision study of every solver and preset (table and plot)",
    ),
    "presets": (
        "brake_sim_ros.solvers.preset_study",
        "each preset's errors over onset phases, against its stated bounds",
    ),
    "node": ("brake_sim_ros.ros.benchmark", "the ROS node's real-time figures"),
    "recording": (
        "brake_sim_ros.recording.benchmark",
        "MCAP recording throughput, CPU at real time and size per simulated second",
    ),
    "realtime": (
        "brake_sim_ros.solvers.realtime_benchmark",
        "worst-case cost per streaming chunk, against the real-time budget",
    ),
    "fidelity": (
        "brake_sim_ros.solvers.fidelity_study",
        "cost and error of each fidelity level against the full model",
    ),
}


def cmd_bench(args: argparse.Namespace) -> int:
    import importlib

    module, _what = BENCHMARKS[args.what]
    return int(importlib.import_module(module).main(args.rest) or 0)


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


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="brake-sim", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"brake-sim-ros {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("simulate", help="run a scenario offline and summarise it")
    p.add_argument("scenario", help="built-in scenario name or path to a .toml file")
    p.add_argument("--out", help="write the full time history (.npz or .csv)")
    p.add_argument("--duration", type=float, help="simulated seconds (default: the scenario's)")
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
    p.add_argument("--dt", type=float, help=argparse.SUPPRESS)  # retired: a one-line pointer
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

    p = sub.add_parser("validate", help="run the study's cases and write the validation report")
    p.add_argument("--out", default="out/validation", help="report directory")
    p.add_argument("--json", help="also write the figures as JSON to this file")
    p.set_defaults(func=cmd_validate)

    p = sub.add_parser("scenarios", help="list the built-in scenarios")
    p.set_defaults(func=cmd_scenarios)

    p = sub.add_parser(
        "bench",
        help="benchmarks that print figures: "
        + "; ".join(f"{name}: {what}" for name, (_m, what) in BENCHMARKS.items()),
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
        "replay",
        help="publish an MCAP recording on ROS 2 with its original timing: brake-sim replay"
        " FILE.mcap [--rate R] [--start-offset S] [--loop] [--topics T ...] [--ros-args ...]",
    )
    return parser


# commands that run the physics kernels (compiled on first use)
PHYSICS_COMMANDS = ("node", "live", "simulate", "validate", "bench")


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] and argv[0] in PHYSICS_COMMANDS and not {"-h", "--help"} & set(argv):
        from brake_sim_ros.solvers.warmup import ensure_compiled

        ensure_compiled()  # says so, once per installed version, instead of a silent pause
    if argv[:1] == ["node"]:
        return run_node(argv[1:])
    if argv[:1] == ["replay"]:
        return run_replay(argv[1:])
    if argv[:1] == ["live"]:
        return run_live(argv[1:])
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except BrakeSimError as exc:
        print(f"brake-sim: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        print("brake-sim: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
