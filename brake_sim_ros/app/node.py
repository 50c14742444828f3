"""``brake-sim node`` / ``python -m brake_sim_ros.app.node [options] [--ros-args ...]``.

The composition root of the live node: option parsing, signals, and the sinks (MCAP
recorder, Rerun) handed to :class:`~brake_sim_ros.ros.node.BrakeSimNode` as
``sink_openers``. The node class itself knows neither recording nor viz.

Options (they override ``--ros-args -p`` values of the same parameters):
    --scenario NAME_OR_PATH   built-in scenario name or .toml path (default "symmetric");
                              the operator's choice, so any readable file (a ``~/reset``
                              request may only name files in ``scenario_dirs``)
    --duration S              simulated seconds of the free run (default: the scenario's)
    --exit-at-end             print a summary and exit 0 when the duration is reached
    --continuous              run without end (the ``continuous`` parameter): until
                              SIGINT/SIGTERM, following live commands or a cycle
    --record PATH             record the stream and accepted commands to an MCAP file
                              (see brake_sim_ros.recording; --record-compression,
                              --record-flush-s tune it)
    --rerun TARGET ...        log to Rerun (repeatable)

SIGINT and SIGTERM end the node cleanly: recordings are closed with every message.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time

import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.utilities import remove_ros_args

from brake_sim_ros.app.stop import start_ros
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.ros.node import BrakeSimNode

EXIT_LINGER_S = 0.3  # keep spinning this long before exiting, so the last messages go out
MODULE_PROG = "python -m brake_sim_ros.app.node"
CLI_PROG = "brake-sim node"


def _parse_cli(argv: list[str], prog: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog=prog,
        description="Drum-brake simulator as a ROS 2 node. ROS parameters go after"
        " --ros-args (-p name:=value); the options below override them.",
    )
    parser.add_argument("--scenario", help="built-in scenario name or path to a .toml file")
    parser.add_argument(
        "--duration",
        type=float,
        metavar="S",
        help="simulated seconds of the free run (default: the scenario's)",
    )
    parser.add_argument(
        "--exit-at-end",
        action="store_true",
        help="print a summary and exit 0 when the duration is reached",
    )
    parser.add_argument(
        "--continuous",
        action="store_true",
        help="run without end, until SIGINT/SIGTERM (duration and --exit-at-end then unused)",
    )
    parser.add_argument(
        "--rerun",
        action="append",
        nargs="+",
        metavar="TARGET",
        help="log to Rerun: spawn | connect [URL] | serve | save FILE.rrd (repeatable)",
    )
    parser.add_argument("--record", metavar="PATH", help="record to this MCAP file")
    parser.add_argument("--record-compression", choices=("zstd", "none"), default="zstd")
    parser.add_argument(
        "--record-flush-s",
        type=float,
        default=1.0,
        metavar="S",
        help="simulated seconds between chunk writes: bounds a crash's loss (default 1)",
    )
    parser.add_argument(
        "--overwrite",
        action="store_true",
        help="replace an existing --record or --rerun save file (never a link or an input)",
    )
    args = parser.parse_args(argv)
    _check_outputs(parser, args)
    if args.rerun:
        # imported only when asked for: importing rerun costs about a second at start-up
        from brake_sim_ros.viz.commands import parse_targets

        try:
            args.rerun = parse_targets(args.rerun)
        except BrakeSimError as exc:
            parser.error(str(exc))
    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0):
        parser.error(f"--duration {args.duration}: allowed a finite time > 0 s")
    if not (math.isfinite(args.record_flush_s) and args.record_flush_s > 0):
        parser.error(f"--record-flush-s {args.record_flush_s}: allowed a finite time > 0 s")
    return args


def _check_outputs(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """The files the node will write, refused before it starts by the rules every command
    follows (:func:`~brake_sim_ros.recording.output.check_outputs`): an existing file
    without --overwrite, a link, the scenario file under any name, a directory that does
    not exist or takes no new file."""
    from brake_sim_ros.recording.output import OutputError, check_outputs

    inputs = [args.scenario] if args.scenario and os.path.lexists(args.scenario) else []
    named = [("--record", args.record, {".mcap": ""})] if args.record else []
    named += [
        ("--rerun save", target[1], {".rrd": ""})
        for target in args.rerun or []
        if target[:1] == ["save"] and len(target) == 2
    ]
    try:
        check_outputs(named, inputs=inputs, overwrite=args.overwrite)
    except OutputError as exc:
        parser.error(str(exc))


def _overrides(cli: argparse.Namespace) -> list[Parameter]:
    overrides = []
    if cli.scenario is not None:
        overrides.append(Parameter("scenario", value=cli.scenario))
    if cli.duration is not None:
        overrides.append(Parameter("duration_s", value=float(cli.duration)))
    if cli.exit_at_end:
        overrides.append(Parameter("exit_at_end", value=True))
    if cli.continuous:
        overrides.append(Parameter("continuous", value=True))
    return overrides


def _sink_openers(cli: argparse.Namespace) -> list:
    openers = []
    if cli.record:
        from brake_sim_ros.recording.record import open_node_recorder

        openers.append(open_node_recorder(cli.record, cli.record_compression, cli.record_flush_s))
    if cli.rerun:
        from brake_sim_ros.viz.commands import rerun_openers

        openers.extend(rerun_openers(cli.rerun))
    return openers


def main(args: list[str] | None = None) -> int:
    """Run the node until shutdown (or the end of the run with --exit-at-end).

    Args:
        args: command line like ``sys.argv`` (program name first); default ``sys.argv``.
            A program name of ``"brake-sim node"`` is shown as such in usage messages.

    Returns:
        0 on a clean exit, 1 when the node refused to start, 2 for bad options.
    """
    argv = list(sys.argv if args is None else args)
    stripped = remove_ros_args(argv)
    prog = CLI_PROG if argv and argv[0] == CLI_PROG else MODULE_PROG
    cli = _parse_cli(stripped[1:], prog)
    openers = _sink_openers(cli)
    stop = start_ros(argv)
    node = None
    try:
        try:
            node = BrakeSimNode(parameter_overrides=_overrides(cli), sink_openers=openers)
        except BrakeSimError as exc:
            print(f"brake_sim: refused to start: {exc}", file=sys.stderr)
            return 1
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        while not node.done and rclpy.ok() and not stop.requested:
            executor.spin_once(timeout_sec=0.1)
        if node.done:
            linger_end = time.monotonic() + EXIT_LINGER_S
            while time.monotonic() < linger_end and rclpy.ok():
                executor.spin_once(timeout_sec=0.05)
        if node.done or stop.requested:
            print(node.summary(), flush=True)
        return 0
    except (KeyboardInterrupt, ExternalShutdownException):
        return 0
    finally:
        if node is not None:
            node.close_sinks()
            node.destroy_node()
        rclpy.try_shutdown()
        stop.restore()


if __name__ == "__main__":
    sys.exit(main())
