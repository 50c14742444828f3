"""The output directory of ``brake-sim sweep``: its files' names, the claim a sweep holds
on it, the check of a resumed one, finished runs' records and the manifest.

The directory ``DIR``:

* ``campaign.lock``: the campaign, its base scenario, the library version and every run
  resolved (JSON). A sweep resumes only into a directory whose lock is the same bytes.
* ``samples/run=<run_id>/part-0.parquet``: one Parquet file per finished run, a
  hive-partitioned dataset (``pyarrow.dataset.dataset(DIR/samples, partitioning="hive")``
  gives a ``run`` column); the columns of ``simulate --out run.parquet``
  (:func:`~brake_sim_ros.datasets.parquet.run_table`: units in names, per-sample defect
  label columns, the full scenario in the metadata) plus the run id, unit and split in it.
* ``manifest.parquet``: one row per run (:data:`MANIFEST_COLUMNS`, the varied values and
  the defect label columns), written when the sweep ends.
* ``.done/<run_id>.json``: what a finished run wrote (its file's SHA-256, rows, cost),
  written after the file; a resumed sweep skips a run whose record and file agree. Not
  synced to disk (the other files are): a record lost or torn by a crash only reruns its run.

Every file is written under a temporary name and renamed when whole, so a killed sweep
never leaves a partly written file that counts as done; its leftover temporary files are
removed when the sweep resumes.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import json
import os
import re
import secrets
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.recording.mcap_format import describe_path
from brake_sim_ros.recording.output import OutputError, atomic_output, output_directory

if TYPE_CHECKING:
    from brake_sim_ros.campaigns.loader import RunSpec

LOCK_NAME = "campaign.lock"
MANIFEST_NAME = "manifest.parquet"
SAMPLES_DIR = "samples"
DONE_DIR = ".done"
PART_NAME = "part-0.parquet"
# the manifest's own columns (then the varied values, then the defect label columns)
MANIFEST_COLUMNS = ("run_id", "unit_id", "seed", "split")
STATUS_COLUMNS = ("status", "error", "cost_cpu_s", "file", "sha256", "rows")
# the temporary names of recording.output.atomic_output: removed when a sweep resumes
_PARTIAL = re.compile(r"\..+\.[0-9a-f]{8}\.partial(\.[a-z]+)?")


class SweepError(BrakeSimError, ValueError):
    """An output directory a sweep refuses, in one line."""


@dataclass(frozen=True)
class Outcome:
    """What one run gave.

    Attributes:
        run_id: the run.
        status: ``"ok"`` or ``"failed"``.
        error: one line when failed, else "".
        cost_cpu_s: CPU time of the worker process during the run (simulate, measure,
            write; pyarrow's threads included), s. A Dask worker running several tasks
            at once in threads counts theirs too: give it one thread per process.
        file: the run's file relative to the output directory ("" when failed).
        sha256: the file's SHA-256 ("" when failed).
        rows: samples written.
        peak_rss_mb: the worker process's peak resident memory so far, MB (not in the
            manifest: a measurement of the machine, for the benchmark).
    """

    run_id: str
    status: str
    error: str = ""
    cost_cpu_s: float = 0.0
    file: str = ""
    sha256: str = ""
    rows: int = 0
    peak_rss_mb: float = 0.0


def sha256_file(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def run_file(run_id: str) -> str:
    """A run's file, relative to the output directory."""
    return f"{SAMPLES_DIR}/run={run_id}/{PART_NAME}"


@contextlib.contextmanager
def claimed_output(out: Path, lock_text: str) -> Iterator[None]:
    """``out`` checked and prepared (:func:`prepare_output`) and held by this sweep for the
    block: a second sweep into it meanwhile is refused (an advisory ``flock`` on the
    directory, released however this process ends).

    Raises:
        SweepError: one line naming the directory.
    """
    _make_directory(out)
    try:
        fd = os.open(out, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)
    except OSError as exc:
        raise SweepError(f"--out {describe_path(out)}: cannot open it ({exc.strerror})") from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise SweepError(
                f"--out {describe_path(out)} is in use by another sweep running now: wait"
                " for it to end, or give another directory"
            ) from None
        prepare_output(out, lock_text)
        yield
    finally:
        os.close(fd)


def write_whole(path: Path, write: Callable[[Path], None]) -> None:
    """``write`` a temporary file renamed to ``path`` when whole; a full disk or any other
    write error is one line (the temporary file removed)."""
    try:
        with atomic_output(path, overwrite=True, option="--out") as partial:
            write(partial)
    except OSError as exc:  # OutputError is a BrakeSimError, not an OSError
        raise SweepError(
            f"--out {describe_path(path)}: cannot write it ({exc.strerror or exc})"
        ) from None


def _make_directory(out: Path) -> None:
    """``out`` made (with its parents) if missing; refused if a link or not a directory
    (:func:`.output_directory`'s rules, as a SweepError)."""
    try:
        output_directory(out, "--out")
    except OutputError as exc:
        raise SweepError(str(exc)) from None


def prepare_output(out: Path, lock_text: str) -> None:
    """Check ``out`` and write its lock: a new directory (made with any missing parents),
    an empty one, or one holding this campaign's lock (resumed). Refused: a link, a non-directory,
    a directory with other files or another campaign's lock. Stale temporary files of a
    killed sweep are removed.

    Raises:
        SweepError: one line naming the directory.
    """
    _make_directory(out)
    name = describe_path(out)
    lock = out / LOCK_NAME
    entries = sorted(os.listdir(out))
    if LOCK_NAME in entries:
        for part in (lock, out / SAMPLES_DIR, out / DONE_DIR, *(out / SAMPLES_DIR).glob("*")):
            if part.is_symlink():  # a file written into it would land elsewhere
                raise SweepError(
                    f"--out {name}: {describe_path(part.relative_to(out))} is a symbolic link:"
                    " outputs are never written through a link"
                )
        if not lock.is_file() or lock.stat().st_size > 64 * 1024**2:
            raise SweepError(f"--out {name}: {LOCK_NAME} is not a campaign lock file")
        _same_campaign(lock.read_bytes(), lock_text, name)
        remove_partials(out)
        return
    if entries:
        raise SweepError(
            f"--out {name} is not empty and holds no {LOCK_NAME}: allowed a new or empty"
            " directory, or one of this campaign's sweeps (to resume it)"
        )
    write_whole(lock, lambda partial: partial.write_text(lock_text, encoding="utf-8"))


def _same_campaign(held: bytes, lock_text: str, name: str) -> None:
    """Refuse a directory whose lock is not this campaign's: the same bytes, or the same
    but for the path the campaign was named by (``c.toml``, ``./c.toml``: one file).

    Raises:
        SweepError: a damaged lock, or another campaign's.
    """
    if held == lock_text.encode():
        return
    try:
        old = json.loads(held.decode("utf-8"))
        if not isinstance(old, dict) or not isinstance(old.get("runs"), list):
            raise ValueError("not a lock")
    except (UnicodeDecodeError, ValueError, RecursionError):
        raise SweepError(
            f"--out {name}: its {LOCK_NAME} is damaged (truncated, or not a campaign lock):"
            " give a new directory"
        ) from None
    new = json.loads(lock_text)
    source = "campaign_source"
    if {**old, source: None} != {**new, source: None}:
        raise SweepError(
            f"--out {name} holds another campaign (or this one with another version of"
            f" brake-sim-ros): its {LOCK_NAME} differs; give a new directory"
        )


def remove_partials(out: Path) -> None:
    for directory in (out, out / DONE_DIR, *(out / SAMPLES_DIR).glob("run=*")):
        if not directory.is_dir() or directory.is_symlink():
            continue
        for entry in os.scandir(directory):
            if _PARTIAL.fullmatch(entry.name) and entry.is_file(follow_symlinks=False):
                with contextlib.suppress(OSError):
                    os.unlink(entry.path)


def finished(out: Path, run_id: str) -> Outcome | None:
    """The record of a run a previous sweep finished, when its file is there and has the
    recorded SHA-256; else None (the run is done again)."""
    record = out / DONE_DIR / f"{run_id}.json"
    try:
        if record.is_symlink() or not record.is_file() or record.stat().st_size > 4096:
            return None
        outcome = Outcome(**json.loads(record.read_text(encoding="utf-8")))
        path = out / outcome.file
        if outcome.status != "ok" or outcome.file != run_file(run_id) or path.is_symlink():
            return None
        if not path.is_file() or sha256_file(path) != outcome.sha256:
            return None
    except (OSError, ValueError, TypeError):
        return None
    return outcome


def record_outcome(out: Path, outcome: Outcome) -> None:
    """Write a finished run's record: under a temporary name, renamed when whole, never
    through a link, but not fsync'ed. A record vouches for nothing by itself (a resumed
    sweep trusts it only when it parses and the file has its SHA-256, :func:`finished`),
    so one lost or torn by a crash only makes that run run again; the two fsyncs per run
    it cost were most of the parent's work (10-30 ms a run on a loaded disk) and, on 2
    workers, the sweep's bottleneck for short runs."""
    directory = out / DONE_DIR
    target = directory / f"{outcome.run_id}.json"
    directory.mkdir(exist_ok=True)
    if directory.is_symlink() or target.is_symlink():
        raise SweepError(
            f"--out {describe_path(out)}: {describe_path(target.relative_to(out))} is a symbolic"
            " link: outputs are never written through a link"
        )
    partial = directory / f".{target.name}.{secrets.token_hex(4)}.partial.json"
    try:
        partial.write_text(json.dumps(asdict(outcome), sort_keys=True), encoding="utf-8")
        os.replace(partial, target)
    except OSError as exc:
        with contextlib.suppress(OSError):
            partial.unlink()
        raise OutputError(
            f"--out {describe_path(out)}: cannot write {describe_path(target.relative_to(out))}"
            f" ({exc.strerror or exc})"
        ) from None


def manifest_table(runs: list[RunSpec], outcomes: dict[str, Outcome]) -> Any:
    """One row per run: :data:`MANIFEST_COLUMNS`, the varied values, the defect label
    columns, then :data:`STATUS_COLUMNS` (error, file and sha256 null where not
    applicable)."""
    import pyarrow as pa

    varied = list(dict.fromkeys(c for r in runs for c in r.columns))
    labels = list(dict.fromkeys(c for r in runs for c in r.labels))
    rows = [outcomes[r.run_id] for r in runs]
    columns: dict[str, Any] = {
        "run_id": pa.array([r.run_id for r in runs], pa.string()),
        "unit_id": pa.array([r.unit_id for r in runs], pa.string()),
        "seed": pa.array([r.seed for r in runs], pa.int64()),
        "split": pa.array([r.split for r in runs], pa.string()),
    }
    for name in varied:
        columns[name] = pa.array([r.columns.get(name) for r in runs])
    for name in labels:
        columns[name] = pa.array([r.labels.get(name, 0.0) for r in runs], pa.float64())
    columns["status"] = pa.array([o.status for o in rows], pa.string())
    columns["error"] = pa.array([o.error or None for o in rows], pa.string())
    columns["cost_cpu_s"] = pa.array([o.cost_cpu_s for o in rows], pa.float64())
    columns["file"] = pa.array([o.file or None for o in rows], pa.string())
    columns["sha256"] = pa.array([o.sha256 or None for o in rows], pa.string())
    columns["rows"] = pa.array([o.rows for o in rows], pa.int64())
    return pa.table(columns)
