"""A drive cycle through the ROS node, over real DDS: the node streams the urban cycle's
first seconds as the offline stepper does, bit for bit, and refuses actuation commands
(the cycle commands the brake) without stopping."""

from __future__ import annotations

import numpy as np
import pytest

from brake_sim_ros.model.layout import COL
from brake_sim_ros.ros.harness import LOSSLESS, domain_id_for
from brake_sim_ros.scenarios import load_scenario, parse_scenario
from brake_sim_ros.stream.build import stepper_for
from tests.model.test_cycle_load import LAPS

DOMAIN = domain_id_for(23)
RUN_S = 1.0


def test_the_node_streams_a_drive_cycle_and_refuses_commands_to_its_brake(node_and_client):
    args = ["--scenario", "urban", "--duration", str(RUN_S), "--ros-args", "-p", "paused:=true",
            "-p", "real_time_factor:=0.0", "-p", "diagnostics_period_s:=0.2"]  # fmt: skip
    with node_and_client(args, DOMAIN, stream_qos=LOSSLESS) as (_, client):
        client.spin_for(0.2)
        assert client.set_parameter("paused", False).successful
        client.command(500.0, 500.0)  # a brake the cycle commands: refused, the run goes on
        client.wait_for(
            lambda: client.diagnostics().get("state") == "finished", 60.0, "the end of the run"
        )
        scenario = load_scenario("urban")
        n = round(RUN_S * scenario.sample_rate_hz)
        client.wait_for(lambda: client.sample_count >= n, 10.0, "every sample")
        diag = client.next_diagnostics()
    assert int(diag["commands_rejected"]) >= 1 and int(diag["commands_accepted"]) == 0
    assert "drive cycle" in diag["last_command_rejection"]
    got = client.chunk_arrays()
    offline = stepper_for(scenario).run(RUN_S).data
    np.testing.assert_array_equal(got["index"], np.arange(len(offline)))
    for side in ("left", "right"):
        for axis in ("fx", "fy"):
            np.testing.assert_array_equal(
                got[f"{side}_{axis}_n"], offline[:, COL[f"{side}_pivot_{axis}_n"]]
            )
    # the vehicle drove: the drum speeds up from rest in the first second
    assert offline[-1, COL["drum_speed_rad_s"]] > 1.0


@pytest.mark.slow
def test_the_node_carries_the_load_a_hold_draws_across_its_chunks(tmp_path, node_and_client):
    """A repeating cycle whose standing holds change the vehicle's load (tests/
    test_cycle_load.py), streamed by the node over 6 s: the second lap drives and brakes
    with the drawn load, and the published pivot forces equal the offline run's bit for
    bit (the node's own chunking carries the load and the draw count)."""
    path = tmp_path / "laden.toml"
    path.write_text(LAPS.format(seed=5))
    run_s = 6.0
    args = ["--scenario", str(path), "--duration", str(run_s), "--ros-args", "-p", "paused:=true",
            "-p", "real_time_factor:=0.0", "-p", f"scenario_dirs:={tmp_path}"]  # fmt: skip
    scenario = parse_scenario(path.read_text(), str(path))
    n = round(run_s * scenario.sample_rate_hz)
    with node_and_client(args, DOMAIN, stream_qos=LOSSLESS) as (_, client):
        client.spin_for(0.2)
        assert client.set_parameter("paused", False).successful
        client.wait_for(
            lambda: client.diagnostics().get("state") == "finished", 120.0, "the end of the run"
        )
        client.wait_for(lambda: client.sample_count >= n, 10.0, "every sample")
    offline = stepper_for(scenario).run(run_s)
    inertia, segment = offline["flywheel_inertia_kg_m2"], offline["cycle_segment"]
    changed = np.flatnonzero(inertia != inertia[0])[0]  # the first load change
    assert np.any(segment[changed:] == 0.0) and np.any(segment[changed:] == 1.0)  # lap 2
    got = client.chunk_arrays()
    np.testing.assert_array_equal(got["index"], np.arange(len(offline)))
    for side in ("left", "right"):
        for axis in ("fx", "fy"):
            np.testing.assert_array_equal(
                got[f"{side}_{axis}_n"], offline[f"{side}_pivot_{axis}_n"]
            )
