"""A paused run needs no real time: a node started paused (stepped over ~/step, as a
co-simulation drives it) starts at a real-time factor this machine cannot keep, steps on
request, and is refused in one line when it is resumed at that factor; once the factor
is one it can keep, it resumes. Real node, real DDS, own ROS domain."""

from __future__ import annotations

from brake_sim_ros.ros.harness import domain_id_for

HOPELESS = 1000.0  # a thousand times real time: no machine keeps it


def test_a_paused_node_starts_whatever_its_pace_and_is_checked_at_resume(node_and_client):
    args = ["--duration", "3600", "--ros-args", "-p", "paused:=true",
            "-p", f"real_time_factor:={HOPELESS}"]  # fmt: skip
    with node_and_client(args, domain_id_for(93), wait_s=30.0) as (node, sim):
        assert sim.step(steps=256).success
        refused = sim.set_parameter("paused", False)
        assert not refused.successful and "cannot keep real time" in refused.reason
        assert "\n" not in refused.reason
        assert sim.get_parameters(["paused"]) == {"paused": True}
        assert sim.step(steps=256).success  # still stepped on request
        assert sim.set_parameters_atomically(
            {"real_time_factor": 0.0, "paused": False}
        ).successful  # as fast as it goes: nothing to keep up with
    assert "started paused: the real-time check runs at resume" in node.output()
