"""Damaged sweep directories read by ``dataset info``, ``score`` and ``fit``: each damage
gives a non-zero exit and one line (no traceback, no hang, no model file written), and a
detector never sees a sample whose file is not what the manifest promises. A real sweep
(real worker processes, real Parquet) is damaged one way per case.

Two kinds of damage: naive (bytes changed under the recorded SHA-256) and consistent (the
file rewritten and the manifest's SHA-256 and rows updated to match), so that the checks
of the content itself (columns, types, a regular time axis) are reached too.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from brake_sim_ros import cli
from brake_sim_ros.campaigns import load_campaign
from brake_sim_ros.datasets.sweep import sweep
from brake_sim_ros.datasets.sweep_output import LOCK_NAME, MANIFEST_NAME
from tests import cli_process

ROOT = Path(__file__).resolve().parents[2]
CAMPAIGN = """
name = "damaged"
base = "symmetric"
seed = 3
units = 3
[outputs]
duration_s = 0.3
sample_rate_hz = 2560.0
[[axes]]
defects = ["initial_angle"]
severities = [1.0]
healthy = true
"""
COMMANDS = {
    "info": lambda d, tmp: ["dataset", "info", str(d)],
    "score": lambda d, tmp: ["score", str(d), "--fit-split", "train", "--split", "test"],
    "fit": lambda d, tmp: ["fit", str(d), "--detector", "rms", "--out", str(tmp / "m.json")],
}


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("dataset")
    (folder / "c.toml").write_text(CAMPAIGN)
    out = folder / "out"
    summary, _ = sweep(load_campaign(folder / "c.toml"), out, workers=2, quiet=True)
    assert summary.failed == 0 and summary.done == summary.runs
    return out


def _manifest(d: Path) -> pa.Table:
    return pq.read_table(d / MANIFEST_NAME)


def _set_column(table: pa.Table, name: str, values: pa.Array) -> pa.Table:
    return table.set_column(table.schema.get_field_index(name), name, values)


def _first_file(d: Path, split: str = "train") -> tuple[int, Path]:
    """A run every command reads (score and fit fit on train)."""
    rows = _manifest(d).to_pylist()
    i = next(i for i, r in enumerate(rows) if r["split"] == split)
    return i, d / rows[i]["file"]


def _rewrite_run(d: Path, change: Callable[[pa.Table], pa.Table], split: str = "train") -> None:
    """Consistent damage: a run's table changed and the manifest updated to its new bytes."""
    i, path = _first_file(d, split)
    table = change(pq.read_table(path))
    pq.write_table(table, path)
    manifest = _manifest(d)
    sha = manifest["sha256"].to_pylist()
    rows = manifest["rows"].to_pylist()
    sha[i] = hashlib.sha256(path.read_bytes()).hexdigest()
    rows[i] = table.num_rows
    manifest = _set_column(manifest, "sha256", pa.array(sha, pa.string()))
    pq.write_table(_set_column(manifest, "rows", pa.array(rows, pa.int64())), d / MANIFEST_NAME)


def _flip(d: Path) -> None:
    _, path = _first_file(d, "train")
    data = bytearray(path.read_bytes())
    data[len(data) // 3] ^= 0x01
    path.write_bytes(bytes(data))


def _swap(d: Path) -> None:
    rows = [r for r in _manifest(d).to_pylist() if r["split"] == "train"]
    a, b = (d / r["file"] for r in rows[:2])
    data = a.read_bytes()
    a.write_bytes(b.read_bytes())
    b.write_bytes(data)


def _reverse(table: pa.Table) -> pa.Table:
    return table.take(pa.array(np.arange(table.num_rows)[::-1]))


def _constant_time(table: pa.Table) -> pa.Table:
    return _set_column(table, "time_s", pa.array(np.zeros(table.num_rows)))


def _manifest_change(change: Callable[[pa.Table], pa.Table]) -> Callable[[Path], None]:
    def damage(d: Path) -> None:
        pq.write_table(change(_manifest(d)), d / MANIFEST_NAME)

    return damage


def _lock_text(text: str) -> Callable[[Path], None]:
    def damage(d: Path) -> None:
        (d / LOCK_NAME).write_text(text)

    return damage


def _lock_change(change: Callable[[dict], None]) -> Callable[[Path], None]:
    def damage(d: Path) -> None:
        lock = json.loads((d / LOCK_NAME).read_text())
        change(lock)
        (d / LOCK_NAME).write_text(json.dumps(lock))

    return damage


def _replace_with_link(name: str, target: str) -> Callable[[Path], None]:
    def damage(d: Path) -> None:
        (d / name).unlink()
        (d / name).symlink_to(target)

    return damage


def _replace_with_fifo(name: str) -> Callable[[Path], None]:
    def damage(d: Path) -> None:
        (d / name).unlink()
        os.mkfifo(d / name)

    return damage


DAMAGE: dict[str, Callable[[Path], None]] = {
    "run directory removed": lambda d: shutil.rmtree(_first_file(d)[1].parent),
    "sample file byte-flipped": _flip,
    "two sample files swapped": _swap,
    "sample file time-reversed": lambda d: pq.write_table(
        _reverse(pq.read_table(_first_file(d)[1])), _first_file(d)[1]
    ),
    "time-reversed, manifest updated": lambda d: _rewrite_run(d, _reverse),
    "time_s missing, manifest updated": lambda d: _rewrite_run(d, lambda t: t.drop(["time_s"])),
    "time_s constant, manifest updated": lambda d: _rewrite_run(d, _constant_time),
    "time_s as text, manifest updated": lambda d: _rewrite_run(
        d, lambda t: _set_column(t, "time_s", pa.array([str(x) for x in t["time_s"].to_pylist()]))
    ),
    "measured channel as text, manifest updated": lambda d: _rewrite_run(
        d,
        lambda t: _set_column(
            t,
            next(c for c in t.column_names if c.startswith("measured:")),
            pa.array(["x"] * t.num_rows),
        ),
    ),
    "one row, manifest updated": lambda d: _rewrite_run(d, lambda t: t.slice(0, 1)),
    "rows disagree with the manifest": _manifest_change(
        lambda m: _set_column(m, "rows", pa.array([r + 1 for r in m["rows"].to_pylist()]))
    ),
    "integer run_id": _manifest_change(
        lambda m: _set_column(m, "run_id", pa.array(range(m.num_rows), pa.int64()))
    ),
    "manifest without defect_location": _manifest_change(lambda m: m.drop(["defect_location"])),
    "manifest without sha256": _manifest_change(lambda m: m.drop(["sha256"])),
    "manifest missing a run": _manifest_change(lambda m: m.slice(1)),
    "manifest run in another split": _manifest_change(
        lambda m: _set_column(m, "split", pa.array(["train"] * m.num_rows))
    ),
    "manifest severity NaN": _manifest_change(
        lambda m: _set_column(
            m, "defect_severity", pa.array([float("nan")] * m.num_rows, pa.float64())
        )
    ),
    "manifest run labelled another defect": _manifest_change(
        lambda m: _set_column(m, "defect_kind", pa.array(["healthy"] * m.num_rows))
    ),
    "manifest status not ok or failed": _manifest_change(
        lambda m: _set_column(m, "status", pa.array(["done"] * m.num_rows))
    ),
    "measured channels dropped, manifest updated": lambda d: _rewrite_run(
        d, lambda t: t.drop([c for c in t.column_names if c.startswith("measured:")])
    ),
    "manifest not Parquet": lambda d: (d / MANIFEST_NAME).write_bytes(b"PAR1 nonsense"),
    "manifest removed": lambda d: (d / MANIFEST_NAME).unlink(),
    "manifest a FIFO": _replace_with_fifo(MANIFEST_NAME),
    "manifest a link to /dev/zero": _replace_with_link(MANIFEST_NAME, "/dev/zero"),
    "lock removed": lambda d: (d / LOCK_NAME).unlink(),
    "lock a FIFO": _replace_with_fifo(LOCK_NAME),
    "lock a link to /dev/zero": _replace_with_link(LOCK_NAME, "/dev/zero"),
    "lock nested 1e5 deep": _lock_text("[" * 100_000 + "]" * 100_000),
    "lock runs of integers": _lock_change(lambda lock: lock.update(runs=[1, 2, 3])),
    "lock run_id an integer": _lock_change(lambda lock: lock["runs"][0].update(run_id=7)),
    "lock split a list": _lock_change(lambda lock: lock["runs"][0].update(split=["test"])),
    "lock held_out a string": _lock_change(lambda lock: lock.update(held_out="x")),
    "lock held_out minimum text": _lock_change(
        lambda lock: lock.update(held_out=[{"column": "a", "values": [], "minimum": "0"}])
    ),
    "lock campaign an object": _lock_change(lambda lock: lock.update(campaign={})),
    "lock not UTF-8": lambda d: (d / LOCK_NAME).write_bytes(b"\xff\xfe{"),
    "lock truncated": lambda d: (d / LOCK_NAME).write_text(
        (d / LOCK_NAME).read_text()[: len((d / LOCK_NAME).read_text()) // 2]
    ),
}


def _run(args: list[str], timeout: float = 120) -> subprocess.CompletedProcess[str]:
    """A real process: a hang is a failure, not a stuck test."""
    return cli_process.run(
        [sys.executable, "-m", "brake_sim_ros.cli", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )


def _main(capsys, args: list[str]) -> tuple[int, str]:
    try:
        code = cli.main(args)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    return code, capsys.readouterr().err


@pytest.mark.parametrize("damage", list(DAMAGE))
def test_damage_is_one_line_from_every_reader(tmp_path, capsys, reference, damage):
    d = tmp_path / "d"
    shutil.copytree(reference, d, symlinks=True)
    DAMAGE[damage](d)
    special = "FIFO" in damage or "/dev/zero" in damage
    for command, argv in COMMANDS.items():
        args = argv(d, tmp_path)
        # a hang or reading until memory runs out: first in a process, with a timeout (the
        # other commands open the directory the same way: in this process once it did not)
        if special and command == "info":
            result = _run(args)
            code, err = result.returncode, result.stderr
        else:
            code, err = _main(capsys, args)
        assert code == 2, f"{command}: {code} {err}"
        assert err.count("\n") == 1 and "Traceback" not in err, f"{command}: {err}"
        assert not (tmp_path / "m.json").exists()


def test_the_undamaged_dataset_is_read_by_every_command(tmp_path, capsys, reference):
    for command, argv in COMMANDS.items():
        code, err = _main(capsys, argv(reference, tmp_path))
        assert code == 0, f"{command}: {err}"
    assert json.loads((tmp_path / "m.json").read_text())["detector"]
