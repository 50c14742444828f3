"""One entry point: ``brake-sim <command>``.

Every command exits 0 on success and non-zero with a one-line reason on failure.

A module per command (or small family of commands) holds its ``cmd_*`` function, the
function that adds its options and its :class:`~brake_sim_ros.cli.common.Command` entry;
here the entries are listed in the order ``brake-sim --help`` shows them. A command's
modules are imported when it runs, so starting one pays only for what it needs.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Collection

from brake_sim_ros import __version__
from brake_sim_ros.cli import bench, detectors, recordings, ros, scenarios, simulate, sweep
from brake_sim_ros.cli.common import (
    EXIT_BROKEN_PIPE,
    EXIT_ERROR,
    EXIT_INTERRUPTED,
    Command,
    Parser,
    debug_traceback,
)
from brake_sim_ros.cli.validate import VALIDATE
from brake_sim_ros.errors import BrakeSimError

__all__ = ["EXIT_ERROR", "build_parser", "main"]

# in the order brake-sim --help lists them
COMMANDS: tuple[Command, ...] = (
    simulate.SIMULATE,
    recordings.VIEW,
    recordings.RECOVER,
    recordings.RESIM,
    VALIDATE,
    scenarios.SCENARIOS,
    scenarios.DEFECTS,
    scenarios.UNIT,
    bench.SEVERITY,
    sweep.SWEEP,
    sweep.DATASET,
    detectors.SCORE,
    detectors.FIT,
    detectors.PLOT,
    bench.BENCH,
    ros.NODE,
    ros.LIVE,
    ros.MONITOR,
    ros.REPLAY,
)
# the commands that parse their own command line: main hands them the arguments
OWN_PARSERS: dict[str, Callable[[list[str]], int]] = {
    "node": ros.run_node,
    "replay": ros.run_replay,
    "monitor": ros.run_monitor,
    "live": ros.run_live,
    "severity": bench.run_severity,
}
# commands that run the physics kernels (compiled on first use)
PHYSICS_COMMANDS = (
    "node", "live", "simulate", "resim", "validate", "bench", "severity", "sweep",
)  # fmt: skip


def build_parser(commands: Collection[str] | None = None) -> Parser:
    """The parser of every command but those in :data:`OWN_PARSERS` (listed for --help).

    Args:
        commands: the commands whose options are added (default: every one's); the others
            have only their line in ``brake-sim --help``, which is all a command line
            naming none of them reaches.
    """
    parser = Parser(prog="brake-sim", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"brake-sim-ros {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    for command in COMMANDS:
        p = sub.add_parser(command.name, help=command.help)
        if command.options is not None and (commands is None or command.name in commands):
            command.options(p)
    return parser


def main(argv: list[str] | None = None) -> int:
    """``brake-sim ...``: the exit status (0, or a one-line error's)."""
    try:
        return _main(list(sys.argv[1:] if argv is None else argv))
    except BrokenPipeError:
        # the reader of stdout went away (`brake-sim defects | head`): no traceback, and no
        # second error when Python flushes stdout at exit
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return EXIT_BROKEN_PIPE


def _main(argv: list[str]) -> int:
    if argv[:1] and argv[0] in PHYSICS_COMMANDS and not {"-h", "--help"} & set(argv):
        from brake_sim_ros.datasets.threads import one_numerics_thread

        one_numerics_thread()  # before numpy's BLAS starts its threads
        from brake_sim_ros.solvers.warmup import ensure_compiled

        ensure_compiled()  # says so, once per installed version, instead of a silent pause
    if argv[:1] and argv[0] in OWN_PARSERS:
        return OWN_PARSERS[argv[0]](argv[1:])
    # argparse takes a command only by its exact name: one absent from argv is never parsed
    args = build_parser(commands=set(argv)).parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except BrakeSimError as exc:
        debug_traceback(exc, getattr(args, "debug", False))
        print(f"brake-sim: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        print("brake-sim: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
