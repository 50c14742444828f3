"""A run parameter declared in the table only (``stream/run_parameters.py``, patched in
this process) reaches a real node's declared parameters (with its descriptor), its run
session, the recording the node makes (start value, accepted change) and ``resim`` of
that recording, with no edit elsewhere; a parameter the table fixes at start is refused
by the node with the table's reason.

The node runs in this process (real rclpy, private domain), as fast as possible, and
records with the ``--record`` sink; the file is read back by the independent ``mcap``
reader and re-simulated by :func:`~brake_sim_ros.app.resim.resimulate`.
"""

from __future__ import annotations

import time

import pytest

pytestmark = [
    pytest.mark.ros,
    pytest.mark.filterwarnings("ignore:module 'sre_(parse|constants)' is deprecated"),
]

rclpy = pytest.importorskip("rclpy", reason="rclpy not installed (run scripts/setup.sh)")

from mcap.reader import make_reader  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402

from brake_sim_ros.app.resim import resimulate  # noqa: E402
from brake_sim_ros.recording.record import open_node_recorder  # noqa: E402
from brake_sim_ros.ros.harness import domain_id_for  # noqa: E402
from brake_sim_ros.ros.node import BrakeSimNode  # noqa: E402
from brake_sim_ros.stream import run_parameters  # noqa: E402
from brake_sim_ros.stream.run_parameters import Change, RunParameter  # noqa: E402


def _metadata(path) -> dict[str, dict[str, str]]:
    with path.open("rb") as f:
        return {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}


def test_a_parameter_added_to_the_table_reaches_node_recording_and_resim(tmp_path, monkeypatch):
    knob = RunParameter("test_knob_hz", 7.0, "A knob only this test declares (Hz).", (0.0, 50.0))
    fixed = RunParameter("test_fixed", "a", "Fixed for this test.", changes=Change.AT_START)
    monkeypatch.setattr(
        run_parameters, "RUN_PARAMETERS", (*run_parameters.RUN_PARAMETERS, knob, fixed)
    )
    path, out = tmp_path / "live.mcap", tmp_path / "again.mcap"
    context = rclpy.context.Context()
    rclpy.init(context=context, domain_id=domain_id_for(61))
    try:
        node = BrakeSimNode(
            context=context,
            parameter_overrides=[
                Parameter("test_knob_hz", value=9.0),
                Parameter("real_time_factor", value=0.0),
                Parameter("duration_s", value=0.05),
                Parameter("exit_at_end", value=True),
            ],
            sink_openers=[open_node_recorder(path)],
        )
        try:
            assert node.get_parameter("test_knob_hz").value == 9.0
            (described,) = node.describe_parameters(["test_knob_hz"])
            assert described.description == knob.description
            assert described.floating_point_range[0].to_value == 50.0
            assert node.session.settings["test_knob_hz"] == 9.0
            refused = node.set_parameters([Parameter("test_fixed", value="b")])[0]
            assert not refused.successful
            assert refused.reason == (
                "test_fixed is fixed at start-up (restart the node to change it)"
            )
            accepted = node.set_parameters([Parameter("test_knob_hz", value=11)])[0]
            assert accepted.successful, accepted.reason
            assert node.session.settings["test_knob_hz"] == 11.0
            executor = SingleThreadedExecutor(context=context)
            executor.add_node(node)
            end = time.monotonic() + 120.0
            while not node.done and time.monotonic() < end:
                executor.spin_once(timeout_sec=0.1)
            assert node.done, node.summary()
        finally:
            node.close_sinks()
            node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
    recorded = _metadata(path)
    assert recorded["brake_sim_run"]["test_knob_hz"] == "9.0"
    assert recorded["brake_sim_ros_parameters"]["test_knob_hz"] == "9.0"
    assert recorded["brake_sim_parameter_change"] == {
        "test_knob_hz": "11.0",
        "sample_index": "0",
    }
    result = resimulate(path, out)
    assert result.comparison.first_difference is None
    assert result.comparison.samples == round(0.05 * 25_600)
    assert _metadata(out)["brake_sim_run"]["test_knob_hz"] == "9.0"
