"""A real node and the hydraulic line's defects (catalogue location ``line``): on the study
brake its ``defects.line.*`` parameters refuse a value in one line (no circuit); after a
~/reset to a service-brake scenario the same parameter injects a leak live and the ground
truth lists it."""

from __future__ import annotations

from brake_sim_ros.ros.harness import domain_id_for

SERVICE = 'name = "service"\nbrake = "service"\nduration_s = 2.0\n'


def _line(truth) -> list[tuple]:
    return [(d.kind, d.severity, d.unit) for d in truth.defects if d.location == "line"]


def test_a_line_leak_is_refused_on_the_study_brake_and_injected_live_on_the_service_brake(
    tmp_path, node_and_client
):
    (tmp_path / "service.toml").write_text(SERVICE)
    args = ["-p", f"scenario_dirs:={tmp_path}", "-p", "real_time_factor:=0.2"]  # a busy CPU
    with node_and_client(
        ["--duration", "3600", "--ros-args", *args], domain_id_for(75), wait_s=30.0
    ) as (_, sim):
        refused = sim.set_parameter("defects.line.line_leak_pct", 20.0)  # symmetric: study
        assert not refused.successful
        assert "line_leak_pct=20 is invalid on the study brake" in refused.reason
        assert "\n" not in refused.reason
        assert sim.reset(scenario="service.toml", timeout_s=10.0).success
        n = len(sim.rx.defects)
        result = sim.set_parameter("defects.line.line_leak_pct", 20.0)
        assert result.successful, result.reason
        sim.wait_for(lambda: len(sim.rx.defects) > n, 5.0, "ground truth after the change")
        assert _line(sim.rx.defects[-1]) == [("line_leak", 20.0, "%")]
        refused = sim.set_parameter("defects.line.air_in_line_ml", 50.0)  # the range
        assert not refused.successful and "out of range" in refused.reason
