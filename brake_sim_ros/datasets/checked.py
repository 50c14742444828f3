"""The checked reading of a sweep's directory: every file read as hostile input, and a run's
samples given out only once they are what the manifest promises.

* files: regular files only (a FIFO, a device, a link to ``/dev/zero`` refused before a
  byte is read), at most a stated size, read once into memory;
* ``campaign.lock``: JSON of the shape :meth:`Campaign.lock_text` writes (types checked,
  nesting bounded);
* ``manifest.parquet``: the columns :mod:`.sweep` writes, with their types, one row per
  run of the lock, run by run the same unit and split;
* a run's file: the manifest's SHA-256 over the bytes read (the same bytes then parsed),
  its row count, a finite ``time_s`` strictly increasing at a constant step, numeric
  measured and label columns.

Each refusal is a :class:`~.reader.DatasetError` naming the directory and what is wrong.
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from brake_sim_ros import regular_file
from brake_sim_ros.campaigns.splits import SPLITS
from brake_sim_ros.datasets.sweep_output import run_file
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.recording.mcap_format import describe_path
from brake_sim_ros.regular_file import FileRefusedError, read_regular_file

LOCK_LIMIT_BYTES = 64 * 1024**2  # what prepare_output accepts
MANIFEST_LIMIT_BYTES = 256 * 1024**2
RUN_LIMIT_BYTES = 4 * 1024**3
# the manifest's columns and the Arrow types the sweep writes them with
MANIFEST_TYPES = {
    "run_id": pa.string(),
    "unit_id": pa.string(),
    "seed": pa.int64(),
    "split": pa.string(),
    "status": pa.string(),
    "file": pa.string(),
    "sha256": pa.string(),
    "rows": pa.int64(),
}
# what a run of the manifest became: written whole, or failed with its error
STATUSES = ("ok", "failed")
# a constant sample step, to this relative tolerance (the times are i / rate in float64)
STEP_TOLERANCE = 1e-6


class DatasetError(BrakeSimError, ValueError):
    """A sweep directory that cannot be read, is damaged, or leaks (one line)."""


def read_bytes(path: Path, limit: int, where: str) -> bytes:
    """The bytes of the regular file ``path`` (not through a link), at most ``limit``.

    Raises:
        DatasetError: missing, not a regular file, too large or unreadable (one line).
    """
    try:
        return read_regular_file(path, limit, follow_symlinks=False)
    except FileRefusedError as exc:
        raise DatasetError(_refusal(where, limit, exc)) from None


def _refusal(where: str, limit: int, exc: FileRefusedError) -> str:
    """The one-line message for a file of the sweep :func:`read_regular_file` refused."""
    if exc.reason == regular_file.MISSING:
        return f"{where}: missing"
    if exc.reason == regular_file.NOT_OPENED:
        return f"{where}: cannot open it ({exc.detail}; a link?)"
    if exc.reason == regular_file.NOT_A_PATH:
        return f"{where}: cannot open it (not a valid path)"
    if exc.reason == regular_file.NOT_REGULAR:
        return f"{where}: not a regular file"
    if exc.reason == regular_file.TOO_LARGE:
        return f"{where}: {exc.size} bytes; allowed at most {limit}"
    if exc.reason == regular_file.GREW:
        return f"{where}: grew past {limit} bytes while read"
    return f"{where}: cannot read it ({exc.detail})"


def parse_lock(data: bytes, where: str) -> dict[str, Any]:
    """``campaign.lock``'s JSON, its shape checked (the keys readers use).

    Raises:
        DatasetError: not UTF-8 JSON of a lock's shape (one line naming the item).
    """
    try:
        lock = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        kind = "nested too deep" if isinstance(exc, RecursionError) else type(exc).__name__
        raise DatasetError(f"{where}: not a campaign lock ({kind})") from None
    if not isinstance(lock, dict) or not isinstance(lock.get("runs"), list):
        raise DatasetError(f"{where}: not a campaign lock (no list of runs)")
    if not isinstance(lock.get("campaign"), str):
        raise DatasetError(f"{where}: campaign: allowed a name (string)")
    for i, run in enumerate(lock["runs"]):
        if not isinstance(run, dict):
            raise DatasetError(f"{where}: runs[{i}]: allowed an object")
        for key in ("run_id", "unit_id", "split"):
            if not isinstance(run.get(key), str):
                raise DatasetError(f"{where}: runs[{i}].{key}: allowed a string")
        if run["split"] not in SPLITS:
            raise DatasetError(f"{where}: runs[{i}].split {run['split']!r}: allowed {SPLITS}")
    held = lock.get("held_out", [])
    if not isinstance(held, list):
        raise DatasetError(f"{where}: held_out: allowed a list")
    for i, rule in enumerate(held):
        _check_held_out(rule, f"{where}: held_out[{i}]")
    return lock


def _number_or_none(value: Any) -> bool:
    if value is None:
        return True
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _check_held_out(rule: Any, where: str) -> None:
    if not isinstance(rule, dict) or not isinstance(rule.get("column"), str):
        raise DatasetError(f"{where}: allowed an object with a column name")
    if not isinstance(rule.get("values"), list) or any(
        isinstance(v, list | dict) for v in rule["values"]
    ):
        raise DatasetError(f"{where}.values: allowed a list of plain values")
    for key in ("minimum", "maximum"):
        if not _number_or_none(rule.get(key)):
            raise DatasetError(f"{where}.{key}: allowed a finite number or null")


def parquet_table(data: bytes) -> pa.Table:
    """The Parquet file ``data`` as a table, read from a copy in Arrow's own memory.

    Read from the Python bytes themselves, Arrow may release its last reference to them on
    one of its pool's threads after the read has returned; if that happens while the
    interpreter shuts down, the thread cannot take the GIL and the process aborts
    ("terminate called without an active exception"). Arrow's memory needs no GIL.

    Raises:
        pyarrow.ArrowException, OSError, ValueError: the bytes are not a Parquet file.
    """
    owned = pa.allocate_buffer(len(data))
    np.frombuffer(owned, np.uint8)[:] = np.frombuffer(data, np.uint8)
    return pq.read_table(pa.BufferReader(owned))


def parse_manifest(data: bytes, lock: dict[str, Any], where: str) -> pa.Table:
    """``manifest.parquet``, its columns and types checked (then :func:`check_agreement`).

    Raises:
        DatasetError: one line naming the column or run.
    """
    try:
        manifest = parquet_table(data)
    except (pa.ArrowException, OSError, ValueError) as exc:
        raise DatasetError(f"{where}: cannot be read ({type(exc).__name__})") from None
    for name, kind in MANIFEST_TYPES.items():
        if name not in manifest.column_names:
            raise DatasetError(f"{where} has no column {name!r}: damaged")
        if manifest.schema.field(name).type != kind:
            raise DatasetError(
                f"{where}: column {name!r} is {manifest.schema.field(name).type}, allowed"
                f" {kind}: damaged"
            )
    if "defect_kind" in manifest.column_names and "defect_location" not in manifest.column_names:
        raise DatasetError(f"{where}: column 'defect_kind' without 'defect_location': damaged")
    return manifest


def check_agreement(manifest: pa.Table, lock: dict[str, Any], where: str) -> None:
    """The manifest lists the lock's runs, each with the lock's unit, split and label
    columns (its defect, severity and force: a NaN agrees with nothing), a status of
    :data:`STATUSES`, and each finished run with its file, SHA-256 and rows.

    Raises:
        DatasetError: one line naming the run.
    """
    rows = manifest.to_pylist()
    locked = {r["run_id"]: r for r in lock["runs"]}
    if len(rows) != len(locked) or {r["run_id"] for r in rows} != set(locked):
        raise DatasetError(f"{where} and the lock list different runs: damaged")
    for row in rows:
        run = locked[row["run_id"]]
        if (run["unit_id"], run["split"]) != (row["unit_id"], row["split"]):
            raise DatasetError(f"{where}: run {row['run_id']} disagrees with the lock: damaged")
        columns = run.get("columns", {})
        for name, value in columns.items() if isinstance(columns, dict) else ():
            if name not in row or row[name] != value:
                raise DatasetError(
                    f"{where}: run {row['run_id']}: {name} {row.get(name)!r} is not the"
                    f" lock's {value!r}: damaged"
                )
        if row["status"] not in STATUSES:
            raise DatasetError(
                f"{where}: run {row['run_id']}: status {row['status']!r}, allowed one of"
                f" {list(STATUSES)}: damaged"
            )
        if row["status"] == "ok" and (
            row["file"] != run_file(row["run_id"])
            or not isinstance(row["sha256"], str)
            or len(row["sha256"]) != 64
            or row["rows"] is None
            or row["rows"] < 2
        ):
            raise DatasetError(
                f"{where}: run {row['run_id']}: its file, SHA-256 or rows are not a finished"
                " run's: damaged"
            )


def read_run(root: Path, row: dict[str, Any]) -> pa.Table:
    """The samples of the finished run of manifest row ``row``, once its bytes have the
    recorded SHA-256 and its table the recorded rows and a regular time axis.

    Raises:
        DatasetError: one line naming the run.
    """
    where = f"{describe_path(root)}: run {row['run_id']}"
    path = root / run_file(row["run_id"])
    data = read_bytes(path, RUN_LIMIT_BYTES, f"{where}: {run_file(row['run_id'])}")
    if hashlib.sha256(data).hexdigest() != row["sha256"]:
        raise DatasetError(f"{where}: its file's SHA-256 is not the manifest's: damaged")
    try:
        table = parquet_table(data)
    except (pa.ArrowException, OSError, ValueError) as exc:
        raise DatasetError(f"{where}: its file cannot be read ({type(exc).__name__})") from None
    if table.num_rows != row["rows"]:
        raise DatasetError(f"{where}: {table.num_rows} rows, the manifest says {row['rows']}")
    check_samples(table, where)
    return table


def check_samples(table: pa.Table, where: str) -> None:
    """A run's table: a finite, strictly increasing ``time_s`` at a constant step, and
    numeric measured and label columns.

    Raises:
        DatasetError: one line naming the column.
    """
    if "time_s" not in table.column_names:
        raise DatasetError(f"{where}: no column 'time_s'")
    if not pa.types.is_floating(table.schema.field("time_s").type):
        raise DatasetError(f"{where}: time_s is {table.schema.field('time_s').type}: allowed float")
    time_s = table["time_s"].to_numpy(zero_copy_only=False).astype(np.float64)
    if time_s.size < 2 or not np.all(np.isfinite(time_s)):
        raise DatasetError(f"{where}: time_s: allowed 2 or more finite times")
    steps = np.diff(time_s)
    step = float(steps[0])
    if not step > 0.0 or np.any(np.abs(steps - step) > STEP_TOLERANCE * step):
        raise DatasetError(
            f"{where}: time_s is not strictly increasing at a constant step: damaged"
        )
    for field in table.schema:
        if field.name.startswith(("measured:", "defect:")) and not (
            pa.types.is_floating(field.type) or pa.types.is_integer(field.type)
        ):
            raise DatasetError(f"{where}: column {field.name!r} is {field.type}: allowed numbers")
