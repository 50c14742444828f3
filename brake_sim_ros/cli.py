"""One entry point: ``brake-sim <command>``.

Every command exits 0 on success and non-zero with a one-line reason on failure.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from brake_sim_ros import __version__
from brake_sim_ros.errors import BrakeSimError

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


def cmd_simulate(args: argparse.Namespace) -> int:
    from brake_sim_ros.scenarios import load_scenario
    from brake_sim_ros.solvers.run import run_scenario

    scenario = load_scenario(args.scenario)
    progress = _progress(f"simulating {scenario.name}") if not args.quiet else None
    result = run_scenario(
        scenario, duration_s=args.duration, method=args.method, dt_s=args.dt, progress=progress
    )
    m = result.metrics
    sim_s = result.samples.time_s[-1] if len(result.samples) else 0.0
    rtf = sim_s / result.cpu_s if result.cpu_s > 0 else float("inf")
    stop = f"{m.stop_time_s:.4f} s" if m.stop_time_s is not None else "not stopped"
    unit = "steps" if result.method == "rk4" else "f-evals"
    print(
        f"scenario {scenario.name} ({result.method}): drum stop {stop};"
        f" cost {result.cpu_s:.3f} s CPU for {sim_s:.3f} s simulated"
        f" ({rtf:.0f}x real time, {result.n_steps} {unit})"
    )
    for side in ("left", "right"):
        s = m.shoe(side)
        first = s.onsets_s[0] if s.n_impacts else float("nan")
        print(
            f"  {side:5s}: {s.n_impacts} impacts, first at {first:.4f} s"
            f" ({s.first_impact_actuation_n:.1f} N actuation), first-impact peak |F_pivot|"
            f" {s.first_impact_peak_n:.0f} N, period T {1e3 * s.period_s:.2f} ms,"
            f" contact-regime |F_pivot| {s.contact_regime_force_n:.0f} N"
        )
    if args.out:
        _write_history(Path(args.out), result, scenario)
        print(
            f"time history: {args.out} ({len(result.samples)} samples x"
            f" {result.samples.data.shape[1]} columns)"
        )
    return 0


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
    for c in check_list:
        print(
            f"{'ok  ' if c.passed else 'MISS'} {c.what}: published {c.published},"
            f" model {c.model} ({c.difference})"
        )
    print(
        f"{passed}/{len(check_list)} calibration checks within their bands;"
        f" report: {out / 'report.md'}"
    )
    return 0


# --- scenarios ---------------------------------------------------------------------------------
def cmd_scenarios(args: argparse.Namespace) -> int:
    from brake_sim_ros.scenarios import builtin_names, load_scenario

    for name in builtin_names():
        print(f"{name:24s} {load_scenario(name).description}")
    return 0


# --- bench ---------------------------------------------------------------------------
def cmd_bench(args: argparse.Namespace) -> int:
    if args.what == "core":
        from brake_sim_ros.solvers.benchmark import main as bench_core

        return bench_core(args.rest)
    if args.what == "node":
        from brake_sim_ros.ros.benchmark import main as bench_node

        return bench_node(args.rest)
    raise BrakeSimError(f"unknown benchmark '{args.what}': allowed core, node")


def run_node(argv: list[str]) -> int:
    """``brake-sim node ...``: the node parses its own options and ``--ros-args``."""
    from brake_sim_ros.ros.node import main as node_main

    return node_main(["brake-sim node", *argv]) or 0


def run_replay(argv: list[str]) -> int:
    """``brake-sim replay FILE.mcap ...``: publishes a recording on ROS 2 (own options)."""
    from brake_sim_ros.ros.replay import main as replay_main

    return replay_main(["brake-sim replay", *argv]) or 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="brake-sim", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"brake-sim-ros {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("simulate", help="run a scenario offline and summarise it")
    p.add_argument("scenario", help="built-in scenario name or path to a .toml file")
    p.add_argument("--out", help="write the full time history (.npz or .csv)")
    p.add_argument("--duration", type=float, help="simulated seconds (default: the scenario's)")
    p.add_argument("--method", choices=("rk4", "reference"), help="override the scenario's solver")
    p.add_argument("--dt", type=float, help="override the fixed step, s")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.set_defaults(func=cmd_simulate)

    p = sub.add_parser("validate", help="run the study's cases and write the validation report")
    p.add_argument("--out", default="out/validation", help="report directory")
    p.add_argument("--json", help="also write the figures as JSON to this file")
    p.set_defaults(func=cmd_validate)

    p = sub.add_parser("scenarios", help="list the built-in scenarios")
    p.set_defaults(func=cmd_scenarios)

    p = sub.add_parser("bench", help="benchmarks that print figures (core, node)")
    p.add_argument("what", choices=("core", "node"))
    p.add_argument("rest", nargs=argparse.REMAINDER)
    p.set_defaults(func=cmd_bench)

    # handled before parsing (see main), listed here for --help
    sub.add_parser(
        "node",
        help="run the ROS 2 node: brake-sim node [--scenario S] [--duration S]"
        " [--exit-at-end] [--ros-args ...]",
    )
    sub.add_parser(
        "replay",
        help="publish an MCAP recording on ROS 2 with its original timing: brake-sim replay"
        " FILE.mcap [--rate R] [--start-offset S] [--loop] [--topics T ...] [--ros-args ...]",
    )
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["node"]:
        return run_node(argv[1:])
    if argv[:1] == ["replay"]:
        return run_replay(argv[1:])
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
