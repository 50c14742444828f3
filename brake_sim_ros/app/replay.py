"""``brake-sim replay FILE.mcap``: open a recording, check it, publish it on ROS 2.

The composition root of the replay: argument parsing, the checked recording
(:mod:`brake_sim_ros.recording.playback`), the node (:mod:`brake_sim_ros.ros.replay`).
See the latter for what is published and when.

Options:
    --rate R            replay speed factor (default 1: the original timing)
    --start-offset S    skip the first S seconds of the recording (log time)
    --loop              start again at the end, until interrupted
    --topics T [T ...]  replay only these topics (default: all)
    --wait-for-subscribers N  wait (up to 10 s) until every topic has N matched subscribers
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.utilities import remove_ros_args

from brake_sim_ros.app.stop import start_ros
from brake_sim_ros.command_line import Parser
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.recording.playback import Recording
from brake_sim_ros.recording.reader import RecordingReadError
from brake_sim_ros.ros.replay import ReplayNode, serve


def _parse_cli(argv: list[str]) -> argparse.Namespace:
    parser = Parser(
        prog="brake-sim replay",
        description="Publish an MCAP recording on ROS 2 with its original timing.",
    )
    parser.add_argument("recording", type=Path, help="MCAP file (brake-sim --record/--mcap)")
    parser.add_argument("--rate", type=float, default=1.0, help="speed factor (default 1)")
    parser.add_argument(
        "--start-offset", type=float, default=0.0, metavar="S", help="skip the first S seconds"
    )
    parser.add_argument("--loop", action="store_true", help="play again from the start offset")
    parser.add_argument("--topics", nargs="+", metavar="TOPIC", help="only these topics")
    parser.add_argument(
        "--wait-for-subscribers",
        type=int,
        default=0,
        metavar="N",
        help="before playing, wait up to 10 s for N subscribers on every topic",
    )
    args = parser.parse_args(argv)
    if not (math.isfinite(args.rate) and args.rate > 0):
        parser.error(f"--rate {args.rate}: allowed a finite factor > 0")
    if not (math.isfinite(args.start_offset) and args.start_offset >= 0):
        parser.error(f"--start-offset {args.start_offset}: allowed a finite time >= 0 s")
    if args.wait_for_subscribers < 0:
        parser.error(f"--wait-for-subscribers {args.wait_for_subscribers}: allowed >= 0")
    return args


def main(args: list[str] | None = None) -> int:
    """Replay until the end (or, with --loop, until interrupted).

    Args:
        args: command line like ``sys.argv`` (program name first); default ``sys.argv``.

    Returns:
        0 after a complete replay or Ctrl-C / SIGTERM, 1 for a recording that cannot be
        replayed, 2 for bad options.
    """
    argv = list(sys.argv if args is None else args)
    cli = _parse_cli(remove_ros_args(argv)[1:])
    try:
        recording = Recording(cli.recording, cli.topics)
    except BrakeSimError as exc:
        print(f"brake-sim replay: error: {exc}", file=sys.stderr)
        return 1
    if cli.start_offset >= recording.duration_s and recording.duration_s > 0:
        recording.close()
        print(
            f"brake-sim replay: error: --start-offset {cli.start_offset:g} s is past the end of"
            f" {cli.recording} ({recording.duration_s:.6g} s)",
            file=sys.stderr,
        )
        return 1
    stop = start_ros(argv)  # Ctrl-C ends the play between two messages, never mid-publish

    def stopped() -> bool:
        return stop.requested or not rclpy.ok()

    brake, why = recording.brake()
    node = None
    try:
        try:
            node = ReplayNode(
                recording, rate=cli.rate, start_offset_s=cli.start_offset, brake=brake
            )
        except BrakeSimError as exc:
            print(f"brake-sim replay: error: {exc}", file=sys.stderr)
            return 1
        topics = ", ".join(f"{t.name} ({t.count})" for t in recording.topics.values())
        says = (
            f"the {brake} brake (its parameter brake)"
            if brake
            else f"no brake ({why}): a monitor of it needs --brake"
        )
        print(
            f"brake-sim replay: {cli.recording}, {recording.duration_s:.3f} s at {cli.rate:g}x"
            f" from {cli.start_offset:g} s: {topics}; {node.get_fully_qualified_name()} says"
            f" {says}",
            flush=True,
        )
        with serve(node):
            if cli.wait_for_subscribers and not node.wait_for_subscribers(
                cli.wait_for_subscribers, 10.0
            ):
                print("brake-sim replay: not every topic has its subscribers; playing anyway")
            while not stopped():
                node.play_once(stopped)
                if not cli.loop:
                    break
        print(f"brake-sim replay: published {node.published} messages", flush=True)
        return 0
    except RecordingReadError as exc:  # the file changed after it was checked
        print(f"brake-sim replay: error: {exc}", file=sys.stderr)
        return 1
    except (KeyboardInterrupt, ExternalShutdownException):
        return 0
    finally:
        if node is not None:
            node.destroy_node()
        recording.close()
        rclpy.try_shutdown()
        stop.restore()


if __name__ == "__main__":
    sys.exit(main())
