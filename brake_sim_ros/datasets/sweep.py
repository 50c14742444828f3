"""``brake-sim sweep``: run every run of a campaign and write a labelled, leak-free dataset.

The output directory ``DIR``:

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
removed when the sweep resumes. The same campaign gives the same bytes in every file but
the cost column of the manifest (CPU seconds, a measurement).

Runs are independent tasks: a local pool of worker processes
(:class:`concurrent.futures.ProcessPoolExecutor`, one numerics thread each, forked from a
server that loaded the kernels once: :mod:`.warm_worker`) or the workers of an existing
Dask cluster (``--scheduler``; start them with one thread each and ``OMP_NUM_THREADS=1``
``NUMBA_NUM_THREADS=1``), which must share ``DIR``'s file system. A run that fails is
recorded with its error and the others go on; a worker process that dies ends the sweep
(finished runs kept, the rerun resumes).
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import fcntl
import functools
import hashlib
import json
import os
import re
import secrets
import stat
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from brake_sim_ros.datasets import life
from brake_sim_ros.datasets.executors import ExecutorError, one_line, open_executor, pool_context
from brake_sim_ros.datasets.orphans import die_with_parent
from brake_sim_ros.datasets.threads import limit_threads
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.recording.mcap_format import describe_path
from brake_sim_ros.recording.output import OutputError, atomic_output

if TYPE_CHECKING:
    from brake_sim_ros.campaigns.campaign import Campaign, RunSpec
    from brake_sim_ros.datasets.executors import Executor

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


@dataclass(frozen=True)
class SweepSummary:
    """What a sweep did.

    Attributes:
        runs, done, failed, resumed: run counts (``resumed``: done by an earlier sweep).
        wall_s: wall time from the output directory checked and locked to the manifest
            written, s.
        cpu_s: CPU time of the runs done now, in their workers, s.
        simulated_s: simulated time of the runs done now, s.
        parent_s: wall time this process spent on its own work (planning the runs, the
            lock, the resume check, each outcome's record and progress, the manifest),
            not waiting for workers, s.
        parent_cpu_s: CPU time of this process (every thread: the pool's or the Dask
            client's too) from planning to the manifest, s.
    """

    runs: int
    done: int
    failed: int
    resumed: int
    wall_s: float
    cpu_s: float
    simulated_s: float
    parent_s: float = 0.0
    parent_cpu_s: float = 0.0

    def describe(self, out: Path) -> str:
        rate = self.simulated_s / self.wall_s if self.wall_s > 0 else float("nan")
        return (
            f"sweep {out}: {self.runs} runs, {self.done} ok ({self.resumed} already done),"
            f" {self.failed} failed; {self.wall_s:.1f} s wall, {self.cpu_s:.1f} s CPU in runs,"
            f" {rate:.1f} simulated s per wall s; manifest {out / MANIFEST_NAME}"
        )


def sha256_file(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _init_worker() -> None:
    """A pool worker: one thread (the fork server set it), the kernels loaded (by the fork
    server; else from numba's cache here, once)."""
    die_with_parent()  # the fork server: killed with the sweep, and so this worker with it
    limit_threads()
    import pyarrow

    pyarrow.set_cpu_count(1)  # Parquet encoding and compression in this thread's stead
    from brake_sim_ros.solvers.warmup import ensure_compiled

    ensure_compiled(say=lambda _line: None)


def start_pool_server() -> None:
    """Start the pool's fork server now (it imports and warms the run path), e.g. to keep
    its start out of a measurement."""
    # a first fork waits for the server's imports and warm-up (ensure_running does not)
    with concurrent.futures.ProcessPoolExecutor(1, mp_context=pool_context()) as pool:
        pool.submit(int).result()


def run_file(run_id: str) -> str:
    """A run's file, relative to the output directory."""
    return f"{SAMPLES_DIR}/run={run_id}/{PART_NAME}"


def run_task(spec: RunSpec, out_dir: str) -> Outcome:
    """Run one campaign run and write its file (temporary name, then renamed); a failure
    is returned as a failed :class:`Outcome`, never raised. Runs in a worker."""
    import pyarrow.parquet as pq

    from brake_sim_ros.datasets.parquet import run_table
    from brake_sim_ros.scenarios.loader import parse_scenario
    from brake_sim_ros.stream.run import run_scenario

    start = time.process_time()
    relative = run_file(spec.run_id)
    try:
        scenario = parse_scenario(spec.scenario_text, spec.run_id)
        result = run_scenario(scenario)
        extra = {"run_id": spec.run_id, "split": spec.split}  # the unit: the scenario's
        table = run_table(scenario, result, scenario.duration_s, extra)
        if spec.keep:
            missing = [c for c in spec.keep if c not in table.column_names]
            if missing:
                raise BrakeSimError(
                    f"outputs.columns: {missing[0]!r} is not a column of this run: allowed"
                    f" {table.column_names[:60]}"
                )
            always = ("sample_index", "time_s", *spec.labels, life.RUL_COLUMN, "phase")
            keep = [c for c in table.column_names if c in always or c in spec.keep]
            table = table.select(keep)
        path = Path(out_dir) / relative
        with atomic_output(path, overwrite=True, option=spec.run_id) as partial:
            pq.write_table(table, partial, compression="zstd")
            digest = sha256_file(partial)
        cost = time.process_time() - start
        return Outcome(spec.run_id, "ok", "", cost, relative, digest, table.num_rows, _rss_mb())
    except Exception as exc:  # recorded for this run; the sweep goes on
        error = (
            one_line(exc)
            if isinstance(exc, BrakeSimError)
            else (f"{type(exc).__name__}: {one_line(exc)}")
        )
        return Outcome(spec.run_id, "failed", error, time.process_time() - start)


def _rss_mb() -> float:
    """This process's peak resident set size, MB (Linux reports kB)."""
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


# --- the output directory -------------------------------------------------------------------
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


def _write_whole(path: Path, write: Callable[[Path], None]) -> None:
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
    """``out`` made (with its parents) if missing; refused if a link or not a directory."""
    name = describe_path(out)
    try:
        info = os.lstat(out)
    except FileNotFoundError:
        info = None
    except OSError as exc:
        raise SweepError(f"--out {name}: cannot check it ({exc.strerror or exc})") from None
    if info is None:
        try:
            out.mkdir(parents=True)
        except OSError as exc:
            raise SweepError(f"--out {name}: cannot make it ({exc.strerror or exc})") from None
    elif stat.S_ISLNK(info.st_mode):
        raise SweepError(
            f"--out {name} is a symbolic link: outputs are never written through a link"
        )
    elif not stat.S_ISDIR(info.st_mode):
        raise SweepError(f"--out {name} exists and is not a directory: allowed a directory")


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
        _remove_partials(out)
        return
    if entries:
        raise SweepError(
            f"--out {name} is not empty and holds no {LOCK_NAME}: allowed a new or empty"
            " directory, or one of this campaign's sweeps (to resume it)"
        )
    _write_whole(lock, lambda partial: partial.write_text(lock_text, encoding="utf-8"))


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


def _remove_partials(out: Path) -> None:
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


def _record(out: Path, outcome: Outcome) -> None:
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


# --- running --------------------------------------------------------------------------------
def task_tag(specs: list[RunSpec], out_dir: str) -> str:
    """16 hex digits naming these runs of this campaign into ``out_dir`` (an absolute
    path): the part of a Dask task key that keeps two sweeps on one cluster apart."""
    digest = hashlib.sha256(out_dir.encode("utf-8", "surrogateescape") + b"\0")
    for spec in specs:
        digest.update(spec.run_id.encode() + b"\0" + spec.scenario_text.encode() + b"\0")
    return digest.hexdigest()[:16]


def _checked(outcome: Outcome, todo: dict[str, RunSpec], out: Path) -> Outcome:
    """A worker's outcome, refused unless it is one of this sweep's runs and, when ok, its
    file is on disk with the SHA-256 the worker reported (a result that is not this
    sweep's must never reach the manifest)."""
    if outcome.run_id not in todo:
        raise SweepError(
            f"a worker returned run {outcome.run_id!r}, not one of this sweep's: refused"
        )
    if outcome.status == "ok":
        path = out / run_file(outcome.run_id)
        if (
            outcome.file != run_file(outcome.run_id)
            or not path.is_file()
            or (sha256_file(path) != outcome.sha256)
        ):
            raise SweepError(
                f"run {outcome.run_id}: the worker's result does not match"
                f" {describe_path(path)} (another sweep writing there?): the finished runs"
                " are kept; run the command again to resume"
            )
    return outcome


def run_columns(spec: RunSpec) -> tuple[str, ...]:
    """The columns a run of ``spec`` writes, from its first few samples (a worker task)."""
    from brake_sim_ros.datasets.parquet import run_table
    from brake_sim_ros.scenarios.loader import parse_scenario
    from brake_sim_ros.stream.run import run_scenario

    scenario = parse_scenario(spec.scenario_text, spec.run_id)
    short = min(scenario.duration_s, 8.0 / scenario.sample_rate_hz)
    return tuple(run_table(scenario, run_scenario(scenario, duration_s=short), short).column_names)


def _check_columns(executor: Executor, spec: RunSpec) -> None:
    """Refuse ``outputs.columns`` naming a column the campaign's first run does not write
    (a few of its samples simulated on a worker); the runs check it again."""
    try:
        columns = executor.call(
            run_columns,
            spec,
            "brake-sim-columns-" + hashlib.sha256(spec.scenario_text.encode()).hexdigest()[:16],
        )
    except ExecutorError:
        raise
    except Exception:  # the run itself fails: recorded as a failed run by the sweep
        return
    missing = [c for c in spec.keep if c not in columns]
    if missing:
        raise SweepError(
            f"outputs.columns: {missing[0]!r} is not a column of this campaign's runs"
            f" ({spec.run_id} writes {len(columns)}: {', '.join(columns[:40])}"
            f"{' ...' if len(columns) > 40 else ''})"
        )


def sweep(
    campaign: Campaign,
    out: Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    quiet: bool = False,
) -> tuple[SweepSummary, dict[str, Outcome]]:
    """Run ``campaign`` into ``out`` (resuming a previous sweep of it there).

    Args:
        workers: local worker processes (default: every core); ignored with ``scheduler``.
        scheduler: the address of a Dask scheduler whose workers share ``out``.
        quiet: no progress bar (it is shown on a terminal's stderr only).

    Raises:
        SweepError, OutputError: ``out`` refused (before any run), or a file not written.
    """
    planning, start_cpu = time.perf_counter(), time.process_time()
    runs = campaign.runs()
    n_workers = workers or os.cpu_count() or 1
    # a scheduler that cannot be reached is refused before DIR is made or written
    with open_executor(n_workers, scheduler, _init_worker) as executor:
        try:
            return _sweep_on(executor, campaign, runs, out, quiet, (planning, start_cpu))
        except ExecutorError as exc:
            raise SweepError(str(exc)) from None


def _sweep_on(
    executor: Executor,
    campaign: Campaign,
    runs: list[RunSpec],
    out: Path,
    quiet: bool,
    began: tuple[float, float],
) -> tuple[SweepSummary, dict[str, Outcome]]:
    """:func:`sweep` on ``executor``'s workers; ``began``: the sweep's start (wall clock,
    CPU time of this process), s."""
    planning, start_cpu = began
    if campaign.outputs.columns and runs:  # a typo found before DIR is made, not after
        _check_columns(executor, runs[0])
    with claimed_output(out, campaign.lock_text(runs)):
        start = time.perf_counter()
        planning = start - planning
        outcomes: dict[str, Outcome] = {}
        for spec in runs:
            done = finished(out, spec.run_id)
            if done is not None:
                outcomes[spec.run_id] = done
        resumed = len(outcomes)
        todo = [s for s in runs if s.run_id not in outcomes]
        failed = 0
        bar = _progress(len(runs), resumed, quiet)
        busy = time.perf_counter() - start
        try:
            by_id = {s.run_id: s for s in todo}
            out_dir = str(out.resolve())
            # keys unique to this campaign and directory: a cluster is shared, and a key
            # another sweep submitted would hand this one that sweep's result
            tag = task_tag(todo, out_dir)
            keys = [f"brake-sim-{tag}-{s.run_id}" for s in todo]
            task = functools.partial(run_task, out_dir=out_dir)
            for outcome in executor.map(task, todo, keys) if todo else ():
                received = time.perf_counter()
                outcome = _checked(outcome, by_id, out)
                outcomes[outcome.run_id] = outcome
                if outcome.status == "ok":
                    _record(out, outcome)
                else:
                    failed += 1
                bar.set_postfix(failed=failed, refresh=False)
                bar.update(1)
                busy += time.perf_counter() - received
        except ExecutorError:
            _remove_partials(out)  # what a killed worker left: the directory is this sweep's
            raise
        finally:
            bar.close()
        import pyarrow.parquet as pq

        received = time.perf_counter()
        table = manifest_table(runs, outcomes)
        _write_whole(  # while the directory is still this sweep's
            out / MANIFEST_NAME, lambda partial: pq.write_table(table, partial, compression="zstd")
        )
        busy += time.perf_counter() - received
    cpu = sum(outcomes[s.run_id].cost_cpu_s for s in todo)
    simulated = sum(s.duration_s for s in todo if outcomes[s.run_id].status == "ok")
    summary = SweepSummary(
        runs=len(runs),
        done=sum(o.status == "ok" for o in outcomes.values()),
        failed=failed,
        resumed=resumed,
        wall_s=time.perf_counter() - start,
        cpu_s=cpu,
        simulated_s=simulated,
        parent_s=planning + busy,
        parent_cpu_s=time.process_time() - start_cpu,
    )
    return summary, outcomes


def _progress(total: int, initial: int, quiet: bool) -> Any:
    from tqdm import tqdm

    return tqdm(
        total=total,
        initial=initial,
        desc="runs",
        unit="run",
        file=sys.stderr,
        disable=quiet or not sys.stderr.isatty(),
        dynamic_ncols=True,
    )


__all__ = ["Outcome", "OutputError", "SweepError", "SweepSummary", "run_task", "sweep"]
