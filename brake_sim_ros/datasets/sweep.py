"""``brake-sim sweep``: run every run of a campaign and write a labelled, leak-free dataset.

The output directory ``DIR`` (its lock, one Parquet file per run, the manifest, the
finished runs' records) is :mod:`.sweep_output`'s. The same campaign gives the same bytes
in every file but the cost column of the manifest (CPU seconds, a measurement).

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
import functools
import hashlib
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from brake_sim_ros.datasets import life
from brake_sim_ros.datasets.executors import ExecutorError, one_line, open_executor, pool_context
from brake_sim_ros.datasets.orphans import die_with_parent
from brake_sim_ros.datasets.sweep_output import (
    MANIFEST_NAME,
    Outcome,
    SweepError,
    claimed_output,
    finished,
    manifest_table,
    record_outcome,
    remove_partials,
    run_file,
    sha256_file,
    write_whole,
)
from brake_sim_ros.datasets.threads import limit_threads
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.recording.mcap_format import describe_path
from brake_sim_ros.recording.output import OutputError, atomic_output

if TYPE_CHECKING:
    from brake_sim_ros.campaigns.campaign import Campaign, RunSpec
    from brake_sim_ros.datasets.executors import Executor


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
        # a campaign that keeps a few columns: the samples' others are never built
        wanted = set(spec.keep) if spec.keep else None
        table = run_table(scenario, result, scenario.duration_s, extra, wanted)
        if spec.keep:
            missing = [c for c in spec.keep if c not in table.column_names]
            if missing:
                written = dict.fromkeys([*table.column_names, *result.samples.columns])
                raise BrakeSimError(
                    f"outputs.columns: {missing[0]!r} is not a column of this run: allowed"
                    f" {list(written)[:60]}"
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
                    record_outcome(out, outcome)
                else:
                    failed += 1
                bar.set_postfix(failed=failed, refresh=False)
                bar.update(1)
                busy += time.perf_counter() - received
        except ExecutorError:
            remove_partials(out)  # what a killed worker left: the directory is this sweep's
            raise
        finally:
            bar.close()
        import pyarrow.parquet as pq

        received = time.perf_counter()
        table = manifest_table(runs, outcomes)
        write_whole(  # while the directory is still this sweep's
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
