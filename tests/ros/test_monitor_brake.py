"""``brake-sim monitor`` judges a stream only with a detector fitted on the stream's brake.

No message carries the brake. The simulator says it in its read-only parameter ``brake``
(the running scenario's); the monitor asks it before judging the first window and at
each new run (a ``~/reset`` may load a scenario of the other brake). ``--brake`` (the
monitor's ROS parameter ``brake``) declares it for a stream no node says (a replay, a
driver), and is refused when the simulator says otherwise. Every refusal is one line,
exit 2, as for samples at another rate (tests/ros/test_monitor.py). Real nodes, real DDS,
each test on a private domain.
"""

from __future__ import annotations

import contextlib
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import rclpy
from brake_sim_msgs.msg import HealthAssessment, MeasuredChunk
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile

from brake_sim_ros import stream
from brake_sim_ros.detection import saved
from brake_sim_ros.detection.baselines import VibrationThreshold
from brake_sim_ros.ros.harness import LOSSLESS, domain_id_for, ros_environment
from brake_sim_ros.ros.monitor import HEALTH
from tests import cli_process

CLI = [sys.executable, "-m", "brake_sim_ros.cli"]
SCENARIO = """\
name = "{brake}_brake"
brake = "{brake}"
duration_s = {duration}
sample_rate_hz = 5120.0
[actuation]
profile = "ramp"
peak_force_n = 1300.0
"""
# the node's sensors on, the run held until the monitor subscribes (the documented order)
MEASURED_FIRST = ["--ros-args", "-p", "publish_measured:=true", "-p", "measured_subscribers:=1"]
# a node whose stream is refused whole: paced as fast as it goes, so that a loaded machine
# cannot make it refuse to start (it cannot keep real time) before the monitor refuses
AS_FAST = ["-p", "real_time_factor:=0.0"]
WINDOW_S = 0.07


def _scenario(tmp_path: Path, brake: str, duration_s: float = 0.5) -> Path:
    path = tmp_path / f"{brake}_brake.toml"
    path.write_text(SCENARIO.format(brake=brake, duration=duration_s))
    return path


def _model(tmp_path: Path, brake: str) -> Path:
    """A saved rms fitted on ``brake``'s samples; its threshold is any (1 m/s^2): what is
    tested is whether it judges, not what it says."""
    detector = VibrationThreshold("rms", window_s=WINDOW_S)
    detector.threshold = 1.0
    detector.fitted_brake = brake
    path = tmp_path / f"rms_{brake}.json"
    path.write_text(
        saved.dumps(detector, fitted_on={"dataset": "test", "split": "train", "windows": 0})
    )
    return path


class Ears:
    """The monitor's health messages, received in this process (own context)."""

    def __init__(self, domain: int) -> None:
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = rclpy.create_node("brake_test_ears", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.health: list[HealthAssessment] = []
        self.node.create_subscription(HealthAssessment, HEALTH.name, self.health.append, LOSSLESS)

    def spin_until(self, done, timeout_s: float) -> bool:
        end = time.monotonic() + timeout_s
        while not done() and time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.05)
        return done()

    def hear_monitor(self, monitor: subprocess.Popen, log: Path) -> None:
        """Wait until the monitor's ~/health reaches this listener (volatile: a window
        published before the match is lost to it)."""
        matched = self.spin_until(
            lambda: monitor.poll() is not None or self.node.count_publishers(HEALTH.name) > 0,
            60.0,
        )
        assert matched and monitor.poll() is None, log.read_text()
        self.spin_until(lambda: False, 0.5)  # both ends of the match settled

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


@contextlib.contextmanager
def _monitor(domain: int, model: Path, log: Path, *options: str) -> Iterator[subprocess.Popen]:
    """``brake-sim monitor --detector rms --model MODEL OPTIONS`` in its own process;
    stopped (SIGINT) at the end of the block if it still runs."""
    with log.open("w") as out:
        proc = cli_process.popen(
            [*CLI, "monitor", "--detector", "rms", "--model", str(model), *options],
            env=ros_environment(domain),
            stdout=out,
            stderr=subprocess.STDOUT,
        )
    try:
        yield proc
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
        proc.wait(timeout=10)


def _wait_exit(proc: subprocess.Popen, timeout_s: float) -> int | None:
    try:
        return proc.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        return None


def _refusals(output: str) -> list[str]:
    return [line for line in output.splitlines() if "brake-sim monitor: refused:" in line]


def test_without_brake_the_monitor_learns_the_study_brake_from_the_node_and_judges(tmp_path, nodes):
    """A monitor without --brake, a detector fitted on the study brake, the simulator
    running a study-brake scenario: the monitor asks the node, holds the samples until it
    says, and judges every window from sample 0 (before: refused, the brake not declared)."""
    domain = domain_id_for(80)
    log = tmp_path / "monitor.log"
    scenario = _scenario(tmp_path, "study")
    window = round(WINDOW_S * 5120.0)
    expected = [(w * window, (w + 1) * window - 1) for w in range(2560 // window)]
    ears = Ears(domain)
    try:
        with _monitor(domain, _model(tmp_path, "study"), log) as monitor:
            ears.hear_monitor(monitor, log)
            # the node stays up after its run (no --exit-at-end): the monitor may ask it
            # late on a loaded machine
            with nodes.process(["--scenario", str(scenario), *MEASURED_FIRST], domain):
                ears.spin_until(lambda: len(ears.health) >= len(expected), 60.0)
                assert monitor.poll() is None, log.read_text()
    finally:
        ears.close()
    output = log.read_text()
    assert [(h.first_sample_index, h.last_sample_index) for h in ears.health] == expected
    assert "/brake_sim says the study brake" in output
    assert monitor.returncode == 0 and not _refusals(output), output


def _refused_study_detector_on_service(output: str) -> None:
    """One refusal line: a study-fitted detector on the stream /brake_sim says is the
    service brake's."""
    refused = _refusals(output)
    assert len(refused) == 1, output
    assert "fitted on the study brake's samples" in refused[0]
    assert "as /brake_sim says, comes from the service brake" in refused[0]
    assert "Traceback" not in output


def test_the_node_says_its_brake_read_only_and_follows_a_reset(tmp_path, nodes):
    """The simulator's parameter ``brake`` is its scenario's; a change is refused, an
    override at start that says another brake is refused in one line, and a ~/reset to a
    scenario of the other brake changes it. A monitor judging the study brake's stream
    with a study-fitted detector asks again at the new run and refuses the service brake's
    in one line naming both (before: it judged the service brake's samples on)."""
    domain = domain_id_for(81)
    study = _scenario(tmp_path, "study", duration_s=600.0)
    service = _scenario(tmp_path, "service")
    # as fast as it can (AS_FAST): what is tested is the brake, not the pacing, and a loaded
    # machine made the node refuse to start ("cannot keep real time") before it was asked
    code, output = nodes.run(
        ["--scenario", str(study), "--ros-args", "-p", "brake:=service", *AS_FAST], domain
    )
    refused = [line for line in output.splitlines() if "brake='service'" in line]
    assert code != 0 and len(refused) == 1, output
    assert "runs the study brake" in refused[0] and "Traceback" not in output
    log = tmp_path / "monitor.log"
    ears = Ears(domain)
    args = ["--scenario", str(study), "--ros-args", "-p", "publish_measured:=true"]
    args += ["-p", "measured_subscribers:=2", "-p", f"scenario_dirs:={tmp_path}"]  # + client
    args += AS_FAST
    try:
        with (
            _monitor(domain, _model(tmp_path, "study"), log) as monitor,
            nodes.with_client(args, domain) as (_node, client),
        ):  # the client waits for the node: the monitor has long matched the listener
            assert client.get_parameters(["brake"]) == {"brake": "study"}
            result = client.set_parameter("brake", "service")
            assert not result.successful and "brake is read-only" in result.reason
            assert ears.spin_until(lambda: len(ears.health) >= 3, 30.0), log.read_text()
            reply = client.reset(scenario=str(service))
            assert reply.success, reply.message
            assert client.get_parameters(["brake"]) == {"brake": "service"}
            assert _wait_exit(monitor, 30.0) == 2, log.read_text()
    finally:
        ears.close()
    _refused_study_detector_on_service(log.read_text())


def test_without_brake_a_service_stream_is_refused_for_a_study_detector(tmp_path, nodes):
    """The node runs the service brake, the detector was fitted on the study brake's
    samples, no --brake: one line naming both, exit 2 (before: a line saying the brake is
    not declared, which names only the study brake)."""
    domain = domain_id_for(82)
    log = tmp_path / "monitor.log"
    service = ["--scenario", str(_scenario(tmp_path, "service")), *MEASURED_FIRST, *AS_FAST]
    # the node stays up after its run (no --exit-at-end): the monitor may ask it late
    with (
        _monitor(domain, _model(tmp_path, "study"), log) as monitor,
        nodes.process(service, domain),
    ):
        assert _wait_exit(monitor, 60.0) == 2, log.read_text()
    _refused_study_detector_on_service(log.read_text())


def test_a_brake_declared_that_the_node_contradicts_is_refused_naming_both(tmp_path, nodes):
    """--brake study while the node runs the service brake (the detector fitted on the
    study brake, so the declared brake alone would let it judge): one line naming both,
    exit 2 (before: the service brake's samples judged as the study brake's)."""
    domain = domain_id_for(83)
    log = tmp_path / "monitor.log"
    service = ["--scenario", str(_scenario(tmp_path, "service")), *MEASURED_FIRST, *AS_FAST]
    # the node stays up after its run (no --exit-at-end): the monitor may ask it late
    with (
        _monitor(domain, _model(tmp_path, "study"), log, "--brake", "study") as monitor,
        nodes.process(service, domain),
    ):
        assert _wait_exit(monitor, 60.0) == 2, log.read_text()
    output = log.read_text()
    refused = _refusals(output)
    assert len(refused) == 1, output
    assert re.search(r"declared .* is the study brake \(--brake", refused[0]), refused[0]
    assert "/brake_sim says the service brake" in refused[0]
    assert "Traceback" not in output


def test_a_stream_whose_publisher_says_no_brake_needs_brake(tmp_path):
    """A stream published by a node that has no parameter ``brake`` (here this test's, as
    a real brake's driver would): without --brake the monitor asks that node and refuses
    in one line saying who publishes it and to give --brake; a declared --brake study for
    a detector fitted on the service brake is refused at start, naming both."""
    domain = domain_id_for(84)
    model = _model(tmp_path, "service")
    log = tmp_path / "declared.log"
    with _monitor(domain, model, log, "--brake", "study") as monitor:
        assert _wait_exit(monitor, 60.0) == 2, log.read_text()
    refused = _refusals(log.read_text())
    assert len(refused) == 1 and "comes from the study brake" in refused[0], log.read_text()
    log = tmp_path / "monitor.log"
    context = Context()
    rclpy.init(context=context, domain_id=domain)
    node = rclpy.create_node("brake_test_driver", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)  # it answers the monitor's question (no parameter brake)
    publisher = node.create_publisher(MeasuredChunk, stream.MEASURED.name, QoSProfile(depth=10))
    try:
        with _monitor(domain, model, log) as monitor:
            end = time.monotonic() + 60.0
            while monitor.poll() is None and time.monotonic() < end:
                publisher.publish(MeasuredChunk(sample_rate_hz=5120.0))
                executor.spin_once(timeout_sec=0.2)
            assert _wait_exit(monitor, 5.0) == 2, log.read_text()
    finally:
        executor.shutdown(timeout_sec=1.0)
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    output = log.read_text()
    refused = _refusals(output)
    assert len(refused) == 1, output
    assert "/brake_test_driver, which publishes it, has no string parameter brake" in refused[0]
    assert "fitted on the service brake's samples" in refused[0] and "--brake" in refused[0]
    assert "Traceback" not in output


def test_a_replay_says_its_recordings_brake(tmp_path):
    """``brake-sim replay`` of a service-brake recording: its node says the recording's
    brake (its read-only parameter ``brake``), so a monitor without --brake, its detector
    fitted on the study brake, refuses the replayed stream in one line naming the replay's
    node and both brakes (before: the replay said no brake, and the monitor needed
    --brake to know it)."""
    domain = domain_id_for(85)
    recorded, measured = tmp_path / "service.mcap", tmp_path / "service_measured.mcap"
    scenario = _scenario(tmp_path, "service", duration_s=0.3)
    for command in (
        ["simulate", str(scenario), "--mcap", str(recorded)],
        ["resim", str(recorded), "--out", str(measured), "--measured"],
    ):
        done = cli_process.run([*CLI, *command], capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stdout + done.stderr
    log, replay_log = tmp_path / "monitor.log", tmp_path / "replay.log"
    with (
        _monitor(domain, _model(tmp_path, "study"), log) as monitor,
        replay_log.open("w") as out,
    ):
        command = [*CLI, "replay", str(measured), "--loop", "--wait-for-subscribers", "1"]
        command += ["--topics", stream.MEASURED.name, stream.DEFECTS.name]  # the monitor's
        replay = cli_process.popen(
            command,
            env=ros_environment(domain),
            stdout=out,
            stderr=subprocess.STDOUT,
        )
        try:
            assert _wait_exit(monitor, 60.0) == 2, log.read_text() + replay_log.read_text()
        finally:
            replay.send_signal(signal.SIGINT)
            replay.wait(timeout=10)
    output = log.read_text()
    refused = _refusals(output)
    assert len(refused) == 1, output
    assert "fitted on the study brake's samples" in refused[0]
    assert "as /brake_sim_replay says, comes from the service brake" in refused[0]
    assert "/brake_sim_replay says the service brake (its parameter brake)" in (
        replay_log.read_text()
    )
    assert "Traceback" not in output + replay_log.read_text()
