"""One running node under a barrage of hostile ``~/reset`` requests and parameter sets.

Every request is refused with one line that quotes nothing of any file, and after each
the node is alive and still publishing pivot forces within 1 s. The node allows scenario
files from one directory (``scenario_dirs``) of this test; a secret file lies outside it.
"""

from __future__ import annotations

import math
import os
import sys
import time
import uuid
from pathlib import Path

import pytest
import rclpy
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from brake_sim_ros.ros.harness import (
    SimClient,
    domain_id_for,
    ros_environment,
)
from brake_sim_ros.scenarios import loader
from brake_sim_ros.scenarios.files import MAX_SCENARIO_BYTES
from tests import cli_process

# each refusal answered within 1-2 s of wall time, then a chunk in 1 s
pytestmark = pytest.mark.realtime

DOMAIN = domain_id_for(17)
MARKER = f"SECRET{uuid.uuid4().hex[:12]}"  # in every hostile file: must never come back
BUILTIN = Path(loader.__file__).parent / "builtin" / "symmetric.toml"
REPLY_TIMEOUT_S = 5.0  # a request the node cannot answer this fast hangs it


def _scenario_text(**solver) -> str:
    """The symmetric scenario with a [solver] table of ``solver`` (it has none)."""
    table = "\n".join(f"{k} = {v}" for k, v in solver.items())
    return BUILTIN.read_text() + f"\n[solver]\n{table}\n"


@pytest.fixture(scope="module")
def dirs(tmp_path_factory):
    root = tmp_path_factory.mktemp("hostile")
    allowed, outside = root / "allowed", root / "outside"
    allowed.mkdir()
    outside.mkdir()
    (outside / "secret.toml").write_text(f'name = "{MARKER}"\n')
    (allowed / "good.toml").write_text(BUILTIN.read_text())
    os.symlink(outside / "secret.toml", allowed / "link.toml")
    os.mkfifo(allowed / "fifo.toml")
    (allowed / "dir.toml").mkdir()
    (allowed / "binary.toml").write_bytes(os.urandom(2000) + MARKER.encode())
    (allowed / "nul.toml").write_text(f'name = "{MARKER}\x00"\n')
    (allowed / "deep.toml").write_text("a = " + "[" * 5000 + "]" * 5000 + f"\n# {MARKER}\n")
    (allowed / "huge.toml").write_text(f"# {MARKER}\n" * (MAX_SCENARIO_BYTES // 10))
    (allowed / "syntax.toml").write_text(f"name = 'x'\n{MARKER} == {MARKER}\n")
    (allowed / "invalid.toml").write_text(f'name = "x"\nseed = "{MARKER}"\n{MARKER} = 1\n')
    for name, step in (("femto", "1e-300"), ("nano", "1e-9"), ("nan", "nan"), ("inf", "inf")):
        (allowed / f"{name}_step.toml").write_text(_scenario_text(max_step_s=step))
    return allowed, outside


@pytest.fixture(scope="module")
def sim(dirs, node_and_client):
    allowed, _outside = dirs
    args = ["--duration", "3600", "--ros-args", "-p", f"scenario_dirs:={allowed}",
            "-p", "diagnostics_period_s:=0.2"]  # fmt: skip
    with node_and_client(args, DOMAIN, wait_s=30.0) as (node, client):
        yield client
    assert MARKER not in node.output()  # not in the node's log (/rosout) either


def assert_refused_and_alive(sim: SimClient, success: bool, message: str) -> None:
    assert not success, message
    assert message and "\n" not in message and len(message) < 1000, message
    assert MARKER not in message, message
    chunks = sim.chunk_count
    sim.wait_for(lambda: sim.chunk_count > chunks, 1.0, "pivot-force chunk after the refusal")


def test_a_good_file_in_an_allowed_dir_is_accepted(sim, dirs):
    allowed, _ = dirs
    for request in ("good.toml", str(allowed / "good.toml"), "symmetric"):
        response = sim.reset(scenario=request, timeout_s=REPLY_TIMEOUT_S)
        assert response.success, response.message


@pytest.mark.parametrize(
    ("request_name", "why"),
    [
        ("x" * 256, "unknown scenario"),
        ("a\nb", "printable"),
        ("/dev/zero", "outside the allowed directories"),
        ("/etc/passwd", "outside the allowed directories"),
        ("fifo.toml", "allowed a regular file"),
        ("dir.toml", "allowed a regular file"),
        ("link.toml", "outside the allowed directories"),
        ("../outside/secret.toml", "outside the allowed directories"),
        ("{outside}/secret.toml", "outside the allowed directories"),
        ("{allowed}/../outside/secret.toml", "outside the allowed directories"),
        ("binary.toml", "not UTF-8"),
        ("nul.toml", "NUL"),
        ("deep.toml", "nested too deep"),
        ("huge.toml", "at most"),
        ("syntax.toml", "not valid TOML (at line 2"),
        ("invalid.toml", "not a valid scenario"),
        ("femto_step.toml", "not a valid scenario"),  # max_step_s >= 1e-8
        ("nano_step.toml", "not a valid scenario"),
        ("nan_step.toml", "not a valid scenario"),
        ("inf_step.toml", "not a valid scenario"),
        ("missing.toml", "no such file"),
        ("./good.txt", "only .toml"),
    ],
)
def test_hostile_reset_is_refused_in_one_line(sim, dirs, request_name, why):
    allowed, outside = dirs
    request = request_name.format(allowed=allowed, outside=outside)
    start = time.monotonic()
    response = sim.reset(scenario=request, timeout_s=REPLY_TIMEOUT_S)
    assert time.monotonic() - start < 2.0
    assert why in response.message, response.message
    assert_refused_and_alive(sim, response.success, response.message)


def test_negative_seed_is_refused(sim):
    response = sim.reset(seed=-5, timeout_s=REPLY_TIMEOUT_S)
    assert "seed=-5" in response.message
    assert_refused_and_alive(sim, response.success, response.message)


@settings(
    max_examples=30,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(request=st.text(min_size=1, max_size=300))
def test_any_scenario_text_is_answered_in_one_line(sim, request):
    # a ROS string is a C string: the node receives the text up to its first NUL, and an
    # empty scenario field means "keep the current scenario"
    received = request.split("\x00", 1)[0]
    response = sim.reset(scenario=request, timeout_s=REPLY_TIMEOUT_S)
    if received == "" or received in loader.builtin_names():
        assert response.success, response.message
        return
    assert_refused_and_alive(sim, response.success, response.message)


@settings(
    max_examples=20,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(content=st.binary(max_size=4000))
def test_any_file_content_is_refused_without_quoting_it(sim, dirs, content):
    allowed, _ = dirs
    path = allowed / "fuzz.toml"
    path.write_bytes(MARKER.encode() + content + MARKER.encode())
    response = sim.reset(scenario="fuzz.toml", timeout_s=REPLY_TIMEOUT_S)
    assert_refused_and_alive(sim, response.success, response.message)


@pytest.mark.parametrize(
    ("values", "why"),
    [
        ({"chunk_rate_hzz": 5.0}, "did you mean chunk_rate_hz"),
        ({"shoe.mass_kgg": 1.0}, "did you mean shoe.mass_kg"),
        ({"shoe.mass_kg": 0.0}, "mass_kg=0.0 is invalid: allowed > 0"),
        ({"shoe.inertia_about_pivot_kg_m2": 0.0}, "allowed > 0"),
        ({"driveline.flywheel_inertia_kg_m2": 0.0}, "allowed > 0"),
        ({"driveline.drum_inertia_kg_m2": 0.0}, "allowed > 0"),
        ({"friction.coefficient": math.nan}, ""),
        (
            {"shoe.pose": "eye"},
            "pose='eye' is invalid: allowed one of ['tip-abutment', 'eye-piston']",
        ),
        ({"shoe.pose": 1.0}, "expected 'Type.STRING'"),
        ({"shoe.mass_kg": math.inf}, ""),
        ({"chunk_rate_hz": 1000.0, "state_rate_hz": 10000.0}, "cannot keep real time"),
        ({"real_time_factor": 1000.0}, "cannot keep real time"),
    ],
)
def test_hostile_parameters_are_refused(sim, values, why):
    result = sim.set_parameters_atomically(values)
    assert why in result.reason, result.reason
    assert_refused_and_alive(sim, result.successful, result.reason)


def test_a_step_request_is_bounded_by_its_wall_time(sim):
    assert sim.set_parameter("paused", True).successful
    try:
        start = time.monotonic()
        response = sim.step(duration_s=59.99, timeout_s=REPLY_TIMEOUT_S)
        assert time.monotonic() - start < 1.0
        assert not response.success
        assert "allowed at most" in response.message and "per call" in response.message
    finally:
        assert sim.set_parameter("paused", False).successful
    chunks = sim.chunk_count
    sim.wait_for(lambda: sim.chunk_count > chunks, 1.0, "pivot-force chunk after the refusal")


@pytest.mark.parametrize(
    "request_fields",
    [
        {"duration_s": math.nan},
        {"duration_s": math.inf},
        {"duration_s": -math.inf},
        {"duration_s": -1.0},
        {"duration_s": 1e-300},
        {"duration_s": 1e-9},
        {"duration_s": 1e300},
        {"steps": 2**64 - 1},
        {"steps": 10, "duration_s": 1.0},
        {},
    ],
)
def test_hostile_step_requests_are_refused(sim, request_fields):
    assert sim.set_parameter("paused", True).successful
    try:
        start = time.monotonic()
        response = sim.step(**request_fields, timeout_s=REPLY_TIMEOUT_S)
        assert time.monotonic() - start < 1.0
        assert not response.success and "\n" not in response.message, response.message
    finally:
        assert sim.set_parameter("paused", False).successful
    chunks = sim.chunk_count
    sim.wait_for(lambda: sim.chunk_count > chunks, 1.0, "pivot-force chunk after the refusal")


QOS = "qos_overrides./brake_sim/pivot_forces.publisher"  # a publisher's QoS overrides


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["-p", "chunk_rate_hzz:=5.0"], "did you mean chunk_rate_hz"),
        (["-p", "shoe.mass_kg:=0.0"], "mass_kg=0.0 is invalid"),
        (["-p", "scenario_dirs:=/no/such/dir"], "allowed an existing directory"),
        (["-p", "chunk_rate_hz:=1000.0", "-p", "state_rate_hz:=10000.0"], "cannot keep real"),
        (["-p", "run_id:=a/b"], "run_id='a/b': allowed empty"),
        (["-p", f"run_id:={'x' * 65}"], "1 to 64 characters"),
        (["-p", f"{QOS}.depth:=0"], "depth an integer from 1 to 100000"),
        (["-p", f"{QOS}.depth:=100001"], "depth an integer from 1 to 100000"),
        (["-p", f"{QOS}.depth:=deep"], "depth an integer from 1 to 100000"),
        (["-p", f"{QOS}.reliability:={'x' * 500}"], "one of system_default, reliable, best_effort"),
        (["-p", "qos_overrides./brake_sim/pivot_force.publisher.depth:=9"], f"did you mean {QOS}"),
        (["-p", "qos_overrides./brake_sim/measured.publisher.depth:=9"], "not declared"),
    ],
)
def test_refuses_to_start_with_hostile_parameters(args, message):
    proc = cli_process.run(
        [sys.executable, "-m", "brake_sim_ros.app.node", "--ros-args", *args],
        env=ros_environment(domain_id_for(18)),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 1, proc.stdout + proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.startswith("brake_sim:")]
    assert len(lines) == 1 and message in lines[0], proc.stderr
    assert "x" * 80 not in lines[0]  # a hostile value is not echoed at any length


def test_heard_chunks_are_not_counted_as_unheard(sim):
    first = sim.next_diagnostics()
    sim.spin_for(0.5)
    later = sim.next_diagnostics()
    assert int(later["chunks_published"]) > int(first["chunks_published"])
    assert later["chunks_unheard"] == first["chunks_unheard"], (first, later)
    assert later["publish_failures"] == "0"


def test_chunks_nobody_subscribes_to_are_counted(nodes):
    """A listener of /diagnostics only: every chunk the node published went to nobody."""
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor

    from brake_sim_ros import stream
    from brake_sim_ros.ros import qos

    domain = domain_id_for(19)
    seen: list[dict[str, str]] = []

    def on_diagnostics(msg: DiagnosticArray) -> None:
        for status in msg.status:
            if status.hardware_id == "brake_sim":
                seen.append({kv.key: kv.value for kv in status.values})

    with nodes.process(["--ros-args", "-p", "diagnostics_period_s:=0.1"], domain) as node:
        context = Context()
        rclpy.init(context=context, domain_id=domain)
        listener = rclpy.create_node("diagnostics_listener", context=context)
        listener.create_subscription(
            DiagnosticArray, "/diagnostics", on_diagnostics, qos.for_topic(stream.DIAGNOSTICS)
        )
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(listener)
        try:
            end = time.monotonic() + 30.0
            while not (seen and int(seen[-1]["chunks_published"]) >= 10):
                assert time.monotonic() < end, node.output()
                executor.spin_once(timeout_sec=0.1)
            assert seen[-1]["chunks_unheard"] == seen[-1]["chunks_published"], seen[-1]
        finally:
            executor.shutdown(timeout_sec=1.0)
            listener.destroy_node()
            rclpy.try_shutdown(context=context)
