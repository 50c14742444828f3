"""A real node (paused, stepped over ~/step, own ROS domain) on a scenario whose defects
grow: its DefectState messages are the offline stream's, stamp for stamp and severity for
severity, and a run-time change of a growing defect's value keeps its growth law."""

from __future__ import annotations

from brake_sim_ros import stream
from brake_sim_ros.ros.harness import domain_id_for
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.stream.offline import offline_messages

GROWING = (
    'name = "growing"\nduration_s = 2.0\n[defects.left]\n'
    'pivot_radius_change_pct = {value = 2.0, onset_s = 0.1, growth = "linear",'
    " rate_per_s = 4.0}\n"
)
SAMPLES = 16_384  # 0.64 s at 25.6 kHz: the onset, growth and the final value


def _truth(msg) -> tuple:
    return tuple(
        (d.kind, d.location, d.severity, d.onset_s, d.growth, d.growth_rate) for d in msg.defects
    )


def test_the_node_publishes_the_growing_truth_the_offline_stream_does(tmp_path, node_and_client):
    (tmp_path / "growing.toml").write_text(GROWING)
    args = ["--duration", "3600", "--ros-args", "-p", "paused:=true",
            "-p", f"scenario_dirs:={tmp_path}"]  # fmt: skip
    with node_and_client(args, domain_id_for(74), wait_s=30.0) as (_, sim):
        assert sim.reset(scenario="growing.toml", timeout_s=10.0).success
        sim.wait_for(
            lambda: sim.rx.defects and sim.rx.defects[-1].scenario == "growing", 5.0, "reset"
        )
        sim.forget()
        for _ in range(SAMPLES // 4096):
            assert sim.step(steps=4096).success
        offline = [
            (ns, _truth(m))
            for topic, m, ns in offline_messages(
                parse_scenario(GROWING), duration_s=SAMPLES / 25_600.0
            )
            if topic is stream.DEFECTS and ns > 0
        ]
        assert len(offline) > 5
        sim.wait_for(lambda: len(sim.rx.defects) >= len(offline), 10.0, "the growing truth")
        got = [
            (m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec, _truth(m))
            for m in sim.rx.defects
        ]
        assert got == offline
        # a live change of the final value keeps the onset and the law
        result = sim.set_parameter("defects.left.pivot_radius_change_pct", 3.0)
        assert result.successful, result.reason
        sim.wait_for(lambda: len(sim.rx.defects) > len(offline), 5.0, "the truth after the change")
        (changed,) = sim.rx.defects[-1].defects
        assert (changed.growth, changed.growth_rate, changed.onset_s) == ("linear", 4.0, 0.1)
        assert dict(zip(changed.attribute_names, changed.attribute_values, strict=True)) == {
            "final_severity_pct": 3.0
        }
