"""The brake_sim node in real time, over real DDS, started as a user would start it.

One node process runs the symmetric scenario for 3 s of simulated time at real-time
factor 1 while this module's client (its own rclpy context, on a ROS domain of its own)
checks the interfaces, sends bad commands and bad parameters, and records everything.
The recorded stream must be complete, stamped with simulated time, and equal, sample for
sample, to the offline run of the same stepper (``stepper_for``): the refused inputs
changed nothing.
"""

from __future__ import annotations

import itertools
import math
import re
import subprocess
import sys
import time

import numpy as np
import pytest
from rclpy.qos import (
    DurabilityPolicy,
    ReliabilityPolicy,
)

from brake_sim_ros import stream
from brake_sim_ros.ros import qos
from brake_sim_ros.ros.harness import (
    LOSSLESS,
    domain_id_for,
    ros_environment,
)
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.stream import conversion
from brake_sim_ros.stream.build import stepper_for
from tests import cli_process

DOMAIN = domain_id_for(1)
RUN_S = 3.0
PERIOD = 1 / 25_600  # the scenario's sample rate
N_SAMPLES = round(RUN_S / PERIOD)
CHUNK = 256  # 100 chunks per simulated second
BAD_COMMANDS = [(math.nan, 0.0), (0.0, math.inf), (-math.inf, 0.0), (-1.0, 0.0), (0.0, 1e9)]
BAD_PARAMETERS = {
    "friction.coefficient": 1.5,  # outside the descriptor's range
    "contact.damping_n_s_per_m": "high",  # wrong type
    "defects.left.initial_angle_deg": 10.0,  # lining inside the drum (core)
    "driveline.drum_inertia_kg_m2": 1e-6,  # a step limit of 2 ns: pathological (core)
    "max_actuation_force_n": 100.0,  # fixed at start-up
    "measured_rate_hz": 0.0,  # outside the range, and fixed at start-up
}


@pytest.fixture(scope="module")
def run(node_and_client):
    """Start the node, record its whole 3 s run, stop it; return (client, node process)."""
    # started paused: the stream is recorded from sample 0 once discovery is complete
    args = ["--duration", str(RUN_S), "--ros-args", "-p", "paused:=true",
            "-p", "diagnostics_period_s:=0.2"]  # fmt: skip
    with node_and_client(args, DOMAIN, stream_qos=LOSSLESS, wait_s=30.0, exit_code=None) as (
        node,
        client,
    ):
        client.spin_for(0.2)
        assert client.set_parameter("paused", False).successful
        client.refusals = {}
        for left, right in BAD_COMMANDS:
            client.command(left, right)
        for name, value in BAD_PARAMETERS.items():
            client.refusals[name] = client.set_parameter(name, value)
        client.wait_for(
            lambda: client.diagnostics().get("state") == "finished", RUN_S + 15.0, "end of the run"
        )
        client.wait_for(lambda: client.sample_count >= N_SAMPLES, 5.0, "all samples")
        client.final = client.next_diagnostics()
        yield client, node


@pytest.mark.realtime  # these share the module's run, paced against the wall clock
def test_topics_types_qos_and_services(run):
    client, _ = run
    topics = dict(client.node.get_topic_names_and_types())
    expected = {
        "/brake_sim/pivot_forces": "brake_sim_msgs/msg/PivotForceChunk",
        "/brake_sim/state": "brake_sim_msgs/msg/BrakeState",
        "/brake_sim/joint_states": "sensor_msgs/msg/JointState",
        "/brake_sim/defects": "brake_sim_msgs/msg/DefectState",
        "/brake_sim/actuation": "brake_sim_msgs/msg/ActuationCommand",
        "/clock": "rosgraph_msgs/msg/Clock",
        "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
    }
    for topic, type_name in expected.items():
        assert topics.get(topic) == [type_name], topic

    def offered(topic):
        infos = [
            i for i in client.node.get_publishers_info_by_topic(topic) if i.node_name == "brake_sim"
        ]
        assert len(infos) == 1, topic
        return infos[0].qos_profile

    for topic in ("/brake_sim/pivot_forces", "/brake_sim/state", "/brake_sim/joint_states"):
        profile = offered(topic)  # REP 2003: a driver offers system-default (reliable) QoS
        assert profile.reliability == ReliabilityPolicy.RELIABLE
        assert profile.durability == DurabilityPolicy.VOLATILE
    defects = offered("/brake_sim/defects")
    assert defects.reliability == ReliabilityPolicy.RELIABLE
    assert defects.durability == DurabilityPolicy.TRANSIENT_LOCAL
    assert offered("/clock").reliability == ReliabilityPolicy.BEST_EFFORT
    services = dict(client.node.get_service_names_and_types())
    assert services["/brake_sim/step"] == ["brake_sim_msgs/srv/StepSimulation"]
    assert services["/brake_sim/reset"] == ["brake_sim_msgs/srv/ResetSimulation"]


@pytest.mark.realtime
def test_chunks_are_contiguous_and_complete(run):
    client, _ = run
    chunks = client.rx.chunks
    assert client.gaps == 0
    assert chunks[0].first_sample_index == 0
    for a, b in itertools.pairwise(chunks):
        assert b.first_sample_index == a.first_sample_index + len(a.left_fx_n)
    assert sum(len(c.left_fx_n) for c in chunks) == N_SAMPLES
    assert {len(c.left_fx_n) for c in chunks} == {CHUNK}
    assert {c.sample_rate_hz for c in chunks} == {25_600.0}
    for c in chunks:
        for name in conversion.PIVOT_CHUNK_ARRAYS:
            assert np.isfinite(np.asarray(getattr(c, name))).all()


@pytest.mark.realtime
def test_stamps_are_simulated_time(run):
    client, _ = run
    rx = client.rx

    def ns(stamp):
        return stamp.sec * 1_000_000_000 + stamp.nanosec

    def at(index):  # every stamp is its sample's time: index x 39062.5 ns, to the ns
        return conversion.stamp_ns(index, PERIOD)

    for c in rx.chunks:
        assert ns(c.header.stamp) == at(c.first_sample_index) == c.first_sample_index // 256 * 10**7
        assert c.header.frame_id == "brake_backing_plate"
    assert [s.sample_index for s in rx.states] == list(range(0, N_SAMPLES, CHUNK))
    for s, j in zip(rx.states, rx.joints, strict=True):
        assert ns(s.header.stamp) == at(s.sample_index) == ns(j.header.stamp)
        assert s.header.frame_id == j.header.frame_id == "brake_backing_plate"
        assert list(j.name) == ["flywheel", "drum", "left_shoe", "right_shoe"]
        assert list(j.position) == [
            s.flywheel_angle_rad,
            s.drum_angle_rad,
            s.left_shoe_angle_rad,
            s.right_shoe_angle_rad,
        ]
    clocks = [ns(c.clock) for c in rx.clocks]
    assert clocks == sorted(clocks) and clocks[-1] == at(N_SAMPLES) == RUN_S * 10**9
    for array in rx.diagnostics + rx.defects:
        assert ns(array.header.stamp) <= at(N_SAMPLES)  # not the wall clock's epoch


@pytest.mark.realtime
def test_the_stream_equals_the_offline_stepper(run):
    """Sample for sample: the bad commands and parameters changed nothing."""
    client, _ = run
    stepper = stepper_for(load_scenario("symmetric"))
    block = stepper.advance(N_SAMPLES)
    diag = client.final
    assert float(diag["physics_step_s"]) == stepper.physics_step_s == PERIOD
    assert (diag["substeps_per_sample"], diag["step_limit_force_n"]) == ("1", "1300")
    got = client.chunk_arrays()
    np.testing.assert_array_equal(got["index"], np.arange(N_SAMPLES))
    for side in ("left", "right"):
        np.testing.assert_array_equal(got[f"{side}_fx_n"], block[f"{side}_pivot_fx_n"])
        np.testing.assert_array_equal(got[f"{side}_fy_n"], block[f"{side}_pivot_fy_n"])
        np.testing.assert_array_equal(got[f"{side}_magnitude_n"], block.pivot_force_magnitude(side))
    states = client.rx.states
    np.testing.assert_array_equal(
        [s.left_normal_force_n for s in states], block["left_normal_force_n"][::CHUNK]
    )
    np.testing.assert_array_equal(
        [s.drum_speed_rad_s for s in states], block["drum_speed_rad_s"][::CHUNK]
    )


@pytest.mark.realtime
def test_bad_commands_and_parameters_are_refused_and_counted(run):
    client, _ = run
    diag = client.final
    assert int(diag["commands_rejected"]) == len(BAD_COMMANDS)
    assert int(diag["commands_accepted"]) == 0
    assert "exceeds max_actuation_force_n" in diag["last_command_rejection"]
    assert int(diag["parameter_changes_refused"]) == len(BAD_PARAMETERS)
    reasons = {name: result.reason for name, result in client.refusals.items()}
    assert not any(result.successful for result in client.refusals.values())
    assert "out of range" in reasons["friction.coefficient"]
    assert "Wrong parameter type" in reasons["contact.damping_n_s_per_m"]
    assert "inside the drum" in reasons["defects.left.initial_angle_deg"]
    assert "smallest step taken" in reasons["driveline.drum_inertia_kg_m2"]
    assert "fixed at start-up" in reasons["max_actuation_force_n"]
    assert "measured_rate_hz" in reasons and "\n" not in reasons["measured_rate_hz"]
    values = client.get_parameters(list(BAD_PARAMETERS))
    assert values["friction.coefficient"] == 0.285
    assert values["max_actuation_force_n"] == float(diag["max_actuation_force_n"])


@pytest.mark.realtime
def test_pacing_tracks_the_wall_clock(run):
    client, _ = run
    times = client.rx.chunk_times
    assert times[-1] - times[0] == pytest.approx(RUN_S, rel=0.1)
    diag = client.final
    assert float(diag["real_time_factor_achieved"]) == pytest.approx(1.0, rel=0.05)
    assert diag["state"] == "finished"
    assert int(diag["deadline_misses"]) <= 5  # a loaded CI machine may miss a few


@pytest.mark.realtime
def test_ground_truth_is_latched_for_late_subscribers(run):
    client, _ = run
    from brake_sim_msgs.msg import DefectState

    late = []
    client.node.create_subscription(
        DefectState, "/brake_sim/defects", late.append, qos.for_topic(stream.DEFECTS)
    )
    client.wait_for(lambda: bool(late), 10.0, "latched DefectState")
    assert late[-1].scenario == "symmetric" and late[-1].healthy
    assert list(late[-1].defects) == [] and list(late[-1].labels) == []


def test_exit_at_end_prints_a_summary_and_exits_0(nodes):
    code, out = nodes.run(
        ["--duration", "0.5", "--exit-at-end", "--ros-args", "-p", "real_time_factor:=0.0"],
        domain_id_for(3),
    )
    assert code == 0, out
    assert "ended at simulated time 0.5000 s" in out
    assert "published 12800 samples in 50 chunks" in out
    assert "commands accepted 0, rejected 0" in out


@pytest.mark.slow
def test_brake_sim_node_command_runs_a_scenario_to_the_end():
    """The README's main command, through the ``brake-sim`` CLI, shortened."""
    proc = cli_process.run(
        [
            sys.executable,
            "-m",
            "brake_sim_ros.cli",
            "node",
            "--scenario",
            "case1_left_pivot_out",
            "--duration",
            "0.3",
            "--exit-at-end",
            "--ros-args",
            "-p",
            "real_time_factor:=0.0",
        ],
        env=ros_environment(domain_id_for(5)),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    out = proc.stdout + proc.stderr
    assert "case1_left_pivot_out" in out and "ended at simulated time 0.3000 s" in out


@pytest.mark.slow
def test_a_defect_and_a_force_that_need_small_steps_are_not_refused():
    """Friction smoothed over 5 mm/s with commands up to 20 kN allowed (limit far below the
    sample interval): the node starts, at the scenario's sample rate, and says which
    physics step it takes."""
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "brake_sim_ros.app.node",
            "--scenario",
            "symmetric",
            "--duration",
            "0.05",
            "--exit-at-end",
            "--ros-args",
            "-p",
            "real_time_factor:=0.0",
            "-p",
            "friction.smoothing_speed_m_s:=0.005",
            "-p",
            "max_actuation_force_n:=20000.0",
        ],
        env=ros_environment(domain_id_for(6)),
        capture_output=True,
        text=True,
        timeout=120,
    )
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out
    found = re.search(r"25600 Hz samples, physics step ([0-9.e+-]+) s \((\d+) per sample", out)
    assert found, out
    substeps = int(found.group(2))
    assert substeps >= 3
    assert float(found.group(1)) == pytest.approx(1 / 25_600 / substeps, rel=1e-3)
    assert "published 1280 samples" in out


@pytest.mark.slow
@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--ros-args", "-p", "driveline.drum_inertia_kg_m2:=1e-06"], "smallest step taken"),
        (["--scenario", "no_such_scenario"], "unknown scenario 'no_such_scenario'"),
        (["--ros-args", "-p", "defects.left.initial_angle_deg:=10.0"], "inside the drum"),
        # 25.6 kHz at 1000x real time: 10 us of wall time per 256-sample chunk, far below
        # the stepper's cost on any machine
        (["--ros-args", "-p", "real_time_factor:=1000.0"], "cannot keep real time"),
    ],
)
def test_refuses_to_start_with_a_one_line_reason(args, message, tmp_path):
    start = time.monotonic()
    proc = subprocess.run(
        [sys.executable, "-m", "brake_sim_ros.app.node", *args],
        env=ros_environment(domain_id_for(4)),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 1, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.startswith("brake_sim:")]
    assert len(lines) == 1 and message in lines[0], proc.stderr
    assert time.monotonic() - start < 30.0
