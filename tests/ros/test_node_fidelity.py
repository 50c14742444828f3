"""A real node with ``publish_measured:=true`` and scenarios whose fidelity plan builds no
sensors (``[needs]`` without ``measured_signals``): it refuses to start on one, and a
``~/reset`` to one is refused in one line while the node runs on, still measuring."""

from __future__ import annotations

import subprocess
import sys

import pytest

from brake_sim_ros.ros.harness import (
    domain_id_for,
    ros_environment,
)

LEAN = 'name = "lean"\nduration_s = 1.0\n[needs]\noutputs = ["impacts"]\n'
MEASURING = (
    'name = "measuring"\nduration_s = 1.0\n[needs]\noutputs = ["impacts", "measured_signals"]\n'
)


@pytest.fixture(scope="module")
def allowed(tmp_path_factory):
    root = tmp_path_factory.mktemp("fidelity")
    (root / "lean.toml").write_text(LEAN)
    (root / "measuring.toml").write_text(MEASURING)
    return root


def test_node_refuses_to_start_measuring_a_scenario_without_sensors(allowed):
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "brake_sim_ros.app.node",
            "--ros-args",
            "-p",
            f"scenario:={allowed / 'lean.toml'}",
            "-p",
            "publish_measured:=true",
        ],
        env=ros_environment(domain_id_for(71)),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 1, proc.stdout + proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.startswith("brake_sim:")]
    assert len(lines) == 1, proc.stderr
    assert "publish_measured true refused" in lines[0] and "'measured_signals'" in lines[0]


def test_reset_to_a_scenario_without_sensors_is_refused_and_the_node_runs_on(
    allowed, node_and_client
):
    args = ["--duration", "3600", "--ros-args", "-p", f"scenario_dirs:={allowed}",
            "-p", "publish_measured:=true",
            "-p", "real_time_factor:=0.2"]  # a busy CPU: pace not tested  # fmt: skip
    with node_and_client(args, domain_id_for(72), wait_s=30.0) as (_, sim):
        response = sim.reset(scenario="lean.toml", timeout_s=10.0)
        assert not response.success
        assert "\n" not in response.message and "publish_measured is on" in response.message
        assert "'measured_signals'" in response.message
        chunks, measured = sim.chunk_count, sim.measured_count
        sim.wait_for(
            lambda: sim.chunk_count > chunks and sim.measured_count > measured,
            5.0,
            "pivot-force and measured chunks after the refusal",
        )
        # a scenario whose [needs] ask for measured signals is taken
        response = sim.reset(scenario="measuring.toml", timeout_s=10.0)
        assert response.success, response.message
        measured = sim.measured_count
        sim.wait_for(lambda: sim.measured_count > measured, 5.0, "measured chunks")
