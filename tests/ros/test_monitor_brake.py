"""``brake-sim monitor`` refuses a stream from another brake than its detector's.

No message carries the brake, so the monitor is told it (``--brake``, the ROS parameter
``brake``); a saved detector that recorded the brake it was fitted on refuses, at start,
a stream declared from the other brake or one whose brake is not declared: one line,
exit 2, as for samples at another rate (tests/ros/test_monitor.py). The same brake runs:
test_monitor.py's ``test_the_monitor_runs_a_saved_detector_as_offline`` declares it.
"""

from __future__ import annotations

import sys

import pytest

from brake_sim_ros.detection import saved
from brake_sim_ros.detection.baselines import VibrationThreshold
from brake_sim_ros.ros.harness import domain_id_for, ros_environment
from tests import cli_process

CLI = [sys.executable, "-m", "brake_sim_ros.cli"]


@pytest.mark.parametrize(
    ("declared", "words"),
    [
        (["--brake", "study"], "the stream on /brake_sim/measured comes from the study brake"),
        ([], "the brake of the stream on /brake_sim/measured is not declared"),
    ],
)
def test_a_detector_fitted_on_the_service_brake_refuses_a_study_stream_in_one_line(
    tmp_path, declared, words
):
    """A saved rms fitted on the service brake's samples, monitoring a stream declared to
    come from the study brake, or whose brake is not declared: the monitor refuses in one
    line naming both, and exits 2 as for samples at another rate (before: it judged the
    study brake's samples against the service brake's threshold)."""
    detector = VibrationThreshold("rms", window_s=0.07)
    detector.threshold = 1.0  # m/s^2, any: the stream is refused before its first window
    detector.fitted_brake = "service"
    model = tmp_path / "rms.json"
    model.write_text(
        saved.dumps(detector, fitted_on={"dataset": "test", "split": "train", "windows": 0})
    )
    result = cli_process.run(
        [*CLI, "monitor", "--detector", "rms", "--model", str(model), *declared],
        env=ros_environment(domain_id_for(18)),
        capture_output=True,
        text=True,
        timeout=120,
    )
    output = result.stdout + result.stderr
    assert result.returncode == 2, output
    assert "(fitted at a rate not recorded on the service brake)" in output
    refused = [line for line in output.splitlines() if "brake-sim monitor: refused:" in line]
    assert len(refused) == 1, output
    assert "fitted on the service brake's samples" in refused[0] and words in refused[0]
    assert "Traceback" not in output
