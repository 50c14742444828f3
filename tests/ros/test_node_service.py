"""A real node (private DDS domain) on the service brake: its parameters from the scenario
file and ``--ros-args`` as node parameters (``service.*``, ``service.tyre.*``), the road's
friction changed while it runs (recorded, and re-simulated bit for bit by ``brake-sim
resim``), a value the core refuses refused in one line, and a ``~/reset`` between the
brakes declaring and undeclaring the service brake's parameters with it."""

from __future__ import annotations

import pytest
from mcap.reader import make_reader

from brake_sim_ros.recording import metadata
from brake_sim_ros.ros.harness import domain_id_for
from tests.recording.test_resim_cli import pivot_arrays, resim

SERVICE = (
    'name = "service_node"\nbrake = "service"\nduration_s = 3600.0\nroad_friction = 0.5\n'
    "[actuation]\npeak_force_n = 2000.0\nstart_s = 0.01\nfull_s = 0.1\n"
    "[parameters.service]\nreturn_spring_preload_n = 80.0\n"
)
NAMES = ["service.return_spring_preload_n", "service.tyre.road_friction", "service.tyre.peak_ratio"]
STEPS = 2560  # 0.1 s a step request


@pytest.mark.slow
def test_the_node_runs_the_service_brake_and_its_road_change_resimulates(tmp_path, node_and_client):
    scenario = tmp_path / "service.toml"
    scenario.write_text(SERVICE)
    bag = tmp_path / "live.mcap"
    args = ["--scenario", str(scenario), "--record", str(bag), "--ros-args",
            "-p", "paused:=true", "-p", "service.tyre.peak_ratio:=1.4"]  # fmt: skip
    with node_and_client(args, domain_id_for(91)) as (_, sim):
        assert sim.get_parameters(NAMES) == dict(zip(NAMES, [80.0, 0.5, 1.4], strict=True))
        assert sim.step(steps=STEPS).success
        assert sim.set_parameter("service.tyre.road_friction", 0.15).successful  # ice
        refused = sim.set_parameter("service.residual_force_n", 95.0)  # above the preload
        assert not refused.successful
        assert "residual_force_n" in refused.reason and "\n" not in refused.reason
        assert sim.step(steps=STEPS).success
        assert sim.get_parameters(NAMES[1:2]) == {NAMES[1]: 0.15}
    with bag.open("rb") as f:
        records = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
    params, _ = metadata.model_from_record(records[metadata.MODEL])
    assert params.service.return_spring_preload_n == 80.0
    assert params.service.tyre.peak_ratio == 1.4  # the node's override, recorded
    out = tmp_path / "again.mcap"
    done = resim(bag, "--out", out)
    assert done.returncode == 0, done.stderr
    live, again = pivot_arrays(bag), pivot_arrays(out)
    assert len(live["index"]) >= 2 * STEPS
    assert "bit for bit" in done.stdout
    for name, values in live.items():
        assert values.tobytes() == again[name].tobytes(), name


def _undeclared(sim) -> None:
    for name in NAMES:
        result = sim.set_parameter(name, 0.3)
        assert not result.successful and "not declared by this node" in result.reason, name


@pytest.mark.slow
def test_a_reset_between_the_brakes_declares_the_service_parameters_with_its_brake(
    tmp_path, node_and_client
):
    (tmp_path / "service.toml").write_text(SERVICE)
    args = ["--duration", "3600", "--ros-args", "-p", "paused:=true",
            "-p", f"scenario_dirs:={tmp_path}"]  # fmt: skip
    with node_and_client(args, domain_id_for(92)) as (_, sim):
        _undeclared(sim)  # the study brake has none of them
        assert sim.reset(scenario=str(tmp_path / "service.toml")).success
        assert sim.get_parameters(NAMES) == dict(zip(NAMES, [80.0, 0.5, 1.5], strict=True))
        assert sim.set_parameter(NAMES[1], 0.3).successful
        assert sim.step(steps=STEPS).success
        assert sim.reset(scenario="symmetric").success
        _undeclared(sim)
        assert sim.get_parameters(["friction.coefficient"]) == {"friction.coefficient": 0.285}
