"""A real node as a brake unit: the ``unit_id`` parameter draws the unit from the
scenario, its ground truth and its recording's metadata say which unit and what it has,
and a ~/reset with a new seed keeps the unit (new noise, the same brake)."""

from __future__ import annotations

import json

from mcap.reader import make_reader

from brake_sim_ros.recording import metadata
from brake_sim_ros.ros.harness import domain_id_for
from brake_sim_ros.scenarios import load_scenario

UNIT = "VIN-0042"


def test_the_node_runs_the_unit_records_it_and_redraws_it_with_a_new_seed(
    tmp_path, node_and_client
):
    bag = tmp_path / "unit.mcap"
    args = ["--duration", "3600", "--record", str(bag), "--ros-args", "-p", f"unit_id:={UNIT}",
            "-p", "real_time_factor:=0.2"]  # a busy CPU: pace not tested  # fmt: skip
    first = load_scenario("symmetric").with_unit(UNIT)
    with node_and_client(args, domain_id_for(74), wait_s=30.0) as (_, sim):
        truth = sim.rx.defects[-1]
        assert (truth.unit_id, truth.seed) == (UNIT, 0)
        mu = sim.get_parameters(["friction.coefficient"])["friction.coefficient"]
        assert mu == first.setup.params.friction.coefficient != 0.285
        assert not sim.set_parameter("unit_id", "other").successful  # fixed at start
        n = len(sim.rx.defects)
        assert sim.reset(seed=9, timeout_s=20.0).success
        sim.wait_for(lambda: len(sim.rx.defects) > n, 5.0, "ground truth after the reset")
        assert (sim.rx.defects[-1].unit_id, sim.rx.defects[-1].seed) == (UNIT, 9)
        # a new seed is new noise on the same brake: the unit is not drawn again
        mu = sim.get_parameters(["friction.coefficient"])["friction.coefficient"]
        assert mu == first.setup.params.friction.coefficient
    with open(bag, "rb") as f:
        records = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
    unit = records[metadata.UNIT]
    assert (unit["unit_id"], unit["seed"]) == (UNIT, "0")
    assert json.loads(unit["unit_parameters"]) == [v.as_dict() for v in first.unit_values()]
    params, _ = metadata.model_from_record(records[metadata.MODEL])
    assert params == first.setup.params
