"""The monitor node under hostile input, fed in this process (a real MonitorNode in a real
rclpy context; messages handed to its subscription callback): a flood of malformed
messages is one warning line and a count, a publisher at 1e12 Hz is dropped and counted
instead of buffered, a chunk stamped 1 ns early by float rounding is accepted, and a
detector whose window exceeds the stated limit is refused at start.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pytest
import rclpy
from brake_sim_msgs.msg import MeasuredChunk
from rclpy.context import Context

from brake_sim_ros.detection.detector import Assessment, Detector, chunk_from_measured
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.ros.harness import domain_id_for
from brake_sim_ros.ros.monitor import FAULT_SUMMARY_S, MAX_WINDOW_SAMPLES, MonitorNode
from brake_sim_ros.stream.conversion import stamp_ns, time_msg

RATE = 2560.0
pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_(parse|constants)' is deprecated")


class Counting(Detector):
    name = "counting"
    channels = ("a",)
    window_s = 0.05  # 128 samples at 2560 Hz

    def assess(
        self, window: Mapping[str, np.ndarray], last_sample_index: int, sample_rate_hz: float
    ) -> Assessment:
        return Assessment(last_sample_index, last_sample_index / sample_rate_hz, 0.1, False)


class Forever(Counting):
    window_s = 1e9


@pytest.fixture()
def node():
    context = Context()
    rclpy.init(context=context, domain_id=domain_id_for(33))
    made = MonitorNode(Counting(), chunk_from_measured, context=context)
    yield made
    made.destroy_node()
    rclpy.try_shutdown(context=context)


def _chunk(first: int, n: int, rate: float = RATE, early_ns: int = 0) -> MeasuredChunk:
    msg = MeasuredChunk()
    msg.header.stamp = time_msg(stamp_ns(first, 1.0 / rate) - early_ns)
    msg.first_sample_index = first
    msg.sample_count = n
    msg.sample_rate_hz = rate
    msg.channel_names = ["a"]
    msg.units = ["m/s^2"]
    msg.decimation = [1]
    msg.channel_sample_counts = [n]
    msg.values = np.linspace(0.0, 1.0, n).tolist()
    return msg


def test_a_flood_of_malformed_messages_is_one_line_and_a_count(node):
    bad = _chunk(0, 256)
    bad.values = bad.values[:-1]
    for _ in range(10_000):
        node._on_measured(bad)
    assert node.stats.malformed == 10_000
    assert node.stats.warning_lines == 1
    log = node._faults["malformed messages"]
    assert log.unreported == 9_999
    node._summarise("malformed messages", log, now=log.logged_at + FAULT_SUMMARY_S)
    assert node.stats.warning_lines == 2 and log.unreported == 0


def test_a_rate_whose_window_exceeds_the_buffer_is_dropped_and_counted(node):
    for k in range(200):
        node._on_measured(_chunk(k * 256, 256, rate=1e12))
    assert node.stats.windows_too_long == 200 and node.stats.chunks == 0
    assert node.detector._buffered == 0  # nothing was buffered
    assert node.stats.warning_lines == 1
    assert MAX_WINDOW_SAMPLES < 0.05 * 1e12  # the case is past the limit


def test_a_chunk_stamped_a_rounding_early_is_accepted(node):
    node._on_measured(_chunk(0, 256, early_ns=1))
    node._on_measured(_chunk(256, 256, early_ns=1))
    assert node.stats.malformed == 0 and node.stats.chunks == 2
    assert node.stats.windows == 4  # 512 samples: four windows of 128


def test_a_chunk_stamped_far_before_its_samples_is_malformed(node):
    node._on_measured(_chunk(0, 256, early_ns=10_000))
    assert node.stats.malformed == 1 and node.stats.chunks == 0


def test_a_window_longer_than_the_limit_is_refused_at_start():
    context = Context()
    rclpy.init(context=context, domain_id=domain_id_for(34))
    try:
        with pytest.raises(BrakeSimError, match=r"window_s 1000000000\.0"):
            MonitorNode(Forever(), chunk_from_measured, context=context)
    finally:
        rclpy.try_shutdown(context=context)


class LongMemory(Counting):
    """A history detector that would keep its windows for 1e9 s."""

    history_s = 1e9


def test_a_history_longer_than_the_limit_is_refused_at_start():
    context = Context()
    rclpy.init(context=context, domain_id=domain_id_for(35))
    try:
        with pytest.raises(BrakeSimError, match=r"history_s 1000000000\.0; allowed") as info:
            MonitorNode(LongMemory(), chunk_from_measured, context=context)
        assert "\n" not in str(info.value)
        made = MonitorNode(Counting(), chunk_from_measured, context=context)  # no history: runs
        made.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)


@pytest.mark.parametrize(
    "ros_args",
    [
        ["-p"],
        ["-p", "warn_level"],
        ["-r", "__node:=bad-name"],
        ["--params-file", "/nonexistent/params.yaml"],
        ["--log-level", "nonsense"],
        ["-r", "/brake_sim/measured:=bad::name"],
    ],
)
def test_bad_ros_arguments_are_one_line_and_exit_2(ros_args, capsys):
    from brake_sim_ros.cli import main

    with pytest.raises(SystemExit) as exit_info:
        main(["monitor", "--detector", "rms", "--ros-args", *ros_args])
    assert exit_info.value.code == 2
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("brake-sim monitor: error: --ros-args: ")
