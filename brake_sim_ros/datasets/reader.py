"""Reading a sweep's dataset: a lazy view over its Parquet files, splits, windows, and the
checks of ``brake-sim dataset info`` (leakage, damage).

Every file is read through :mod:`.checked`: a run's samples reach the caller only once
its bytes have the manifest's SHA-256 and its time axis is regular.

Nothing is read until asked: :attr:`SweepDataset.samples` is a :mod:`pyarrow.dataset`
(hive-partitioned by ``run``) that pandas and polars read lazily too
(``ds.samples.to_table(filter=...).to_pandas()``, ``polars.scan_pyarrow_dataset``).
"""

from __future__ import annotations

import os
from collections import Counter
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.dataset as pads

from brake_sim_ros.campaigns.splits import SPLITS, HeldOut, leaks
from brake_sim_ros.datasets import checked
from brake_sim_ros.datasets.checked import DatasetError
from brake_sim_ros.datasets.sweep_output import LOCK_NAME, MANIFEST_NAME, SAMPLES_DIR, run_file
from brake_sim_ros.model.catalogue import label_columns
from brake_sim_ros.recording.mcap_format import describe_path

REQUIRED = ("run_id", "unit_id", "seed", "split", "status", "file", "sha256")


@dataclass(frozen=True)
class Windows:
    """Windows of one run.

    Attributes:
        run_id, unit_id, split: the run's.
        data: shape (windows, n, columns), float64: consecutive samples of ``columns``.
        columns: the column names of the last axis of ``data``.
        labels: shape (windows, labels): each label column's value at a window's last sample.
        label_columns: the label column names (``defect:<kind>:<location> [<unit>]``).
    """

    run_id: str
    unit_id: str
    split: str
    data: np.ndarray
    columns: tuple[str, ...]
    labels: np.ndarray
    label_columns: tuple[str, ...]


class SweepDataset:
    """A sweep's output directory, opened lazily (:func:`open_dataset`)."""

    def __init__(self, root: Path, manifest: pa.Table, lock: dict[str, Any]) -> None:
        self.root = root
        self.manifest = manifest  # one row per run
        self.lock = lock
        self._samples: pads.Dataset | None = None
        self._by_id: dict[str, dict[str, Any]] | None = None

    @property
    def held_out(self) -> tuple[HeldOut, ...]:
        return tuple(
            HeldOut(h["column"], tuple(h["values"]), h["minimum"], h["maximum"])
            for h in self.lock.get("held_out", [])
        )

    @property
    def samples(self) -> pads.Dataset:
        """Every finished run's samples, a ``run`` column from the partitioning."""
        if self._samples is None:
            self._samples = pads.dataset(
                self.root / SAMPLES_DIR, format="parquet", partitioning="hive"
            )
        return self._samples

    def runs(self, split: str | None = None) -> list[str]:
        """The finished runs (of ``split``), in run-id order."""
        if split is not None and split not in SPLITS:
            raise DatasetError(f"split {split!r}: allowed one of {SPLITS}")
        rows = self.manifest.select(["run_id", "split", "status"]).to_pylist()
        return [
            r["run_id"]
            for r in rows
            if r["status"] == "ok" and (split is None or r["split"] == split)
        ]

    def run_table(self, run_id: str) -> pa.Table:
        """One finished run's samples, read whole and checked (:func:`.checked.read_run`).

        Raises:
            DatasetError: not a finished run of the manifest, or its file damaged.
        """
        row = self._rows().get(run_id)
        if row is None or row["status"] != "ok":
            raise DatasetError(f"{describe_path(self.root)}: no finished run {run_id!r}")
        return checked.read_run(self.root, row)

    def run_where(self, run_id: str) -> str:
        """How messages name a run: its id and its file."""
        return f"run {run_id} ({describe_path(self.root / run_file(run_id))})"

    def _rows(self) -> dict[str, dict[str, Any]]:
        if self._by_id is None:
            rows = self.manifest.select(list(checked.MANIFEST_TYPES)).to_pylist()
            self._by_id = {r["run_id"]: r for r in rows}
        return self._by_id

    def split(self, name: str) -> pads.Dataset:
        """The samples of the split ``name`` (lazy)."""
        return self.samples.filter(pads.field("run").isin(self.runs(name)))

    def windows(
        self,
        n: int,
        *,
        split: str | None = None,
        columns: Sequence[str] | None = None,
        step: int | None = None,
    ) -> Iterator[Windows]:
        """Windows of ``n`` consecutive samples (every ``step`` samples, default ``n``),
        run by run, each with its labels; ``columns`` default: the measured channels, or
        every non-label column when the runs measured none."""
        if n < 1 or (step is not None and step < 1):
            raise DatasetError(f"windows of {n} samples every {step}: allowed sizes >= 1")
        step = n if step is None else step
        info = {
            r["run_id"]: r for r in self.manifest.select(["run_id", "unit_id", "split"]).to_pylist()
        }
        for run_id in self.runs(split):
            table = self.run_table(run_id)
            names = table.column_names
            labels = tuple(c for c in names if c.startswith("defect:"))
            chosen = (
                tuple(columns)
                if columns is not None
                else tuple(c for c in names if c.startswith("measured:"))
                or tuple(c for c in names if c not in labels and c != "sample_index")
            )
            missing = [c for c in chosen if c not in names]
            if missing:
                raise DatasetError(f"run {run_id}: no column {missing[0]!r}")
            data = np.column_stack([table[c].to_numpy(zero_copy_only=False) for c in chosen])
            truth = (
                np.column_stack([table[c].to_numpy() for c in labels])
                if labels
                else np.zeros((len(data), 0))
            )
            starts = np.arange(0, len(data) - n + 1, step)
            yield Windows(
                run_id,
                info[run_id]["unit_id"],
                info[run_id]["split"],
                np.stack([data[s : s + n] for s in starts])
                if len(starts)
                else np.zeros((0, n, len(chosen))),
                chosen,
                truth[starts + n - 1] if len(starts) else np.zeros((0, len(labels))),
                labels,
            )


def open_dataset(directory: str | os.PathLike[str]) -> SweepDataset:
    """Open a sweep's output directory (``brake-sim sweep CAMPAIGN --out DIR``).

    Raises:
        DatasetError: no manifest or lock, or one that cannot be read (one line).
    """
    root = Path(directory)
    name = describe_path(root)
    if not root.is_dir():
        raise DatasetError(f"{name}: not a directory: allowed a sweep's output directory")
    if not os.path.lexists(root / LOCK_NAME):
        raise DatasetError(f"{name}: no {LOCK_NAME}: not a sweep's output directory")
    where = f"{name}: {LOCK_NAME}"
    lock = checked.parse_lock(
        checked.read_bytes(root / LOCK_NAME, checked.LOCK_LIMIT_BYTES, where), where
    )
    if not os.path.lexists(root / MANIFEST_NAME):
        raise DatasetError(
            f"{name}: no {MANIFEST_NAME}: the sweep did not finish (run it again to resume)"
        )
    where = f"{name}: {MANIFEST_NAME}"
    data = checked.read_bytes(root / MANIFEST_NAME, checked.MANIFEST_LIMIT_BYTES, where)
    manifest = checked.parse_manifest(data, lock, where)
    _refuse_leaks(root, manifest, lock)  # first: a leak is worse news than damage
    checked.check_agreement(manifest, lock, where)
    return SweepDataset(root, manifest, lock)


def _refuse_leaks(root: Path, manifest: pa.Table, lock: dict[str, Any]) -> None:
    held = [
        HeldOut(h["column"], tuple(h["values"]), h.get("minimum"), h.get("maximum"))
        for h in lock.get("held_out", [])
    ]
    problems = leaks(manifest.to_pylist(), held)
    if problems:
        more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
        raise DatasetError(f"{describe_path(root)}: leakage: {problems[0]}{more}")


def check(dataset: SweepDataset) -> None:
    """Leakage (a unit in two splits, a held-out value outside test) and damage (a
    finished run's file missing, changed or not a regular time series, or its columns not
    the other runs').

    Raises:
        DatasetError: the first problem, with how many there are.
    """
    _refuse_leaks(dataset.root, dataset.manifest, dataset.lock)
    first: tuple[str, list[str]] | None = None
    for run_id in dataset.runs():  # the manifest agrees with the lock (checked on opening)
        names = dataset.run_table(run_id).column_names
        if first is None:
            first = (run_id, names)
        elif names != first[1]:  # one campaign, one set of outputs
            other = sorted(set(first[1]) ^ set(names)) or ["their order"]
            raise DatasetError(
                f"{dataset.run_where(run_id)}: its columns are not run {first[0]}'s"
                f" ({other[0]!r} differs): damaged"
            )


def info_text(dataset: SweepDataset) -> str:
    """``brake-sim dataset info``: runs, units and class balance per split (a class: the
    defect kind and location, or each label column's presence), after :func:`check`."""
    check(dataset)
    rows = dataset.manifest.to_pylist()
    kinds = "defect_kind" in dataset.manifest.column_names
    present = [c for c in label_columns() if c in dataset.manifest.column_names]
    lines = [
        f"dataset {describe_path(dataset.root)}: campaign {dataset.lock.get('campaign')},"
        f" {len(rows)} runs, {sum(r['status'] == 'ok' for r in rows)} ok,"
        f" {sum(r['status'] != 'ok' for r in rows)} failed; leak-free (no unit in two splits"
        + (", held-out values in test only)" if dataset.held_out else ")")
    ]
    for split in SPLITS:
        mine = [r for r in rows if r["split"] == split]
        units = sorted({r["unit_id"] for r in mine})
        lines.append(f"  {split}: {len(mine)} runs on {len(units)} units")
        if kinds:
            counts = Counter(
                f"{r['defect_kind']}:{r['defect_location']}"
                if r["defect_location"]
                else r["defect_kind"]
                for r in mine
            )
        else:
            counts = Counter(",".join(c for c in present if r[c]) or "healthy" for r in mine)
        for label, count in sorted(counts.items()):
            lines.append(f"    {label:40s} {count:6d} ({100 * count / len(mine):.0f} %)")
    return "\n".join(lines)
