"""A real node as a brake unit: the ``unit_id`` parameter draws the unit from the
scenario, its ground truth and its recording's metadata say which unit and what it has,
and a ~/reset with a new seed draws the unit again."""

from __future__ import annotations

import json

import pytest

pytestmark = [
    pytest.mark.ros,
    pytest.mark.filterwarnings("ignore:module 'sre_(parse|constants)' is deprecated"),
]

rclpy = pytest.importorskip("rclpy", reason="rclpy not installed (run scripts/setup.sh)")

from mcap.reader import make_reader  # noqa: E402

from brake_sim_ros.recording import metadata  # noqa: E402
from brake_sim_ros.ros.harness import NodeProcess, SimClient, domain_id_for  # noqa: E402
from brake_sim_ros.scenarios import load_scenario  # noqa: E402

UNIT = "VIN-0042"


def test_the_node_runs_the_unit_records_it_and_redraws_it_with_a_new_seed(tmp_path):
    domain = domain_id_for(74)
    bag = tmp_path / "unit.mcap"
    node = NodeProcess.start(
        ["--duration", "3600", "--record", str(bag), "--ros-args", "-p", f"unit_id:={UNIT}"],
        domain_id=domain,
        log_path=tmp_path / "node.log",
    )
    sim = SimClient(domain)
    first = load_scenario("symmetric").with_unit(UNIT)
    second = first.with_unit(seed=9)
    try:
        sim.wait_for_node(30.0)
        truth = sim.rx.defects[-1]
        assert (truth.unit_id, truth.seed) == (UNIT, 0)
        mu = sim.get_parameters(["friction.coefficient"])["friction.coefficient"]
        assert mu == first.setup.params.friction.coefficient != 0.285
        assert not sim.set_parameter("unit_id", "other").successful  # fixed at start
        n = len(sim.rx.defects)
        assert sim.reset(seed=9, timeout_s=20.0).success
        sim.wait_for(lambda: len(sim.rx.defects) > n, 5.0, "ground truth after the reset")
        assert (sim.rx.defects[-1].unit_id, sim.rx.defects[-1].seed) == (UNIT, 9)
        mu = sim.get_parameters(["friction.coefficient"])["friction.coefficient"]
        assert (
            mu
            == second.setup.params.friction.coefficient
            != first.setup.params.friction.coefficient
        )
    finally:
        sim.close()
        assert node.stop() == 0, node.output()
    with open(bag, "rb") as f:
        records = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
    unit = records[metadata.UNIT]
    assert (unit["unit_id"], unit["seed"]) == (UNIT, "0")
    assert json.loads(unit["unit_parameters"]) == [v.as_dict() for v in first.unit_values()]
    params, _ = metadata.model_from_record(records[metadata.MODEL])
    assert params == first.setup.params
