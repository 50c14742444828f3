"""brake-sim sweep: the dataset it writes, determinism, resumption after a kill, failed
runs, refusals, a real Dask LocalCluster, and dataset info's leakage and damage checks.

Every sweep here runs real worker processes (or a real Dask cluster) on a small campaign.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.dataset as pads
import pyarrow.parquet as pq
import pytest

from brake_sim_ros import cli
from brake_sim_ros.campaigns import load_campaign
from brake_sim_ros.datasets import open as open_dataset
from brake_sim_ros.datasets.parquet import METADATA_KEY
from brake_sim_ros.datasets.reader import info_text
from brake_sim_ros.datasets.sweep import sweep
from brake_sim_ros.datasets.sweep_output import DONE_DIR, LOCK_NAME, MANIFEST_NAME
from brake_sim_ros.scenarios import parse_scenario
from tests import cli_process

ROOT = Path(__file__).resolve().parents[2]
# 3 units x (healthy + 2 sides x 2 severities) x 2 forces = 30 short runs
CAMPAIGN = """
name = "small"
base = "symmetric"
seed = 11
units = 3
[outputs]
duration_s = 0.5
sample_rate_hz = 2560.0
[[axes]]
defects = ["pivot_radius_change"]
severities = [0.5, 1.0]
[[axes]]
name = "peak_force_n"
key = "actuation.peak_force_n"
values = [1200.0, 1300.0]
"""


def _cli(*args: str, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return cli_process.run(
        [sys.executable, "-m", "brake_sim_ros.cli", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=timeout,
    )


def _files(root: Path) -> dict[str, bytes]:
    """Every file of a sweep's directory but its run records, by relative path."""
    return {
        str(p.relative_to(root)): p.read_bytes()
        for p in sorted(root.rglob("*"))
        if p.is_file() and DONE_DIR not in p.parts
    }


def _same_dataset(a: Path, b: Path) -> None:
    """Byte for byte, but the manifest's measured CPU cost column."""
    fa, fb = _files(a), _files(b)
    assert fa.keys() == fb.keys()
    for name in fa:
        if name != MANIFEST_NAME:
            assert fa[name] == fb[name], name
    ma, mb = pq.read_table(a / MANIFEST_NAME), pq.read_table(b / MANIFEST_NAME)
    assert ma.drop_columns(["cost_cpu_s"]).equals(mb.drop_columns(["cost_cpu_s"]))


@pytest.fixture(scope="module")
def campaign_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("campaign") / "small.toml"
    path.write_text(CAMPAIGN)
    return path


@pytest.fixture(scope="module")
def reference(tmp_path_factory, campaign_file) -> Path:
    """The campaign swept without interruption on a local pool of two workers."""
    out = tmp_path_factory.mktemp("sweeps") / "reference"
    summary, _ = sweep(load_campaign(campaign_file), out, workers=2, quiet=True)
    assert (summary.runs, summary.done, summary.failed) == (30, 30, 0)
    return out


@pytest.mark.slow
def test_the_dataset_holds_every_run_labelled_with_its_scenario(reference, campaign_file):
    runs = {r.run_id: r for r in load_campaign(campaign_file).runs()}
    manifest = pq.read_table(reference / MANIFEST_NAME).to_pylist()
    assert [m["run_id"] for m in manifest] == sorted(runs)
    samples = pads.dataset(reference / "samples", format="parquet", partitioning="hive")
    counts = samples.to_table(columns=["run"]).column("run").value_counts().to_pylist()
    assert {c["values"]: c["counts"] for c in counts} == {m["run_id"]: m["rows"] for m in manifest}
    for m in manifest[:6]:
        spec = runs[m["run_id"]]
        assert (m["unit_id"], m["split"], m["seed"], m["status"]) == (
            spec.unit_id,
            spec.split,
            spec.seed,
            "ok",
        )
        assert m["rows"] == round(0.5 * 2560)
        table = pq.read_table(reference / m["file"])
        meta = json.loads(table.schema.metadata[METADATA_KEY])
        assert (meta["run_id"], meta["unit_id"], meta["split"]) == (
            m["run_id"],
            m["unit_id"],
            m["split"],
        )
        scenario = parse_scenario(meta["scenario_toml"])
        assert scenario.seed == m["seed"] and scenario.unit_id == m["unit_id"]
        assert scenario.setup.actuation.left.forces_n[-1] == m["peak_force_n"]
        for label, severity in spec.labels.items():  # per-sample labels = the manifest's
            column = table[label].to_numpy()
            assert np.all(column == severity) and m[label] == severity
        side = m["defect_location"]
        if side:
            column = f"defect:pivot_radius_change:{side} [%]"
            assert table[column][0].as_py() == m["defect_severity"] != 0.0
        # the fraction of the service limit: the campaign's severities axis value
        assert m["defect_severity_fraction"] in ((0.5, 1.0) if side else (0.0,))
        assert any(c.startswith("measured:") and "[" in c for c in table.column_names)
    # the lock holds the campaign resolved, and says which version wrote it
    lock = json.loads((reference / LOCK_NAME).read_text())
    assert tomllib.loads(lock["campaign_toml"])["name"] == "small"
    assert [r["run_id"] for r in lock["runs"]] == sorted(runs)


def test_no_unit_in_two_splits_on_disk(reference):
    dataset = open_dataset(reference)
    units = {
        s: {r["unit_id"] for r in dataset.manifest.to_pylist() if r["split"] == s}
        for s in ("train", "validation", "test")
    }
    assert all(units.values())
    assert not (
        units["train"] & units["validation"]
        or units["train"] & units["test"]
        or units["validation"] & units["test"]
    )
    test_runs = set(dataset.runs("test"))
    in_split = dataset.split("test").to_table(columns=["run"]).column("run")
    assert set(pc.unique(in_split).to_pylist()) == test_runs


def test_windows_carry_their_labels(reference):
    dataset = open_dataset(reference)
    first = next(dataset.windows(256, split="train", columns=["time_s", "drum_speed_rad_s"]))
    table = pq.read_table(reference / "samples" / f"run={first.run_id}")
    assert first.data.shape == (table.num_rows // 256, 256, 2)
    np.testing.assert_array_equal(first.data[1, :, 0], table["time_s"].to_numpy()[256:512])
    label = first.label_columns.index("defect:pivot_radius_change:left [%]")
    np.testing.assert_array_equal(
        first.labels[:, label], table["defect:pivot_radius_change:left [%]"].to_numpy()[255::256]
    )


def _records(out: Path) -> list[Path]:
    """The runs a sweep has recorded as done (not a record's temporary file: .<name>...)."""
    folder = out / DONE_DIR
    return [p for p in folder.glob("run-*.json")] if folder.is_dir() else []


def _sweep_until_a_run_is_done(campaign_file: Path, out: Path) -> subprocess.Popen[str]:
    """``brake-sim sweep`` on one worker in its own session, returned once its first run
    is recorded (and before its last: the caller checks)."""
    process = subprocess.Popen(
        [sys.executable, "-m", "brake_sim_ros.cli", "sweep", str(campaign_file), "--out",
         str(out), "--workers", "1", "--quiet"],
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )  # fmt: skip
    deadline = time.monotonic() + 120
    while not _records(out):
        if process.poll() is not None or time.monotonic() > deadline:
            os.killpg(process.pid, signal.SIGKILL)
            raise AssertionError("the sweep ended, or ran 2 min, before a run was recorded")
        time.sleep(0.005)
    return process


@pytest.mark.slow
def test_a_sweep_killed_midway_resumes_to_the_same_bytes(tmp_path, reference, campaign_file):
    out = tmp_path / "killed"
    process = _sweep_until_a_run_is_done(campaign_file, out)
    os.killpg(process.pid, signal.SIGKILL)
    process.communicate(timeout=30)
    done = len(_records(out))
    assert not (out / MANIFEST_NAME).exists() and 1 <= done < 30  # killed midway
    result = _cli("sweep", str(campaign_file), "--out", str(out), "--workers", "2", "--quiet")
    assert result.returncode == 0, result.stderr
    assert f"({done} already done)" in result.stdout  # the runs recorded before the kill
    assert not [p for p in out.rglob("*") if ".partial" in p.name]
    _same_dataset(reference, out)


def test_a_local_dask_cluster_gives_the_same_bytes(tmp_path, reference, campaign_file):
    from distributed import LocalCluster

    out = tmp_path / "dask"
    with LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
    ) as cluster:
        summary, _ = sweep(
            load_campaign(campaign_file), out, scheduler=cluster.scheduler_address, quiet=True
        )
    assert (summary.done, summary.failed) == (30, 0)
    _same_dataset(reference, out)


@pytest.mark.slow
def test_a_failed_run_is_recorded_and_the_others_go_on(tmp_path, campaign_file):
    campaign = load_campaign(campaign_file)
    out = tmp_path / "failing"
    out.mkdir()
    (out / LOCK_NAME).write_text(campaign.lock_text(campaign.runs()))
    (out / "samples").mkdir()
    (out / "samples" / "run=run-00001").write_text("in the way")  # a file where a directory goes
    result = _cli("sweep", str(campaign_file), "--out", str(out), "--workers", "2", "--quiet")
    assert result.returncode == 1
    assert result.stderr.count("\n") == 1 and "run-00001" in result.stderr
    rows = pq.read_table(out / MANIFEST_NAME).to_pylist()
    failed = [r for r in rows if r["status"] != "ok"]
    assert [r["run_id"] for r in failed] == ["run-00001"]
    assert failed[0]["error"] and failed[0]["file"] is None and failed[0]["sha256"] is None
    assert all((out / r["file"]).is_file() for r in rows if r["status"] == "ok")
    assert len(rows) == 30


def _main(capsys, *args: str) -> tuple[int, str]:
    code = cli.main(list(args))
    return code, capsys.readouterr().err


def test_output_directories_are_refused_in_one_line(tmp_path, capsys, campaign_file, reference):
    target = tmp_path / "real"
    target.mkdir()
    link = tmp_path / "link"
    link.symlink_to(target)
    code, err = _main(capsys, "sweep", str(campaign_file), "--out", str(link))
    assert code == 2 and "symbolic link" in err and err.count("\n") == 1
    full = tmp_path / "full"
    full.mkdir()
    (full / "x").write_text("")
    code, err = _main(capsys, "sweep", str(campaign_file), "--out", str(full))
    assert code == 2 and "not empty" in err and err.count("\n") == 1
    other = tmp_path / "other.toml"
    other.write_text(CAMPAIGN.replace("seed = 11", "seed = 12"))
    before = _files(reference)
    code, err = _main(capsys, "sweep", str(other), "--out", str(reference))
    assert code == 2 and "another campaign" in err and err.count("\n") == 1
    assert _files(reference) == before


def test_a_new_output_directory_is_made_with_its_parents(tmp_path):
    from brake_sim_ros.datasets.sweep_output import SweepError, prepare_output

    out = tmp_path / "data" / "sweeps" / "demo"
    prepare_output(out, "lock")
    assert (out / LOCK_NAME).read_text() == "lock"
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(SweepError, match="file is not a directory"):
        prepare_output(blocker / "demo", "lock")
    assert blocker.read_text() == ""


@pytest.mark.parametrize(
    "text",
    [
        "name = 'x'\nbase = 'symmetric'\nunits = 3\nbogus = 1\n",
        "name = 'x'\nbase = 'symmetric'\nunits = 3\n[[axes]]\nkey = 'actuation.peak_force_n'\n"
        "values = [-5.0]\n",
        "\x00\x01 not toml",
    ],
)
def test_a_bad_campaign_is_one_line_and_leaves_no_directory(tmp_path, text):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    out = tmp_path / "out"
    result = _cli("sweep", str(path), "--out", str(out))
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.stderr
    assert str(path) in result.stderr
    assert not out.exists()


def test_dataset_info_summarises_and_finds_leakage_and_damage(tmp_path, capsys, reference):
    text = info_text(open_dataset(reference))
    assert "leak-free" in text and "train:" in text and "healthy" in text
    doctored = tmp_path / "leaky"
    shutil.copytree(reference, doctored)
    manifest = pq.read_table(doctored / MANIFEST_NAME)
    splits = manifest["split"].to_pylist()
    first_test = splits.index("test")
    splits[first_test] = "train"  # one run of a test unit moved to train
    manifest = manifest.set_column(
        manifest.schema.get_field_index("split"), "split", pa.array(splits)
    )
    pq.write_table(manifest, doctored / MANIFEST_NAME)
    code, err = _main(capsys, "dataset", "info", str(doctored))
    assert code == 2 and "leakage" in err and "is in the splits" in err and err.count("\n") == 1
    damaged = tmp_path / "damaged"
    shutil.copytree(reference, damaged)
    part = next((damaged / "samples").rglob("part-0.parquet"))
    data = bytearray(part.read_bytes())
    data[len(data) // 2] ^= 0xFF
    part.write_bytes(bytes(data))
    code, err = _main(capsys, "dataset", "info", str(damaged))
    assert code == 2 and "damaged" in err and err.count("\n") == 1
    code, err = _main(capsys, "dataset", "info", str(tmp_path / "nowhere"))
    assert code == 2 and err.count("\n") == 1


def _children(pid: int) -> list[int]:
    out = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                out.append(int(entry.name))
    return out


@pytest.mark.slow
def test_a_worker_killed_midway_is_one_line_and_the_sweep_resumes(
    tmp_path, reference, campaign_file
):
    out = tmp_path / "worker-killed"
    process = _sweep_until_a_run_is_done(campaign_file, out)
    try:
        # the pool's workers are forked by its fork server, a child of the sweep
        server = [
            p
            for p in _children(process.pid)
            if b"forkserver" in Path(f"/proc/{p}/cmdline").read_bytes()
        ]
        assert len(server) == 1
        workers = _children(server[0])
        assert len(workers) == 1
        os.kill(workers[0], signal.SIGKILL)  # the pool's worker, as an out-of-memory kill would
        _, err = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    assert process.returncode == 2
    assert err.count("\n") == 1 and "worker process died" in err and "Traceback" not in err
    assert not (out / MANIFEST_NAME).exists()
    result = _cli("sweep", str(campaign_file), "--out", str(out), "--workers", "2", "--quiet")
    assert result.returncode == 0, result.stderr
    _same_dataset(reference, out)
