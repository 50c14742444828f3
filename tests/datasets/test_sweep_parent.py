"""The sweeping process's own work per run (what limits a sweep of short runs), the
memory of a unit's draws that planning uses, and the campaigns the benchmarks sweep.

The sweeps here run real worker processes on a small campaign of short runs.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import pytest

from brake_sim_ros.campaigns import load_campaign, parse_campaign
from brake_sim_ros.campaigns.axes import DefectChoice, condition_points
from brake_sim_ros.campaigns.campaign import plan_runs
from brake_sim_ros.datasets.parquet import measured_column
from brake_sim_ros.datasets.sweep import sweep
from brake_sim_ros.datasets.sweep_output import DONE_DIR, MANIFEST_NAME
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.fleet.scatter import unit_parameters, unit_sensors
from brake_sim_ros.model.catalogue import brake_kinds
from brake_sim_ros.scenarios import load_scenario, parse_scenario
from brake_sim_ros.scenarios.unit_draws import unit_brake, unit_sensor_set
from brake_sim_ros.sensing.sensors import default_sensor_set
from brake_sim_ros.studies import fleet_bench, sweep_bench

# 3 units x (2 sides x 1 severity + healthy) = 9 short runs
CAMPAIGN = """
name = "parent"
base = "symmetric"
seed = 5
units = 3
[outputs]
duration_s = 0.2
sample_rate_hz = 2560.0
[[axes]]
defects = ["pivot_radius_change"]
severities = [1.0]
"""


def _files(root: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(root)): p.read_bytes()
        for p in sorted(root.rglob("*"))
        if p.is_file() and DONE_DIR not in p.parts and p.name != MANIFEST_NAME
    }


def test_the_parent_syncs_no_file_per_run_and_a_torn_record_reruns_its_run(tmp_path, monkeypatch):
    campaign = parse_campaign(CAMPAIGN, "test")
    synced = []
    real_fsync = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: (synced.append(fd), real_fsync(fd))[1])
    out = tmp_path / "sweep"
    summary, _ = sweep(campaign, out, workers=2, quiet=True)
    assert (summary.runs, summary.done, summary.failed) == (9, 9, 0)
    # the lock and the manifest: each its file and its directory; none per run (the workers
    # sync the runs' files, in their own processes)
    assert len(synced) == 4
    assert 0.0 < summary.parent_s < summary.wall_s + 60.0 and summary.parent_cpu_s > 0.0
    records = sorted((out / DONE_DIR).glob("*.json"))
    assert len(records) == 9
    records[0].write_text('{"run_id": "run-0')  # torn by a crash: not trusted
    (out / MANIFEST_NAME).unlink()
    before = _files(out)
    again, _ = sweep(campaign, out, workers=1, quiet=True)
    assert (again.resumed, again.done) == (8, 9)
    assert _files(out) == before  # the run done again gave the same bytes


def test_a_units_draws_are_remembered_and_the_same_as_drawn_afresh():
    scenario = load_scenario("symmetric")
    params, sensors = scenario.drawing_params, scenario.drawing_sensors
    brake = unit_brake(params, "unit-0007", 3)
    assert unit_brake(params, "unit-0007", 3) is brake  # the memory
    assert repr(brake) == repr(unit_parameters(params, "unit-0007", 3))
    assert repr(unit_brake(params, "unit-0008", 3)) != repr(brake)
    assert repr(unit_brake(params, "unit-0007", 4)) != repr(brake)
    drawn = unit_sensor_set(sensors, "unit-0007", 3)
    assert unit_sensor_set(sensors, "unit-0007", 3) is drawn
    assert repr(drawn) == repr(unit_sensors(sensors, "unit-0007", 3))


def _kinds(campaign):
    """Every kind the campaign's brake carries (the line's only the service brake's)."""
    return brake_kinds(campaign.brake == "service")


# the one kind the fleet leaves out: from half its service limit the service brake's
# lining starts inside the drum (fleet10k.toml), which the loader refuses
LEFT_OUT = "pivot_radius_change"


def test_the_fleet_campaign_is_every_kind_at_three_severities_and_healthy_on_20_units():
    campaign = load_campaign(fleet_bench.CAMPAIGN_FILE)
    assert campaign.brake == "service"
    assert len(campaign.unit_ids) == 20
    assert (campaign.outputs.duration_s, campaign.outputs.sample_rate_hz) == (1.2, 25600.0)
    points = condition_points(
        campaign.axes, campaign.draw_method, campaign.draw_count, campaign.seed
    )
    defects = {v for p in points for v in p.values() if isinstance(v, DefectChoice)}
    for kind in _kinds(campaign):
        for location in kind.locations:
            severities = {
                d.severity for d in defects if (d.kind, d.location) == (kind.name, location)
            }
            assert len(severities) == (0 if kind.name == LEFT_OUT else 3), (kind.name, location)
    assert {"air_in_line", "line_leak", "adjuster_seized"} <= {d.kind for d in defects}
    assert any(d.kind == "healthy" for d in defects)
    assert fleet_bench.run_count(campaign) == len(points) * 20 >= 10_000
    measured = {c for c in campaign.outputs.columns if c.startswith("measured:")}
    channels = default_sensor_set().channels
    assert {measured_column(c.name, c.unit) for c in channels} <= measured
    assert all(c.startswith(("measured:", "fault:")) for c in campaign.outputs.columns)


def test_the_kind_the_fleet_leaves_out_is_refused_at_half_its_limit():
    (kind,) = [k for k in brake_kinds(True) if k.name == LEFT_OUT]
    text = (
        'name = "pin"\nbrake = "service"\n[defects.left]\n'
        f"pivot_radius_change_pct = {0.5 * kind.service_limit}\n"
    )
    with pytest.raises(BrakeSimError, match="inside the drum"):
        parse_scenario(text)


def test_the_fleet_slice_keeps_the_runs_settings():
    campaign = load_campaign(fleet_bench.CAMPAIGN_FILE)
    part = fleet_bench.sliced(campaign, 8, 1)
    assert (part.outputs, part.axes, part.seed) == (campaign.outputs, campaign.axes, campaign.seed)
    assert part.unit_ids == campaign.unit_ids[:8]
    # one force of eight, on 8 units of 20
    assert fleet_bench.run_count(part) == fleet_bench.run_count(campaign) // (8 * 20) * 8
    with pytest.raises(BrakeSimError, match="--units 4: allowed 5 to 20"):
        fleet_bench.sliced(campaign, 4, 1)


def test_the_fleet_benchmark_sweeps_and_scores_a_campaign_end_to_end(tmp_path):
    # the fleet's own outputs (measured channels, 25.6 kHz) on 5 units x (one defect at
    # its limit and healthy), short runs: the whole path the full campaign takes
    fleet = load_campaign(fleet_bench.CAMPAIGN_FILE)
    small = parse_campaign(
        'name = "fleet_small"\nbase = "symmetric"\nseed = 3\nunits = 5\n[outputs]\n'
        "duration_s = 0.6\nsample_rate_hz = 25600.0\n"
        '[[axes]]\ndefects = ["friction_change"]\nseverities = [1.0]\nhealthy = true\n',
        "test",
    )
    small = dataclasses.replace(small, outputs=dataclasses.replace(fleet.outputs, duration_s=0.6))
    report = fleet_bench.run(small, fleet_bench.run_count(small), tmp_path / "out", 2)
    lines = report.splitlines()
    sweep_line = next(line for line in lines if line.startswith("  sweep: "))
    runs = fleet_bench.run_count(small)
    assert sweep_line.startswith(f"  sweep: {runs} runs (0 failed)")
    score_line = next(line for line in lines if line.startswith("  score: "))
    assert "impact fitted on train (" in score_line and "scored on test: " in score_line
    assert not any("EXTRAPOLATED to all" in line for line in lines)


def test_the_sweep_benchmarks_short_campaign_is_short_runs_of_every_defect():
    campaign = sweep_bench.bench_campaign("short")
    runs = campaign.runs()
    assert len(runs) == 3 * (2 * sum(len(k.locations) for k in _kinds(campaign)) + 1)
    assert {r.duration_s for r in runs} == {0.5}


def test_the_nominal_unit_is_the_scenarios_own_brake_and_sensors():
    scenario = load_scenario("symmetric")
    params, sensors = scenario.drawing_params, scenario.drawing_sensors
    twin = dataclasses.replace(params)  # equal, another object: not served from the memory
    unit_brake(params, "nominal", 1)
    assert unit_brake(twin, "nominal", 1) is twin
    assert unit_sensor_set(sensors, "nominal", 1) is sensors


def test_a_run_that_keeps_a_few_columns_writes_the_full_tables_selection(tmp_path):
    """A campaign's ``outputs.columns``: the run builds only the samples' columns it keeps
    (datasets/parquet.py ``sample_columns``) and its file has the bytes of the full
    table's selection written as the sweep writes; a column it does not write is refused
    with the samples' columns among those allowed."""
    import pyarrow.parquet as pq

    from brake_sim_ros.datasets.parquet import run_table
    from brake_sim_ros.datasets.sweep import run_task
    from brake_sim_ros.stream.run import run_scenario

    kept = CAMPAIGN.replace(
        "sample_rate_hz = 2560.0\n",
        'sample_rate_hz = 2560.0\ncolumns = ["left_pivot_fx_n", "measured:line_pressure [bar]"]\n',
    )
    spec = plan_runs(parse_campaign(kept, "test"))[0]
    outcome = run_task(spec, str(tmp_path))
    assert outcome.status == "ok", outcome.error
    written = pq.read_table(tmp_path / outcome.file)
    scenario = parse_scenario(spec.scenario_text, spec.run_id)
    extra = {"run_id": spec.run_id, "split": spec.split}
    full = run_table(scenario, run_scenario(scenario), scenario.duration_s, extra)
    assert "right_pivot_fx_n" in full.column_names
    assert "right_pivot_fx_n" not in written.column_names
    assert "left_pivot_fx_n" in written.column_names
    again = tmp_path / "full_selected.parquet"
    pq.write_table(full.select(written.column_names), again, compression="zstd")
    assert again.read_bytes() == (tmp_path / outcome.file).read_bytes()
    bad = dataclasses.replace(spec, keep=(*spec.keep, "no_such_column"))
    refused = run_task(bad, str(tmp_path / "bad"))
    assert refused.status == "failed"
    assert "'no_such_column' is not a column of this run" in refused.error
    assert "right_pivot_fx_n" in refused.error
