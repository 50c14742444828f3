"""``brake-sim monitor``: run a detector as a ROS 2 node until interrupted.

The composition root of the monitor node: ROS start-up and shutdown, and the spin loop.
The command line (detector name, fitting, topics) is parsed by ``brake_sim_ros.cli.ros``,
which builds and fits the detector and hands it in with its chunk conversion: the node
(:class:`brake_sim_ros.ros.monitor.MonitorNode`) and this module import nothing of
``detection``.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.parameter import Parameter

from brake_sim_ros.app.stop import start_ros
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.ros.monitor import MonitorNode, StreamingDetector

EXIT_REFUSED = 2  # as the CLI's own refusals: every reason to refuse is a bad argument


def run(
    ros_argv: list[str],
    detector: StreamingDetector,
    to_chunk: Callable[[Any], Any],
    *,
    overrides: list[tuple[str, object]],
) -> int:
    """Spin a :class:`MonitorNode` until Ctrl-C / SIGTERM / shutdown.

    Args:
        ros_argv: the command line with its ``--ros-args`` (program name first).
        detector: fitted, ready to feed.
        to_chunk: MeasuredChunk -> the detector's input chunk.
        overrides: node parameters the command line sets, ``(name, value)``.

    Returns:
        0 after an interrupt, 2 when the node refused to start (a parameter of
        ``--ros-args`` out of range or of the wrong type, a topic name ROS refuses: bad
        arguments, like every other refusal of ``brake-sim monitor``) or refused the
        samples (at another rate than the detector was fitted at, or from another brake
        than it was fitted on, or whose brake neither the simulator says nor ``--brake``
        declares, or a ``--brake`` the simulator contradicts: ``MonitorNode.refusal``).
    """
    stop = start_ros(ros_argv)  # the loop ends between callbacks, never on a dead context
    node = None
    try:
        try:
            node = MonitorNode(
                detector,
                to_chunk,
                parameter_overrides=[Parameter(k, value=v) for k, v in overrides],
            )
        except BrakeSimError as exc:
            print(f"brake-sim monitor: refused to start: {exc}", file=sys.stderr)
            return EXIT_REFUSED
        print(
            f"brake-sim monitor: detector {detector.name} on {node.measured_topic};"
            f" publishing {', '.join(node.published_topics())}",
            flush=True,
        )
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        while rclpy.ok() and not stop.requested and node.refusal is None:
            executor.spin_once(timeout_sec=0.1)
        if node.refusal is not None:
            print(f"brake-sim monitor: refused: {node.refusal}", file=sys.stderr, flush=True)
            return EXIT_REFUSED
        return 0
    except (KeyboardInterrupt, ExternalShutdownException):
        return 0
    finally:
        if node is not None:
            s = node.stats
            print(
                f"brake-sim monitor: {s.windows} windows assessed, {s.alarms} alarms,"
                f" {s.diagnoses} diagnoses; dropped {s.malformed} malformed and"
                f" {s.out_of_order} out-of-order messages; {s.gaps} gaps"
                f" ({s.samples_lost} samples never received)",
                flush=True,
            )
            node.destroy_node()
        rclpy.try_shutdown()
        stop.restore()
