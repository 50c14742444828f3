"""``brake-sim monitor``: the same detector offline and live gives the same verdicts.

A run with the scenario's sensors is recorded to MCAP by the offline writer. (a) Offline:
its ``~/measured`` messages, read back by the project's checked reader, go through
:func:`chunk_from_measured` into the detector. (b) Live: ``brake-sim replay`` publishes the
file over real DDS (own process, private domain) to ``brake-sim monitor`` (own process),
whose ``~/health`` and ``~/diagnoses`` this process receives. Both must give the same
windows with the same health index and alarm, bit for bit, and the same diagnoses.

The detector is a real baseline (RMS of the backing plate's y acceleration) with a window
(0.07 s) that is not a whole number of chunks (0.1 s), so windows straddle messages; its
threshold is the median of its own statistic over the recording, so about half the
windows alarm and the comparison is not all-False.
"""

from __future__ import annotations

import contextlib
import math
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
import rclpy
from brake_sim_msgs.msg import Diagnosis, HealthAssessment, MeasuredChunk
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile
from rclpy.serialization import deserialize_message

from brake_sim_ros import stream
from brake_sim_ros.datasets.parquet import run_table, write_history
from brake_sim_ros.detection import saved
from brake_sim_ros.detection.baselines import VibrationThreshold
from brake_sim_ros.detection.detector import Diagnosis as DetectorDiagnosis
from brake_sim_ros.detection.detector import chunk_from_measured
from brake_sim_ros.detection.impact import ImpactDetector
from brake_sim_ros.model.catalogue import KIND_BY_NAME
from brake_sim_ros.recording.reader import open_recording
from brake_sim_ros.recording.record import record_offline
from brake_sim_ros.ros.harness import LOSSLESS, domain_id_for, ros_environment
from brake_sim_ros.ros.monitor import DIAGNOSES, HEALTH
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.stream import conversion
from brake_sim_ros.stream.offline import StreamSettings
from brake_sim_ros.stream.run import run_scenario
from tests import cli_process
from tests.sample_blocks import training_windows

SCENARIO = """\
name = "monitor_test"
duration_s = 1.0
sample_rate_hz = 5120.0
[actuation]
profile = "ramp"
peak_force_n = 1300.0
"""
THRESHOLD_ENV = "BRAKE_SIM_TEST_RMS_THRESHOLD"
DETECTOR = "test_monitor:OffsetRms"  # this module, importable by the monitor process
CLI = [sys.executable, "-m", "brake_sim_ros.cli"]
TOPICS = ["--topics", stream.MEASURED.name, stream.DEFECTS.name]  # what the monitor reads
DIAGNOSED = ("initial_angle", "left")
# the node's options in the documented order: its sensors on, the run held for the monitor
MEASURED_FIRST = ["--ros-args", "-p", "publish_measured:=true", "-p", "measured_subscribers:=1"]


class OffsetRms(VibrationThreshold):
    """RMS baseline, 0.07 s windows, threshold from the environment; it diagnoses every
    alarm as a left initial angle with the health index as severity (only so that the
    diagnosis path has something to carry)."""

    def __init__(self) -> None:
        super().__init__("rms", window_s=0.07)
        self.name = "offset_rms"
        self.threshold = float(os.environ.get(THRESHOLD_ENV, "nan"))  # set by the test

    def assess(self, window, last_sample_index, sample_rate_hz):
        a = super().assess(window, last_sample_index, sample_rate_hz)
        if not a.alarm:
            return a
        d = DetectorDiagnosis(*DIAGNOSED, severity=a.health_index, confidence=0.5)
        return type(a)(a.sample_index, a.time_s, a.health_index, a.alarm, d)


def _verdicts(health: list) -> list[tuple[int, int, float, bool]]:
    return [
        (int(h.first_sample_index), int(h.last_sample_index), float(h.health_index), h.alarm)
        for h in health
    ]


@pytest.fixture(scope="module")
def recording(tmp_path_factory) -> tuple[Path, list[MeasuredChunk], str]:
    """An MCAP with ~/measured; its measured messages read back; its run id."""
    folder = tmp_path_factory.mktemp("monitor")
    scenario_path = folder / "monitor_test.toml"
    scenario_path.write_text(SCENARIO)
    path = folder / "measured.mcap"
    run_id = "0123456789abcdef0123456789abcdef"
    record_offline(
        load_scenario(scenario_path),
        path,
        settings=StreamSettings(publish_measured=True),
        run_id=run_id,
    )
    with open_recording(path) as rec:
        measured = [
            deserialize_message(m.data, MeasuredChunk)
            for m in rec.messages(topics=[stream.MEASURED.name])
        ]
    return path, measured, run_id


@pytest.fixture(scope="module")
def threshold(recording) -> float:
    """The median RMS of the recording's 0.07 s windows (about half of them alarm)."""
    _path, measured, _run = recording
    probe = OffsetRms()
    probe.threshold = 1.0
    values = [a.health_index for m in measured for a in probe.feed(chunk_from_measured(m))]
    return float(np.median(values))


def _offline(measured: list[MeasuredChunk], threshold: float) -> list:
    detector = OffsetRms()
    detector.threshold = threshold
    return [a for m in measured for a in detector.feed(chunk_from_measured(m))]


def _expected(offline: list) -> list[tuple[int, int, float, bool]]:
    """What ~/health must say of the windows ``offline``, in :func:`_verdicts`' form."""
    window = OffsetRms().window_samples(5120.0)
    return [(a.sample_index - window + 1, a.sample_index, a.health_index, a.alarm) for a in offline]


@contextlib.contextmanager
def _monitoring(
    offset: int, threshold: float, log: Path, detector: list[str] | None = None
) -> Iterator[Listener]:
    """``brake-sim monitor`` in its own process on a private domain, and a listener;
    ``detector``: the monitor's detector options (default ``--detector`` DETECTOR)."""
    domain = domain_id_for(offset)
    listener = Listener(domain)
    monitor = _start_monitor(domain, threshold, log, detector or ["--detector", DETECTOR])
    listener.monitor = monitor
    try:
        _wait_for_monitor(listener, monitor, log)
        yield listener
    finally:
        listener.exit_code = _stop(monitor)
        listener.close()


class Listener:
    """The monitor's outputs, received in this process (own context, same domain)."""

    def __init__(self, domain_id: int) -> None:
        self.domain_id = domain_id
        self.monitor: subprocess.Popen | None = None
        self.exit_code: int | None = None
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node("monitor_listener", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.health: list[HealthAssessment] = []
        self.diagnoses: list[Diagnosis] = []
        self.diagnostics: list[DiagnosticStatus] = []
        self.node.create_subscription(HealthAssessment, HEALTH.name, self.health.append, LOSSLESS)
        self.node.create_subscription(Diagnosis, DIAGNOSES.name, self.diagnoses.append, LOSSLESS)
        self.node.create_subscription(
            DiagnosticArray, "/diagnostics", self._on_diagnostics, LOSSLESS
        )
        self.measured = self.node.create_publisher(
            MeasuredChunk, stream.MEASURED.name, QoSProfile(depth=100)
        )

    def _on_diagnostics(self, msg: DiagnosticArray) -> None:
        self.diagnostics.extend(s for s in msg.status if s.name.endswith(": health"))

    def spin_until(self, done, timeout_s: float) -> bool:
        end = time.monotonic() + timeout_s
        while not done() and time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.02)
        return done()

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


def _start_monitor(
    domain: int, threshold: float, log: Path, detector: list[str]
) -> subprocess.Popen:
    env = ros_environment(domain)
    env[THRESHOLD_ENV] = repr(threshold)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(Path(__file__).parent), env.get("PYTHONPATH", "")]
    ).rstrip(os.pathsep)
    with log.open("w") as out:
        return subprocess.Popen(
            [*CLI, "monitor", *detector],
            env=env,
            stdout=out,
            stderr=subprocess.STDOUT,
        )


def _stop(proc: subprocess.Popen) -> int:
    if proc.poll() is None:
        proc.send_signal(2)  # SIGINT: a clean rclpy shutdown
        try:
            return proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
    return proc.wait(timeout=10)


def _wait_for_monitor(listener: Listener, proc: subprocess.Popen, log: Path) -> None:
    ready = listener.spin_until(
        lambda: (
            proc.poll() is not None
            or (
                listener.node.count_publishers(HEALTH.name) >= 1
                and listener.node.count_subscribers(stream.MEASURED.name) >= 1
            )
        ),
        30.0,
    )
    assert ready and proc.poll() is None, log.read_text()
    # the graph shows an endpoint before it has matched ours: a first /diagnostics (1 s
    # period) received says this listener's subscriptions to the monitor are matched (a
    # loaded machine once lost the first ~/health to that gap)
    heard = listener.spin_until(lambda: len(listener.diagnostics) >= 1, 10.0)
    assert heard and proc.poll() is None, log.read_text()
    listener.spin_until(lambda: False, 0.3)  # both ends of every match settled


@pytest.mark.slow
def test_offline_and_replayed_through_the_monitor_agree(recording, threshold, tmp_path):
    path, measured, run_id = recording
    offline = _offline(measured, threshold)
    window = OffsetRms().window_samples(5120.0)
    expected = _expected(offline)
    alarms = [e[3] for e in expected]
    assert len(expected) >= 10 and any(alarms) and not all(alarms)  # not a trivial match
    assert any(a.sample_index // 512 != (a.sample_index - window + 1) // 512 for a in offline)

    log = tmp_path / "monitor.log"
    with _monitoring(11, threshold, log) as listener:
        replay = cli_process.run(
            [*CLI, "replay", str(path), "--rate", "2", "--wait-for-subscribers", "1", *TOPICS],
            env=ros_environment(listener.domain_id),
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert replay.returncode == 0, replay.stdout + replay.stderr
        listener.spin_until(lambda: len(listener.health) >= len(expected), 15.0)
        # /diagnostics: the period that held the alarms says ERROR (next period <= 1 s)
        listener.spin_until(
            lambda: any(s.level == DiagnosticStatus.ERROR for s in listener.diagnostics), 3.0
        )
    output = log.read_text()
    assert listener.exit_code == 0, output
    error = next(s for s in listener.diagnostics if s.level == DiagnosticStatus.ERROR)
    assert error.message.startswith("ALARM in ") and _value(error, "detector") == "offset_rms"

    assert _verdicts(listener.health) == expected  # same windows, same numbers, bit for bit
    # the run id comes on another topic (DefectState): windows before it arrives have none
    assert {h.run_id for h in listener.health} <= {"", run_id}
    assert listener.health[-1].run_id == run_id
    assert {h.detector for h in listener.health} == {"offset_rms"}
    # stamps: simulated time of each window's last sample, as the chunks' stamps say
    stamps = [h.header.stamp.sec * 10**9 + h.header.stamp.nanosec for h in listener.health]
    assert stamps == [conversion.stamp_ns(a.sample_index, 1 / 5120.0) for a in offline]
    # diagnoses: one per alarm window, the catalogue's kind, location and unit
    diagnosed = [
        (d.sample_index, d.kind, d.location, d.unit, d.severity) for d in listener.diagnoses
    ]
    unit = KIND_BY_NAME[DIAGNOSED[0]].unit
    assert diagnosed == [
        (a.sample_index, *DIAGNOSED, unit, a.health_index) for a in offline if a.alarm
    ]
    assert [h.has_diagnosis for h in listener.health] == alarms
    assert "[WARN]" not in output and "[ERROR]" not in output, output


def _malformed(msg: MeasuredChunk) -> MeasuredChunk:
    """``msg`` with one value too few for its channel counts."""
    bad = deserialize_message(_serialize(msg), MeasuredChunk)
    bad.values = bad.values[:-1]
    return bad


def _serialize(msg: MeasuredChunk) -> bytes:
    from rclpy.serialization import serialize_message

    return serialize_message(msg)


@pytest.mark.slow
def test_monitor_survives_malformed_and_out_of_order_messages(recording, threshold, tmp_path):
    """Malformed, oversized, rate-less and repeated chunks are dropped with one warning line
    each, and a chunk the detector cannot read is one warning; the valid chunks around them
    are assessed as offline, and /diagnostics counts each."""
    _path, measured, _run = recording
    m0, m1, m2, m3 = measured[:4]
    oversized = deserialize_message(_serialize(m2), MeasuredChunk)
    oversized.sample_count = 2**31
    no_rate = deserialize_message(_serialize(m2), MeasuredChunk)
    no_rate.sample_rate_hz = 5e-324  # > 0, but no sample period a clock can hold
    foreign = deserialize_message(_serialize(measured[4]), MeasuredChunk)
    foreign.channel_names = [f"other_{name}" for name in foreign.channel_names]
    # m1 repeats; the last is well formed but lacks the detector's channel
    sequence = [m0, _malformed(m1), m1, oversized, m1, no_rate, m2, m3, foreign]
    expected = _expected(_offline([m0, m1, m2, m3], threshold))

    log = tmp_path / "monitor.log"
    with _monitoring(12, threshold, log) as listener:
        for msg in sequence:
            listener.measured.publish(msg)
            listener.spin_until(lambda: False, 0.05)
        listener.spin_until(lambda: len(listener.health) >= len(expected), 10.0)
        # the next /diagnostics (1 s period) carries the counters
        listener.spin_until(
            lambda: any(_value(s, "detector_failures") == "1" for s in listener.diagnostics), 5.0
        )
        alive = listener.monitor.poll() is None
    output = log.read_text()
    assert alive and listener.exit_code == 0, output
    assert _verdicts(listener.health) == expected
    last = [s for s in listener.diagnostics if _value(s, "detector_failures") == "1"][-1]
    assert _value(last, "malformed") == "3" and _value(last, "chunks") == "4"
    assert _value(last, "out_of_order") == "1"
    warnings = [line for line in output.splitlines() if "[WARN]" in line]
    # a kind of fault is one line, then counted (no line per message under a flood)
    assert len([w for w in warnings if "malformed" in w]) == 1, output
    assert len([w for w in warnings if "out of order" in w]) == 1, output
    assert len([w for w in warnings if "no channel 'backing_plate_accel_y'" in w]) == 1, output
    assert "Traceback" not in output


def test_the_monitor_runs_a_saved_detector_as_offline(recording, threshold, tmp_path):
    """``brake-sim monitor --model``: a saved rms detector (the threshold and 0.07 s
    windows of OffsetRms) gives, live, the health index and alarms of the same detector
    run offline, bit for bit."""
    _path, measured, _run = recording
    detector = VibrationThreshold("rms", window_s=0.07)
    detector.threshold = threshold
    detector.fitted_brake = "study"  # the recording's scenario runs the study brake
    model = tmp_path / "rms.json"
    model.write_text(
        saved.dumps(detector, fitted_on={"dataset": "test", "split": "train", "windows": 0})
    )
    expected = _expected(_offline(measured[:6], threshold))
    assert any(e[3] for e in expected) and not all(e[3] for e in expected)
    log = tmp_path / "monitor.log"
    options = ["--detector", "rms", "--model", str(model), "--brake", "study"]
    with _monitoring(13, threshold, log, options) as ears:
        for msg in measured[:6]:
            ears.measured.publish(msg)
            ears.spin_until(lambda: False, 0.05)
        ears.spin_until(lambda: len(ears.health) >= len(expected), 10.0)
    output = log.read_text()
    assert ears.exit_code == 0, output
    assert f"rms loaded from {model} (fitted at a rate not recorded on the study brake)" in output
    assert _verdicts(ears.health) == expected
    assert {h.detector for h in ears.health} == {"rms"} and not ears.diagnoses


def test_a_detector_fitted_at_5120_hz_is_refused_at_25600_hz_in_one_line(
    recording, threshold, tmp_path
):
    """A saved rms fitted at 5120 Hz (as ``evaluate.fit`` records it) given a chunk at
    25.6 kHz (the node's default): the monitor stops with exit 2 and one line naming both
    rates; it assesses nothing (before: a health index near 0 through the whole stop)."""
    _path, measured, _run = recording
    detector = VibrationThreshold("rms", window_s=0.07)
    detector.threshold = threshold
    detector.fitted_rate_hz = 5120.0
    model = tmp_path / "rms.json"
    model.write_text(
        saved.dumps(detector, fitted_on={"dataset": "test", "split": "train", "windows": 0})
    )
    faster = deserialize_message(_serialize(measured[0]), MeasuredChunk)
    faster.sample_rate_hz = 25600.0
    log = tmp_path / "monitor.log"
    with _monitoring(14, threshold, log, ["--detector", "rms", "--model", str(model)]) as ears:
        ears.measured.publish(faster)
        ears.spin_until(lambda: ears.monitor.poll() is not None, 15.0)
    output = log.read_text()
    assert ears.exit_code == 2, output
    refused = [line for line in output.splitlines() if "brake-sim monitor: refused:" in line]
    assert len(refused) == 1, output
    assert "fitted at 5120 Hz" in refused[0] and "at 25600 Hz" in refused[0]
    assert not ears.health and "Traceback" not in output


def test_the_monitor_counts_the_samples_sent_before_it_heard_the_run(
    recording, threshold, tmp_path
):
    """A monitor that first hears a run at sample N counts a gap of N samples never
    received, from the run's first sample (before: 0 gaps)."""
    _path, measured, _run = recording
    first = int(measured[2].first_sample_index)
    assert first > 0
    log = tmp_path / "monitor.log"
    with _monitoring(15, threshold, log) as ears:
        for msg in measured[2:5]:
            ears.measured.publish(msg)
            ears.spin_until(lambda: False, 0.05)
        ears.spin_until(lambda: any(_value(s, "chunks") == "3" for s in ears.diagnostics), 10.0)
    output = log.read_text()
    assert ears.exit_code == 0, output
    last = [s for s in ears.diagnostics if _value(s, "chunks") == "3"][-1]
    assert (_value(last, "gaps"), _value(last, "samples_lost")) == ("1", str(first))
    assert f"samples 0 to {first - 1} of the run never arrived" in output
    assert f"1 gaps ({first} samples never received)" in output


def test_monitor_then_node_in_the_documented_order_assess_every_window_from_sample_0(
    recording, threshold, tmp_path
):
    """The documented order: the monitor first, then the node with its sensors on and
    ``measured_subscribers:=1``. The node holds its first sample until the monitor has
    subscribed, so every window from sample 0 is assessed and none is lost (before: the
    first window came at 1.4 s and the stop's impacts were never assessed)."""
    scenario = tmp_path / "monitor_test.toml"
    scenario.write_text(SCENARIO)
    log = tmp_path / "monitor.log"
    window = OffsetRms().window_samples(5120.0)
    expected = [(w * window, (w + 1) * window - 1) for w in range(5120 // window)]
    with _monitoring(16, threshold, log) as ears:
        node = cli_process.run(
            [*CLI, "node", "--scenario", str(scenario), "--exit-at-end", *MEASURED_FIRST],
            env=ros_environment(ears.domain_id),
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert node.returncode == 0, node.stdout + node.stderr
        ears.spin_until(lambda: len(ears.health) >= len(expected), 15.0)
        ears.spin_until(lambda: any(_value(s, "chunks") == "10" for s in ears.diagnostics), 5.0)
    output = log.read_text()
    assert "waiting for 1 ~/measured subscriber(s)" in node.stdout + node.stderr
    assert ears.exit_code == 0, output
    assert [(h.first_sample_index, h.last_sample_index) for h in ears.health] == expected
    last = [s for s in ears.diagnostics if _value(s, "chunks") == "10"][-1]
    assert (_value(last, "gaps"), _value(last, "samples_lost")) == ("0", "0"), output


def test_measured_subscribers_without_measured_is_refused_in_one_line(tmp_path):
    node = cli_process.run(
        [*CLI, "node", "--scenario", "symmetric", "--ros-args", "-p", "measured_subscribers:=1"],
        env=ros_environment(domain_id_for(17)),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert node.returncode != 0
    assert "measured_subscribers=1 without publish_measured" in node.stdout + node.stderr
    assert "Traceback" not in node.stdout + node.stderr


def _impact_fitted_on(measured: list[MeasuredChunk]) -> ImpactDetector:
    """The impact baseline fitted on three made-up healthy "units": the recording's stop
    with its accelerations scaled by 0.5, 0.6 and 0.7 (so the recording itself, at 1, is
    far from them and alarms), windows of 0.1 s as ``brake-sim score`` cuts them."""
    chunks = [chunk_from_measured(m) for m in measured]
    channels = {
        c: np.concatenate([k.channels[c] for k in chunks]) for c in ImpactDetector().channels
    }
    windows = []
    for u, gain in enumerate((0.5, 0.6, 0.7)):
        scaled = {c: v * gain if c.startswith("backing_plate") else v for c, v in channels.items()}
        windows += training_windows(scaled, 5120.0, run_id=f"r{u}", unit_id=f"u{u}")
    detector = ImpactDetector()
    detector.fit(windows)
    return detector


@pytest.mark.slow
def test_the_monitor_runs_the_impact_baseline_as_offline(recording, threshold, tmp_path):
    """A detector that carries state from message to message (it finds the application in
    one message and judges it in a later one, then holds the verdict): a saved impact
    detector gives, live, the health index and alarms of the same detector run offline
    over the recording's messages, bit for bit."""
    _path, measured, _run = recording
    detector = _impact_fitted_on(measured)
    model = tmp_path / "impact.json"
    model.write_text(
        saved.dumps(detector, fitted_on={"dataset": "test", "split": "train", "windows": 0})
    )
    offline = [a for m in measured for a in detector.feed(chunk_from_measured(m))]
    window = detector.window_samples(5120.0)
    expected = [
        (a.sample_index - window + 1, a.sample_index, a.health_index, a.alarm) for a in offline
    ]
    assert expected[0][2] == 0.0 and expected[-1][3]  # no verdict, then the stop's alarm
    log = tmp_path / "monitor.log"
    with _monitoring(14, threshold, log, ["--detector", "impact", "--model", str(model)]) as ears:
        for msg in measured:
            ears.measured.publish(msg)
            ears.spin_until(lambda: False, 0.05)
        ears.spin_until(lambda: len(ears.health) >= len(expected), 10.0)
    output = log.read_text()
    assert ears.exit_code == 0, output
    assert _verdicts(ears.health) == expected
    assert {h.detector for h in ears.health} == {"impact"}
    assert all(math.isnan(h.rul_s) for h in ears.health)  # it forecasts nothing


def _value(status: DiagnosticStatus, key: str) -> str | None:
    return next((kv.value for kv in status.values if kv.key == key), None)


def test_measured_messages_read_as_the_dataset_columns(recording, tmp_path):
    """What the monitor feeds its detector is what ``brake-sim score`` feeds it: the
    recording's ~/measured through :func:`chunk_from_measured` equals, bit for bit and NaN
    for NaN, the measured columns of the same run's Parquet table (a dataset's rows),
    written and read back by pyarrow."""
    path, measured, _run = recording
    scenario = load_scenario(path.with_name("monitor_test.toml"))
    table_path = tmp_path / "run.parquet"
    write_history(table_path, run_table(scenario, run_scenario(scenario), scenario.duration_s))
    table = pq.read_table(table_path)
    chunks = [chunk_from_measured(m) for m in measured]
    assert [c.first_sample_index for c in chunks] == list(
        np.cumsum([0] + [len(c) for c in chunks[:-1]])
    )
    names = list(chunks[0].channels)
    assert len(names) >= 4  # accelerometers, wheel speed, line pressure
    # (every channel at the full 5120 Hz here; test_monitor_parts checks decimated ones)
    for name in names:
        (column,) = [c for c in table.column_names if c.startswith(f"measured:{name} [")]
        dataset = table[column].to_numpy(zero_copy_only=False).astype(np.float64)
        live = np.concatenate([c.channels[name] for c in chunks])
        assert live.shape == dataset.shape == (5120,)
        np.testing.assert_array_equal(live, dataset, err_msg=name)  # NaN where NaN


def test_message_fields():
    """The monitor's messages carry what the README says, with these types."""
    assert HealthAssessment.get_fields_and_field_types() == {
        "header": "std_msgs/Header",
        "run_id": "string",
        "unit_id": "string",
        "detector": "string",
        "first_sample_index": "uint64",
        "last_sample_index": "uint64",
        "sample_rate_hz": "double",
        "health_index": "double",
        "alarm": "boolean",
        "has_diagnosis": "boolean",
        "rul_s": "double",
    }
    assert Diagnosis.get_fields_and_field_types() == {
        "header": "std_msgs/Header",
        "run_id": "string",
        "unit_id": "string",
        "detector": "string",
        "sample_index": "uint64",
        "kind": "string",
        "location": "string",
        "severity": "double",
        "unit": "string",
        "confidence": "double",
    }
