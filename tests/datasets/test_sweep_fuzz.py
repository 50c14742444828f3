"""``brake-sim sweep`` under interruption and concurrency: sweeps killed by every signal
leave no process behind, two sweeps at once on one real Dask cluster (a scheduler and
worker processes) each write their own right dataset, and two sweeps into one directory
are refused in one line. Every case runs real processes.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from brake_sim_ros import cli
from brake_sim_ros.datasets import open as open_dataset
from brake_sim_ros.datasets.reader import check
from brake_sim_ros.datasets.sweep_output import DONE_DIR, MANIFEST_NAME, sha256_file
from tests import cli_process

ROOT = Path(__file__).resolve().parents[2]


def _campaign(path: Path, name: str, units: int, force: float, duration_s: float) -> Path:
    path.write_text(
        f'name = "{name}"\nbase = "symmetric"\nseed = 5\nunits = {units}\n'
        f"[outputs]\nduration_s = {duration_s}\nsample_rate_hz = 2560.0\n"
        f'[[axes]]\nname = "peak_force_n"\nkey = "actuation.peak_force_n"\nvalues = [{force}]\n'
    )
    return path


def _start(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "brake_sim_ros.cli", "sweep", *args, "--quiet"],
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )


def _descendants(pid: int) -> set[int]:
    """Every living process below ``pid`` (zombies excluded)."""
    parents: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if fields[0] != "Z":
                parents.setdefault(int(fields[1]), []).append(int(entry.name))
    found, todo = set(), [pid]
    while todo:
        for child in parents.get(todo.pop(), []):
            found.add(child)
            todo.append(child)
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _records(out: Path) -> int:
    folder = out / DONE_DIR
    return len(list(folder.glob("run-*.json"))) if folder.is_dir() else 0


def _one_line_error(err: str) -> None:
    assert err.count("\n") == 1 and err.startswith("brake-sim: error: "), err
    assert "Traceback" not in err


@pytest.mark.parametrize("signum", [signal.SIGKILL, signal.SIGTERM])
def test_a_killed_sweep_leaves_no_process_behind(tmp_path, signum):
    campaign = _campaign(tmp_path / "long.toml", "long", 40, 1200.0, 0.5)
    out = tmp_path / "out"
    process = _start(str(campaign), "--out", str(out), "--workers", "2")
    deadline = time.monotonic() + 180
    while _records(out) < 1:
        assert process.poll() is None and time.monotonic() < deadline, "no run recorded"
        time.sleep(0.01)
    below = _descendants(process.pid)
    try:
        assert len(below) >= 3  # the fork server, its workers, the resource tracker
        os.kill(process.pid, signum)  # the sweep alone, not its process group
        # the caller's pipes reach their end: no child holds them open
        process.communicate(timeout=30)
        deadline = time.monotonic() + 20
        while any(_alive(p) for p in below) and time.monotonic() < deadline:
            time.sleep(0.05)
        left = [p for p in below if _alive(p)]
    finally:
        for pid in below:  # whatever the outcome, nothing of this test runs on
            if _alive(pid):
                os.kill(pid, signal.SIGKILL)
    assert left == []
    assert not (out / MANIFEST_NAME).exists()


def _right_dataset(out: Path, runs: int, units: int) -> None:
    """Every run ok, every file the manifest's SHA-256, the campaign's own units."""
    dataset = open_dataset(out)
    check(dataset)
    rows = pq.read_table(out / MANIFEST_NAME).to_pylist()
    assert len(rows) == runs and all(r["status"] == "ok" for r in rows)
    assert len({r["unit_id"] for r in rows}) == units
    for row in rows:
        assert sha256_file(out / row["file"]) == row["sha256"]
        assert pq.read_metadata(out / row["file"]).num_rows == row["rows"]


def test_two_sweeps_at_once_on_one_dask_cluster_each_write_their_own(tmp_path):
    from distributed import LocalCluster

    first = _campaign(tmp_path / "first.toml", "first", 4, 1200.0, 0.2)
    second = _campaign(tmp_path / "second.toml", "second", 6, 1300.0, 0.3)
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        address = cluster.scheduler_address
        a = _start(str(first), "--out", str(tmp_path / "a"), "--scheduler", address)
        b = _start(str(second), "--out", str(tmp_path / "b"), "--scheduler", address)
        (_, err_a), (_, err_b) = a.communicate(timeout=300), b.communicate(timeout=300)
    assert (a.returncode, b.returncode) == (0, 0), err_a + err_b
    _right_dataset(tmp_path / "a", 4, 4)
    _right_dataset(tmp_path / "b", 6, 6)


def test_two_sweeps_into_one_directory_the_second_is_refused(tmp_path, capsys):
    # runs of 5 s (about a second of CPU each): the first sweep still holds the directory
    # when the second asks for it, however slowly the second starts on a loaded machine
    # (with runs of 0.5 s the first could finish all 40 and let go of it before)
    campaign = _campaign(tmp_path / "c.toml", "c", 40, 1200.0, 5.0)
    out = tmp_path / "out"
    first = _start(str(campaign), "--out", str(out), "--workers", "1")
    try:
        deadline = time.monotonic() + 180
        while _records(out) < 1:
            assert first.poll() is None and time.monotonic() < deadline
            time.sleep(0.01)
        before = {p.name for p in (out / DONE_DIR).glob("run-*.json")}
        code = cli.main(["sweep", str(campaign), "--out", str(out), "--quiet"])
        err = capsys.readouterr().err
        assert first.poll() is None  # refused while the first ran
    finally:
        os.killpg(first.pid, signal.SIGKILL)
        first.communicate(timeout=60)
    assert code == 2
    _one_line_error(err)
    assert "in use by another sweep" in err
    assert before <= {p.name for p in (out / DONE_DIR).glob("run-*.json")}  # nothing removed


def test_a_cluster_without_workers_is_one_line(tmp_path, monkeypatch):
    from distributed import LocalCluster

    from brake_sim_ros.campaigns import load_campaign
    from brake_sim_ros.datasets import executors
    from brake_sim_ros.datasets.sweep import SweepError, sweep

    monkeypatch.setattr(executors, "WORKERS_TIMEOUT_S", 2.0)
    campaign = load_campaign(_campaign(tmp_path / "c.toml", "c", 3, 1200.0, 0.1))
    with (
        LocalCluster(n_workers=0, processes=True, dashboard_address=None) as cluster,
        pytest.raises(SweepError, match="no worker joined in 2 s"),
    ):
        sweep(campaign, tmp_path / "out", scheduler=cluster.scheduler_address, quiet=True)
    assert not (tmp_path / "out" / MANIFEST_NAME).exists()


def test_a_killed_dask_worker_is_one_line_and_leaves_no_partial_file(tmp_path):
    import dask
    from distributed import Client, LocalCluster

    campaign = _campaign(tmp_path / "c.toml", "c", 30, 1200.0, 0.5)
    out = tmp_path / "out"
    # the scheduler runs here: a task whose worker dies once is KilledWorker at once
    with (
        dask.config.set({"distributed.scheduler.allowed-failures": 0}),
        LocalCluster(
            n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        Client(cluster.scheduler_address) as client,
    ):
        process = _start(str(campaign), "--out", str(out), "--scheduler", cluster.scheduler_address)
        deadline = time.monotonic() + 180
        while _records(out) < 1:
            assert process.poll() is None and time.monotonic() < deadline
            time.sleep(0.01)
        (pid,) = client.run(os.getpid).values()
        os.kill(pid, signal.SIGKILL)  # the worker, mid-run
        _, err = process.communicate(timeout=120)
    assert process.returncode == 2
    _one_line_error(err)
    assert "worker process died" in err
    assert not [p for p in out.rglob("*") if ".partial" in p.name]
    assert not (out / MANIFEST_NAME).exists()


def test_a_full_disk_while_writing_the_lock_is_one_line(tmp_path):
    import resource

    campaign = _campaign(tmp_path / "c.toml", "c", 3, 1200.0, 0.1)
    out = tmp_path / "out"

    def small_files() -> None:  # EFBIG past 100 bytes, as ENOSPC would fail the write
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (100, 100))

    result = cli_process.run(
        [sys.executable, "-m", "brake_sim_ros.cli", "sweep", str(campaign), "--out", str(out),
         "--quiet", "--workers", "1"],
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        capture_output=True,
        text=True,
        timeout=300,
        preexec_fn=small_files,
    )  # fmt: skip
    assert result.returncode == 2, result.stderr
    _one_line_error(result.stderr)
    assert "campaign.lock" in result.stderr and "cannot write it" in result.stderr
    assert not any(out.iterdir())  # neither the lock nor its temporary file


def test_unknown_output_columns_are_refused_before_the_directory_is_made(tmp_path):
    path = _campaign(tmp_path / "c.toml", "c", 3, 1200.0, 0.1)
    path.write_text(path.read_text().replace("[outputs]\n", '[outputs]\ncolumns = ["no_such"]\n'))
    out = tmp_path / "out"
    result = cli_process.run(
        [sys.executable, "-m", "brake_sim_ros.cli", "sweep", str(path), "--out", str(out),
         "--quiet", "--workers", "1"],
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        capture_output=True,
        text=True,
        timeout=300,
    )  # fmt: skip
    assert result.returncode == 2
    _one_line_error(result.stderr)
    assert "'no_such' is not a column" in result.stderr
    assert not out.exists()


def test_a_path_spelled_differently_resumes_and_a_truncated_lock_is_damaged(tmp_path):
    from brake_sim_ros.campaigns import load_campaign
    from brake_sim_ros.datasets.sweep_output import LOCK_NAME, SweepError, prepare_output

    path = _campaign(tmp_path / "c.toml", "c", 3, 1200.0, 0.1)
    out = tmp_path / "out"
    first = load_campaign(path)
    prepare_output(out, first.lock_text(first.runs()))
    other = tmp_path / "sub" / ".." / "c.toml"
    (tmp_path / "sub").mkdir()
    again = load_campaign(str(other))
    assert again.lock_text(again.runs()) != first.lock_text(first.runs())  # the spelling
    prepare_output(out, again.lock_text(again.runs()))  # the same campaign: resumed
    text = (out / LOCK_NAME).read_text()
    (out / LOCK_NAME).write_text(text[: len(text) // 2])
    with pytest.raises(SweepError, match="damaged"):
        prepare_output(out, first.lock_text(first.runs()))
