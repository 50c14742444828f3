"""Units of the drive cycles, which run on the service brake (issue 28): every path that
draws a unit for them draws it from the service brake's table (fleet/scatter.py
``SERVICE_SCATTER``), end to end: the scenario, ``brake-sim unit``, ``brake-sim simulate``
of a file naming a unit, a sweep's runs, and ``bench units``' linear model."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from brake_sim_ros.campaigns import parse_campaign
from brake_sim_ros.datasets.parquet import METADATA_KEY
from brake_sim_ros.datasets.sweep import sweep
from brake_sim_ros.fleet import scatter
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.studies import units as fleet_study
from tests import cli_process
from tests.study_cycles import on_study_brake

ROOT = Path(__file__).resolve().parents[2]
CYCLES = ("urban", "downhill", "downhill_fade", "downhill_wear", "rig")
SERVICE_KEYS = {s.key for s in scatter.SERVICE_SCATTER}
STUDY_KEYS = {s.key for s in scatter.SCATTER}
COUPLING = "driveline.coupling_stiffness_n_m_per_rad"  # the study's only: the tyre replaces it
SPRING = "service.return_spring_preload_n"  # the service brake's only


def _brake_keys(values) -> set[str]:
    """The brake parameters' keys of a unit's values (the sensors' are the same on both)."""
    return {v["key"] if isinstance(v, dict) else v.key for v in values} & (
        SERVICE_KEYS | STUDY_KEYS
    )


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return cli_process.run(
        [sys.executable, "-m", "brake_sim_ros.cli", *args],
        capture_output=True, text=True, cwd=ROOT, env=env, timeout=600,
    )  # fmt: skip


@pytest.mark.parametrize("name", CYCLES)
def test_a_unit_of_a_built_in_cycle_is_drawn_from_the_service_table(name):
    scenario = load_scenario(name).with_unit("VIN-0042", fleet_seed=7)
    assert scenario.setup.params.brake == "service"
    assert _brake_keys(scenario.unit_values()) == SERVICE_KEYS
    drawn = scatter.unit_parameters(scenario.drawing_params, "VIN-0042", 7)
    assert scenario.setup.params == drawn
    spring = scenario.setup.params.service.return_spring_preload_n
    assert spring == 60.0 * (1.0 + scatter.deviations("VIN-0042", 7, "service")[SPRING])
    # the same cycle on the study brake draws the study table (not the service one)
    if name != "rig":
        study = on_study_brake(name).with_unit("VIN-0042", fleet_seed=7)
        assert _brake_keys(study.unit_values()) == STUDY_KEYS


@pytest.mark.slow
def test_the_unit_command_and_simulate_show_a_cycles_service_unit(tmp_path):
    shown = _cli("unit", "VIN-0042", "--fleet-seed", "7", "--scenario", "urban")
    assert shown.returncode == 0, shown.stderr
    assert SPRING in shown.stdout and COUPLING not in shown.stdout
    scenario = load_scenario("urban").with_unit("VIN-0042", fleet_seed=7)
    line = next(x for x in shown.stdout.splitlines() if SPRING in x)
    assert f"{scenario.setup.params.service.return_spring_preload_n:.6g}" in line
    # a file naming a unit of the urban cycle: simulate writes the service unit's values
    source = tmp_path / "unit.toml"
    urban = (ROOT / "brake_sim_ros" / "scenarios" / "builtin" / "urban.toml").read_text()
    source.write_text(
        urban.replace("seed = 0\n", 'seed = 0\nunit_id = "VIN-0042"\nfleet_seed = 7\n')
    )
    out = tmp_path / "run.parquet"
    ran = _cli("simulate", str(source), "--duration", "0.05", "--out", str(out), "--quiet")
    assert ran.returncode == 0, ran.stderr
    meta = json.loads(pq.read_schema(out).metadata[METADATA_KEY])
    assert meta["unit_parameters"] == [v.as_dict() for v in scenario.unit_values()]
    assert _brake_keys(meta["unit_parameters"]) == SERVICE_KEYS


SWEPT = """
name = "cycle_units"
base = "urban"
seed = 3
units = 3
[outputs]
duration_s = 0.05
"""


@pytest.mark.slow
def test_a_sweep_of_a_cycle_runs_service_units(tmp_path):
    campaign = parse_campaign(SWEPT, "cycle_units.toml")
    summary, _ = sweep(campaign, tmp_path / "out", workers=1, quiet=True)
    assert (summary.runs, summary.failed) == (3, 0)
    files = sorted(p for p in (tmp_path / "out").rglob("*.parquet") if p.name != "manifest.parquet")
    assert len(files) == 3
    for path in files:
        meta = json.loads(pq.read_schema(path).metadata[METADATA_KEY])
        unit = load_scenario("urban").with_unit(meta["unit_id"], fleet_seed=3)  # the campaign seed
        assert _brake_keys(meta["unit_parameters"]) == SERVICE_KEYS
        assert meta["unit_parameters"] == [v.as_dict() for v in unit.unit_values()]


def test_the_fleet_bench_moves_the_service_tables_parameters():
    """``bench units``' linear model moves each parameter of the scenario's own brake's
    table (the study table's coupling is refused by a service brake)."""
    scenario = load_scenario("urban")
    _, parts = fleet_study.linear_spread(scenario, duration_s=0.02)
    assert set(parts) == SERVICE_KEYS
