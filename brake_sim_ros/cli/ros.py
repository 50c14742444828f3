"""``brake-sim node``, ``live``, ``replay`` and ``monitor``: the commands that run on ROS 2.
Each parses its own command line (``main`` hands it the arguments, ``--ros-args`` too);
rclpy is imported only when one runs."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from brake_sim_ros.cli.common import DEBUG_HELP, EXIT_ERROR, Command, Parser, debug_traceback
from brake_sim_ros.errors import BrakeSimError

if TYPE_CHECKING:
    from brake_sim_ros.detection.detector import Detector


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
def monitor_parser() -> argparse.ArgumentParser:
    """``brake-sim monitor``'s own parser (its ROS options are removed before it parses)."""
    from brake_sim_ros.detection.registry import help_text
    from brake_sim_ros.model.parameters import BRAKES

    p = Parser(
        prog="brake-sim monitor",
        description="Run a detector as a ROS 2 node on a brake's measured channels"
        " (<simulator>/measured, MeasuredChunk: the simulator, a replay, or a real brake's"
        " driver) and publish its health index (/brake_monitor/health), diagnoses"
        " (/brake_monitor/diagnoses) and /diagnostics status. ROS options go after"
        " --ros-args.",
    )
    p.add_argument("--detector", required=True, help=help_text())
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
    p.add_argument(
        "--brake",
        choices=BRAKES,
        help="the brake the measured samples come from (a scenario's brake); default: asked"
        " of the node that publishes them (the simulator's or a replay's parameter brake),"
        " which must agree when given. Needed for a stream whose publisher does not say it"
        " (a driver): a detector fitted on one brake's samples refuses the other's, and a"
        " brake neither given nor said",
    )
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
    try:
        return _monitor(argv)
    except BrakeSimError as exc:
        debug_traceback(exc, "--debug" in argv)
        print(f"brake-sim monitor: error: {exc}", file=sys.stderr)
        return EXIT_ERROR


def _monitor(argv: list[str]) -> int:
    from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
    from rclpy.utilities import remove_ros_args

    from brake_sim_ros.detection.detector import chunk_from_measured

    parser = monitor_parser()
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
    if args.brake is not None:
        overrides.append(("brake", args.brake))
    detector = _monitor_detector(parser, args)
    from brake_sim_ros.app.monitor import run

    return run(["brake-sim monitor", *argv], detector, chunk_from_measured, overrides=overrides)


def _monitor_detector(parser: argparse.ArgumentParser, args: argparse.Namespace) -> Detector:
    """The monitor's detector: loaded (``--model``), or made and fitted (``--fit``)."""
    from brake_sim_ros.cli.detectors import load_model
    from brake_sim_ros.detection.fitted import facts_text
    from brake_sim_ros.detection.registry import REGISTRY, make_detector

    if args.model is not None:
        if args.fit is not None:
            parser.error("--model and --fit: allowed one (a saved detector, or a dataset)")
        try:
            detector = load_model(args.model, args.detector)
        except ValueError as exc:  # ModelFileError too
            parser.error(str(exc))
        print(
            f"brake-sim monitor: {detector.name} loaded from {args.model} (fitted"
            f" {facts_text(detector)})"
        )
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
        print(
            f"brake-sim monitor: {detector.name} fitted on {windows} windows of"
            f" {args.fit_split} ({facts_text(detector)})"
        )
    return detector


# listed in brake-sim --help; each parses its own command line
NODE = Command(
    "node",
    "run the ROS 2 node: brake-sim node [--scenario S] [--duration S]"
    " [--exit-at-end] [--ros-args ...]",
)
LIVE = Command(
    "live",
    "the main job: stream a scenario through the node in real time, recording MCAP"
    " and Rerun under bags/live/: brake-sim live [SCENARIO] [--duration S] [--no-viewer]",
)
MONITOR = Command(
    "monitor",
    "run a detector as a ROS 2 node on the measured channels and publish its health"
    " index, diagnoses and /diagnostics: brake-sim monitor --detector NAME"
    " [--simulator /brake_sim] [--fit DIR | --model MODEL.json] [--ros-args ...]",
)
REPLAY = Command(
    "replay",
    "publish an MCAP recording on ROS 2 with its original timing: brake-sim replay"
    " FILE.mcap [--rate R] [--start-offset S] [--loop] [--topics T ...] [--ros-args ...]",
)
