"""A real node on a scenario with an out-of-round drum: the harmonics have no node
parameter, and the node still runs them and says so in its ground truth, at start, after a
parameter change of a shoe defect and after a ~/reset to it; the drum's flat is injected
live through its parameters."""

from __future__ import annotations

from brake_sim_ros.ros.harness import domain_id_for

OVAL = (
    'name = "oval"\nduration_s = 2.0\n[defects.drum]\n'
    "harmonics = [{order = 2, amplitude_um = 50, phase_deg = 30}]\n"
)


def _drum(truth) -> list[tuple]:
    return [
        (d.severity, d.unit, list(d.attribute_names), list(d.attribute_values))
        for d in truth.defects
        if d.kind == "drum_out_of_round" and d.location == "drum"
    ]


def test_the_node_keeps_the_scenarios_drum_through_parameter_changes_and_resets(
    tmp_path, node_and_client
):
    (tmp_path / "oval.toml").write_text(OVAL)
    # a fifth of real time: the suite's busy CPU made the reset's real-time check refuse
    args = ["--duration", "3600", "--ros-args", "-p", f"scenario_dirs:={tmp_path}",
            "-p", "real_time_factor:=0.2"]  # fmt: skip
    expected = [(50.0, "um", ["order_2_amplitude_um", "order_2_phase_deg"], [50.0, 30.0])]
    with node_and_client(args, domain_id_for(73), wait_s=30.0) as (_, sim):
        assert _drum(sim.rx.defects[-1]) == []  # the built-in symmetric brake: round
        assert sim.reset(scenario="oval.toml", timeout_s=10.0).success
        sim.wait_for(lambda: _drum(sim.rx.defects[-1]) == expected, 5.0, "the oval drum")
        assert not sim.rx.defects[-1].healthy
        n = len(sim.rx.defects)
        result = sim.set_parameter("defects.left.pivot_radius_change_pct", 1.0)
        assert result.successful, result.reason
        sim.wait_for(lambda: len(sim.rx.defects) > n, 5.0, "ground truth after the change")
        truth = sim.rx.defects[-1]
        assert _drum(truth) == expected  # not dropped by the rebuild from parameters
        assert ("pivot_radius_change", "left", 1.0) in [
            (d.kind, d.location, d.severity) for d in truth.defects
        ]


def test_a_drum_flat_is_injected_live_through_its_parameters(tmp_path, node_and_client):
    (tmp_path / "oval.toml").write_text(OVAL)
    args = ["-p", f"scenario_dirs:={tmp_path}", "-p", "real_time_factor:=0.2"]  # a busy CPU
    with node_and_client(
        ["--duration", "3600", "--ros-args", *args], domain_id_for(74), wait_s=30.0
    ) as (_, sim):
        assert sim.reset(scenario="oval.toml", timeout_s=10.0).success
        sim.wait_for(lambda: _drum(sim.rx.defects[-1]) != [], 5.0, "the oval drum")
        n = len(sim.rx.defects)
        assert sim.set_parameter("defects.drum.flat_centre_deg", 90.0).successful
        result = sim.set_parameter("defects.drum.flat_depth_um", 40.0)
        assert result.successful, result.reason
        sim.wait_for(lambda: len(sim.rx.defects) > n, 5.0, "ground truth after the change")
        truth = sim.rx.defects[-1]
        flat = [
            (d.severity, d.unit, list(d.attribute_names), list(d.attribute_values))
            for d in truth.defects
            if d.kind == "drum_flat"
        ]
        assert flat == [(40.0, "um", ["centre_deg", "width_deg"], [90.0, 5.0])]
        assert _drum(truth) != []  # the scenario's harmonics stay
        refused = sim.set_parameter("defects.drum.flat_depth_um", 1500.0)  # the range
        assert not refused.successful and "out of range" in refused.reason
        assert sim.set_parameter("defects.drum.flat_width_deg", 2.0).successful
        refused = sim.set_parameter("defects.drum.flat_depth_um", 600.0)  # the core's slope
        assert not refused.successful
        assert "slope pi d / (2 w R0) = 0.3000, allowed at most 0.05" in refused.reason
