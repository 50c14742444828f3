"""brake_sim_msgs (msg_defs/): generated types and a real DDS round trip.

Needs the interfaces built and installed by scripts/setup.sh. The round trip
starts a publisher in a separate Python process and receives its
PivotForceChunk messages in this process over DDS, on a ROS domain derived from
the pid (and the pytest-xdist worker) so that parallel runs on one host do not see each
other.
"""

from __future__ import annotations

import inspect
import math
import signal
import subprocess
import sys
import time

import pytest
import rclpy
from brake_sim_msgs.msg import (
    ActuationCommand,
    BrakeState,
    ContactEvent,
    Defect,
    DefectState,
    MeasuredChunk,
    PivotForceChunk,
)
from brake_sim_msgs.srv import ResetSimulation, StepSimulation

from brake_sim_ros.ros.harness import domain_id_for

FRAME = "brake_backing_plate"
TOPIC = "/brake_sim_test/pivot_forces"
RATE_HZ = 20_000.0
CHUNK = 64  # samples per chunk
RECEIVE_TIMEOUT_S = 10.0

EXPECTED_FIELDS = {
    ActuationCommand: {
        "header": "std_msgs/Header",
        "left_force_n": "double",
        "right_force_n": "double",
    },
    PivotForceChunk: {
        "header": "std_msgs/Header",
        "first_sample_index": "uint64",
        "sample_rate_hz": "double",
        "left_fx_n": "sequence<double>",
        "left_fy_n": "sequence<double>",
        "right_fx_n": "sequence<double>",
        "right_fy_n": "sequence<double>",
        "left_magnitude_n": "sequence<double>",
        "right_magnitude_n": "sequence<double>",
    },
    BrakeState: {
        "header": "std_msgs/Header",
        "sample_index": "uint64",
        "flywheel_angle_rad": "double",
        "drum_angle_rad": "double",
        "left_shoe_angle_rad": "double",
        "right_shoe_angle_rad": "double",
        "flywheel_speed_rad_s": "double",
        "drum_speed_rad_s": "double",
        "left_shoe_speed_rad_s": "double",
        "right_shoe_speed_rad_s": "double",
        "left_indentation_m": "double",
        "right_indentation_m": "double",
        "left_normal_force_n": "double",
        "right_normal_force_n": "double",
        "left_friction_force_n": "double",
        "right_friction_force_n": "double",
        "left_actuation_force_n": "double",
        "right_actuation_force_n": "double",
        "left_contact_x_m": "double",
        "left_contact_y_m": "double",
        "right_contact_x_m": "double",
        "right_contact_y_m": "double",
        "left_in_contact": "boolean",
        "right_in_contact": "boolean",
        "regime": "uint8",
    },
    DefectState: {
        "header": "std_msgs/Header",
        "run_id": "string",
        "scenario": "string",
        "unit_id": "string",
        "seed": "uint64",
        "healthy": "boolean",
        "defects": "sequence<brake_sim_msgs/Defect>",
        "labels": "sequence<string>",
    },
    Defect: {
        "kind": "string",
        "location": "string",
        "severity": "double",
        "unit": "string",
        "onset_s": "double",
        "growth": "string",
        "growth_rate": "double",
        "attribute_names": "sequence<string>",
        "attribute_values": "sequence<double>",
    },
    ContactEvent: {
        "header": "std_msgs/Header",
        "run_id": "string",
        "sample_index": "uint64",
        "shoe": "uint8",
        "kind": "uint8",
        "peak_pivot_force_n": "double",
        "peak_sample_index": "uint64",
        "duration_s": "double",
    },
    MeasuredChunk: {
        "header": "std_msgs/Header",
        "first_sample_index": "uint64",
        "sample_count": "uint32",
        "sample_rate_hz": "double",
        "channel_names": "sequence<string>",
        "units": "sequence<string>",
        "decimation": "sequence<uint32>",
        "channel_sample_counts": "sequence<uint32>",
        "values": "sequence<double>",
        "fault_labels": "sequence<uint8>",
        "edge_channel_names": "sequence<string>",
        "tone_ring_teeth": "sequence<uint32>",
        "edge_counts": "sequence<uint32>",
        "edge_times_s": "sequence<double>",
    },
    StepSimulation.Request: {"steps": "uint64", "duration_s": "double"},
    StepSimulation.Response: {
        "success": "boolean",
        "message": "string",
        "sample_index": "uint64",
        "sim_time_s": "double",
    },
    ResetSimulation.Request: {"scenario": "string", "seed": "int64"},
    ResetSimulation.Response: {"success": "boolean", "message": "string"},
}


@pytest.mark.parametrize("msg_type", list(EXPECTED_FIELDS), ids=lambda t: t.__qualname__)
def test_fields_and_types(msg_type):
    # Same names, same types, same order as specified.
    assert list(msg_type.get_fields_and_field_types().items()) == list(
        EXPECTED_FIELDS[msg_type].items()
    )


def test_regime_constants():
    assert (
        BrakeState.REGIME_FREE,
        BrakeState.REGIME_IMPACTING,
        BrakeState.REGIME_CONTACT,
        BrakeState.REGIME_STOPPED,
    ) == (0, 1, 2, 3)


def test_measured_fault_bits_are_the_core_s():
    from brake_sim_ros.sensing.faults import FAULT_BIT

    assert {k: getattr(MeasuredChunk, f"FAULT_{k.upper()}") for k in FAULT_BIT} == FAULT_BIT


def test_defaults_and_type_checks():
    msg = PivotForceChunk()
    assert msg.first_sample_index == 0
    assert len(msg.left_fx_n) == 0
    msg.left_fx_n = [1.0, -2.5]
    assert list(msg.left_fx_n) == [1.0, -2.5]
    req = ResetSimulation.Request()
    assert req.scenario == "" and req.seed == 0
    entry = Defect(kind="pivot_radius_change", location="left", severity=3.0, unit="%")
    state = DefectState(defects=[entry], labels=[entry.kind])
    assert state.defects[0].severity == 3.0 and state.labels == ["pivot_radius_change"]


def _expected_chunk(first: int) -> dict[str, list[float]]:
    """Deterministic chunk content, computed identically in both processes."""
    k = range(first, first + CHUNK)
    lfx = [100.0 * math.sin(0.01 * i) for i in k]
    lfy = [-50.0 + 0.25 * i for i in k]
    rfx = [-75.0 * math.cos(0.02 * i) for i in k]
    rfy = [1e3 + 1e-3 * i for i in k]
    return {
        "left_fx_n": lfx,
        "left_fy_n": lfy,
        "right_fx_n": rfx,
        "right_fy_n": rfy,
        "left_magnitude_n": [math.hypot(x, y) for x, y in zip(lfx, lfy, strict=True)],
        "right_magnitude_n": [math.hypot(x, y) for x, y in zip(rfx, rfy, strict=True)],
    }


# The publisher process: publishes consecutive chunks at 20 Hz until killed
# (or for at most 20 s, so that an orphan cannot linger). _expected_chunk's
# source is prepended, so both processes compute the same content.
# argv: topic frame_id sample_rate_hz chunk_size
PUBLISHER_MAIN = """
import sys
import time

import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from brake_sim_msgs.msg import PivotForceChunk

topic, frame = sys.argv[1], sys.argv[2]
rate_hz, CHUNK = float(sys.argv[3]), int(sys.argv[4])

rclpy.init()
node = rclpy.create_node("brake_sim_test_publisher")
qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                 durability=DurabilityPolicy.VOLATILE)
pub = node.create_publisher(PivotForceChunk, topic, qos)
first = 0
deadline = time.monotonic() + 20.0
try:
    while rclpy.ok() and time.monotonic() < deadline:
        msg = PivotForceChunk(**_expected_chunk(first))
        msg.header.frame_id = frame
        t_ns = round(first / rate_hz * 1e9)
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(t_ns, 1_000_000_000)
        msg.first_sample_index = first
        msg.sample_rate_hz = rate_hz
        pub.publish(msg)
        first += CHUNK
        time.sleep(0.05)
except Exception:
    if rclpy.ok():  # a real error, not the SIGTERM sent by the test
        raise
finally:
    rclpy.try_shutdown()
"""
PUBLISHER = "import math\n\n" + inspect.getsource(_expected_chunk) + PUBLISHER_MAIN


@pytest.fixture
def ros_domain(monkeypatch):
    # 1..100: per run (per pytest-xdist worker: a range of its own), and inside the range
    # that is safe from the Linux ephemeral ports (domain ids above ~101 map to ports that
    # can collide). Offset 0: no other test uses it.
    domain_id = domain_id_for(0)
    monkeypatch.setenv("ROS_DOMAIN_ID", str(domain_id))
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    monkeypatch.delenv("ROS_STATIC_PEERS", raising=False)
    return domain_id


def test_pivot_force_chunk_round_trip_over_dds(ros_domain, tmp_path):
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    # Same interpreter (the venv's): the subprocess inherits the ROS wheels'
    # bootstrapped LD_LIBRARY_PATH and ROS_DOMAIN_ID from this process.
    publisher_log = tmp_path / "publisher.log"
    with publisher_log.open("w") as log:
        proc = subprocess.Popen(
            [sys.executable, "-c", PUBLISHER, TOPIC, FRAME, repr(RATE_HZ), str(CHUNK)],
            stdout=log,
            stderr=subprocess.STDOUT,
        )
    received: list[PivotForceChunk] = []
    context = Context()
    rclpy.init(context=context, domain_id=ros_domain)
    try:
        node = rclpy.create_node("brake_sim_test_subscriber", context=context)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        qos = QoSProfile(
            depth=10,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.VOLATILE,
        )
        node.create_subscription(PivotForceChunk, TOPIC, received.append, qos)
        deadline = time.monotonic() + RECEIVE_TIMEOUT_S
        while len(received) < 2 and time.monotonic() < deadline and proc.poll() is None:
            executor.spin_once(timeout_sec=0.1)
        executor.shutdown()
        node.destroy_node()
    finally:
        context.try_shutdown()
        if proc.poll() is None:
            proc.terminate()  # SIGTERM: rclpy shuts down, the loop ends cleanly
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()

    output = publisher_log.read_text()
    assert len(received) >= 2, (
        f"received {len(received)} PivotForceChunk within {RECEIVE_TIMEOUT_S} s on "
        f"ROS_DOMAIN_ID={ros_domain}; publisher exit code {proc.returncode}, output:\n{output}"
    )
    assert proc.returncode in (0, -signal.SIGTERM), output
    assert "Traceback" not in output, output

    first, second = received[0], received[1]
    for msg in (first, second):
        assert msg.header.frame_id == FRAME
        assert msg.sample_rate_hz == RATE_HZ
        assert msg.first_sample_index % CHUNK == 0
        # header.stamp = simulated time of the first sample
        t_ns = round(msg.first_sample_index / RATE_HZ * 1e9)
        assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == divmod(t_ns, 1_000_000_000)
        expected = _expected_chunk(msg.first_sample_index)
        for field, values in expected.items():
            got = list(getattr(msg, field))
            assert got == values, field  # bit-exact float64 transport
    # Consecutive chunks: the running index lets a subscriber detect gaps.
    assert second.first_sample_index == first.first_sample_index + CHUNK
