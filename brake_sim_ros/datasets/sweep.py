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
  written after the file; a resumed sweep skips a run whose record and file agree.

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
import hashlib
import json
import multiprocessing
import os
import re
import stat
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from brake_sim_ros.datasets import life
from brake_sim_ros.datasets.threads import limit_threads
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.recording.mcap_format import describe_path
from brake_sim_ros.recording.output import OutputError, atomic_output

if TYPE_CHECKING:
    from brake_sim_ros.campaigns.loader import Campaign, RunSpec

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
    runs: int
    done: int
    failed: int
    resumed: int
    wall_s: float
    cpu_s: float
    simulated_s: float

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
    limit_threads()
    import pyarrow

    pyarrow.set_cpu_count(1)  # Parquet encoding and compression in this thread's stead
    from brake_sim_ros.solvers.warmup import ensure_compiled

    ensure_compiled(say=lambda _line: None)


def pool_context() -> multiprocessing.context.BaseContext:
    """The local pool's process context: workers fork from one server process that
    imported and warmed the run path once (:mod:`.warm_worker`); none of this process's
    state is copied. The server starts on first use and serves every later pool of this
    process (:func:`start_pool_server` starts it ahead)."""
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["brake_sim_ros.datasets.warm_worker"])
    return context


def start_pool_server() -> None:
    """Start the pool's fork server now (it imports and warms the run path), e.g. to keep
    its start out of a measurement."""
    # a first fork waits for the server's imports and warm-up (ensure_running does not)
    with concurrent.futures.ProcessPoolExecutor(1, mp_context=pool_context()) as pool:
        pool.submit(int).result()


def run_file(run_id: str) -> str:
    """A run's file, relative to the output directory."""
    return f"{SAMPLES_DIR}/run={run_id}/{PART_NAME}"


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= 500 else text[:400] + " ... " + text[-60:]


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
            _one_line(exc)
            if isinstance(exc, BrakeSimError)
            else (f"{type(exc).__name__}: {_one_line(exc)}")
        )
        return Outcome(spec.run_id, "failed", error, time.process_time() - start)


def _rss_mb() -> float:
    """This process's peak resident set size, MB (Linux reports kB)."""
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


# --- the output directory -------------------------------------------------------------------
def prepare_output(out: Path, lock_text: str) -> None:
    """Check ``out`` and write its lock: a new directory (made with any missing parents),
    an empty one, or one holding this campaign's lock (resumed). Refused: a link, a non-directory,
    a directory with other files or another campaign's lock. Stale temporary files of a
    killed sweep are removed.

    Raises:
        SweepError: one line naming the directory.
    """
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
        if lock.read_bytes() != lock_text.encode():
            raise SweepError(
                f"--out {name} holds another campaign (or this one with another version of"
                f" brake-sim-ros): its {LOCK_NAME} differs; give a new directory"
            )
        _remove_partials(out)
        return
    if entries:
        raise SweepError(
            f"--out {name} is not empty and holds no {LOCK_NAME}: allowed a new or empty"
            " directory, or one of this campaign's sweeps (to resume it)"
        )
    with atomic_output(lock, option="--out") as partial:
        partial.write_text(lock_text, encoding="utf-8")


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
    with atomic_output(out / DONE_DIR / f"{outcome.run_id}.json", overwrite=True) as partial:
        partial.write_text(json.dumps(asdict(outcome), sort_keys=True), encoding="utf-8")


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
@contextlib.contextmanager
def _executor(
    workers: int, scheduler: str | None
) -> Iterator[Callable[[list[RunSpec], str], Iterator[Outcome]]]:
    """A function mapping run specs to outcomes as they finish: on a local process pool
    or on the Dask cluster at ``scheduler``."""
    if scheduler is None:
        context = pool_context()
        pool = concurrent.futures.ProcessPoolExecutor(
            max_workers=workers, mp_context=context, initializer=_init_worker
        )

        def run_local(specs: list[RunSpec], out_dir: str) -> Iterator[Outcome]:
            futures = [pool.submit(run_task, s, out_dir) for s in specs]
            try:
                for future in concurrent.futures.as_completed(futures):
                    yield future.result()
            except concurrent.futures.process.BrokenProcessPool:
                unfinished = sum(not f.done() or f.exception() is not None for f in futures)
                raise SweepError(
                    f"a worker process died (killed, or out of memory?) with {unfinished} runs"
                    " unfinished: the finished ones are kept; run the command again to resume"
                ) from None

        try:
            yield run_local
        except BaseException:  # Ctrl-C or a refusal: queued runs are dropped, not waited for
            pool.shutdown(wait=False, cancel_futures=True)
            raise
        pool.shutdown(wait=True)
        return
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise SweepError(
            "--scheduler needs dask.distributed: pip install 'dask[distributed]'"
        ) from None
    try:
        client = Client(scheduler, timeout=10)
    except (OSError, TimeoutError, ValueError) as exc:
        raise SweepError(f"--scheduler {scheduler}: cannot connect ({_one_line(exc)})") from None
    try:

        def run_dask(specs: list[RunSpec], out_dir: str) -> Iterator[Outcome]:
            futures = client.map(
                run_task,
                specs,
                out_dir=out_dir,
                pure=False,
                key=[f"brake-sim-{s.run_id}" for s in specs],
            )
            for future in as_completed(futures):
                yield future.result()

        yield run_dask
    finally:
        client.close()


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
    runs = campaign.runs()
    n_workers = workers or os.cpu_count() or 1
    # a scheduler that cannot be reached is refused before DIR is made or written
    with _executor(n_workers, scheduler) as execute:  # the pool forks as runs need workers
        prepare_output(out, campaign.lock_text(runs))
        start = time.perf_counter()
        outcomes: dict[str, Outcome] = {}
        for spec in runs:
            done = finished(out, spec.run_id)
            if done is not None:
                outcomes[spec.run_id] = done
        resumed = len(outcomes)
        todo = [s for s in runs if s.run_id not in outcomes]
        failed = 0
        bar = _progress(len(runs), resumed, quiet)
        try:
            for outcome in execute(todo, str(out.resolve())) if todo else ():
                outcomes[outcome.run_id] = outcome
                if outcome.status == "ok":
                    _record(out, outcome)
                else:
                    failed += 1
                bar.set_postfix(failed=failed, refresh=False)
                bar.update(1)
        finally:
            bar.close()
    import pyarrow.parquet as pq

    table = manifest_table(runs, outcomes)
    with atomic_output(out / MANIFEST_NAME, overwrite=True, option="--out") as partial:
        pq.write_table(table, partial, compression="zstd")
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
