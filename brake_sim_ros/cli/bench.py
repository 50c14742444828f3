"""``brake-sim bench`` and ``severity``: the registered studies that print figures (each
parses its own options)."""

from __future__ import annotations

import argparse
import sys

from brake_sim_ros.cli.common import EXIT_ERROR, Command
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.studies import BENCHMARKS


def cmd_bench(args: argparse.Namespace) -> int:
    return int(BENCHMARKS[args.what].run(args.rest) or 0)


def bench_options(p: argparse.ArgumentParser) -> None:
    """``bench``'s options: the benchmark's name, then its own options."""
    p.add_argument("what", choices=tuple(BENCHMARKS))
    p.add_argument("rest", nargs=argparse.REMAINDER)
    p.set_defaults(func=cmd_bench)


def run_severity(argv: list[str]) -> int:
    """``brake-sim severity ...``: the study parses its own options."""
    from brake_sim_ros.studies import severity

    try:
        return severity.main(argv)
    except BrakeSimError as exc:
        print(f"brake-sim: error: {exc}", file=sys.stderr)
        return EXIT_ERROR


BENCH = Command(
    "bench",
    "benchmarks that print figures: "
    + "; ".join(f"{s.name}: {s.measures}" for s in BENCHMARKS.values()),
    bench_options,
)
SEVERITY = Command(  # parsed by the study (main() hands it the arguments)
    "severity",
    "sweep each defect from healthy to its service limit and report how signal"
    " features move: brake-sim severity [--out DIR] [--duration S] [--brake B]",
)
