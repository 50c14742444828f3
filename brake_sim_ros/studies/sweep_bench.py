"""Benchmark of ``brake-sim sweep``: ``brake-sim bench sweep [--campaign NAME] [--out DIR]``.

Sweeps one campaign (default: the built-in ``demo``) three times into fresh directories:
a local pool of 1 worker, of 2 workers, and a Dask ``LocalCluster`` of 2 single-threaded
worker processes. Prints, per configuration: wall time (the pool's includes forking its
workers; the pool's fork server and the cluster are started before the clock, their
start times printed apart), runs per hour, simulated seconds per wall second, the CPU
seconds spent in runs, and the largest peak resident memory of a worker process; then
the scaling efficiency from 1 to 2 workers (rate at 2 / (2 x rate at 1)), the load
average, and whether the three datasets are the same bytes (every file but the
manifest's cost column).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import pyarrow.parquet as pq

from brake_sim_ros.campaigns import load_campaign
from brake_sim_ros.datasets.sweep import (
    DONE_DIR,
    MANIFEST_NAME,
    SweepSummary,
    start_pool_server,
    sweep,
)
from brake_sim_ros.datasets.threads import limit_threads


def _files(root: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(root)): p.read_bytes()
        for p in sorted(root.rglob("*"))
        if p.is_file() and DONE_DIR not in p.parts and p.name != MANIFEST_NAME
    }


def _same(a: Path, b: Path) -> bool:
    manifest = [pq.read_table(d / MANIFEST_NAME).drop_columns(["cost_cpu_s"]) for d in (a, b)]
    return _files(a) == _files(b) and manifest[0].equals(manifest[1])


def _line(label: str, summary: SweepSummary, rss_mb: float) -> str:
    wall = summary.wall_s
    return (
        f"  {label:34s} {wall:7.1f} s wall  {3600 * summary.runs / wall:9.0f} runs/h"
        f"  {summary.simulated_s / wall:6.2f} sim s/wall s  {summary.cpu_s:7.1f} s CPU in runs"
        f"  peak RSS/worker {rss_mb:6.0f} MB"
    )


def run(campaign_name: str, out: Path) -> str:
    campaign = load_campaign(campaign_name)
    n_runs = len(campaign.runs())
    limit_threads()  # the Dask workers below inherit one thread each, as the pool's do
    lines = [
        f"brake-sim bench sweep: campaign {campaign.name}, {n_runs} runs, on"
        f" {os.cpu_count()} cores (os.cpu_count); load average before"
        f" {os.getloadavg()[0]:.1f} (a loaded machine slows and flattens every figure)"
    ]
    results: dict[str, tuple[SweepSummary, Path]] = {}
    start = time.perf_counter()
    start_pool_server()  # once per process: started before the clock, as the cluster is
    lines.append(
        f"  (the pool's fork server, which loads the kernels once, started in"
        f" {time.perf_counter() - start:.1f} s, before the clock)"
    )
    for workers in (1, 2):
        directory = out / f"pool-{workers}"
        summary, outcomes = sweep(campaign, directory, workers=workers, quiet=True)
        rss = max(o.peak_rss_mb for o in outcomes.values())
        label = f"local pool, {workers} worker{'s' * (workers > 1)}"
        lines.append(_line(label, summary, rss))
        results[label] = (summary, directory)
    from distributed import LocalCluster

    start = time.perf_counter()
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        started = time.perf_counter() - start
        directory = out / "dask-2"
        summary, outcomes = sweep(
            campaign, directory, scheduler=cluster.scheduler_address, quiet=True
        )
    rss = max(o.peak_rss_mb for o in outcomes.values())
    lines.append(_line("Dask LocalCluster, 2 processes", summary, rss))
    lines.append(f"    (the cluster started in {started:.1f} s, before the clock)")
    one = results["local pool, 1 worker"][0]
    two = results["local pool, 2 workers"][0]
    efficiency = (one.wall_s / two.wall_s) / 2.0
    lines.append(
        f"  scaling 1 -> 2 workers: {one.wall_s / two.wall_s:.2f}x, efficiency"
        f" {100 * efficiency:.0f} %"
    )
    same = all(_same(out / "pool-1", d) for d in (out / "pool-2", directory))
    lines.append(f"  load average after: {os.getloadavg()[0]:.1f} (1 min)")
    lines.append(
        "  the three datasets are "
        + ("the same bytes (but the manifest's cost column)" if same else "NOT the same bytes")
    )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="brake-sim bench sweep", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--campaign", default="demo", help="built-in name or .toml (default demo)")
    parser.add_argument("--out", type=Path, help="keep the three datasets under this new directory")
    args = parser.parse_args(argv)
    if args.out is not None:
        args.out.mkdir(parents=False, exist_ok=False)
        print(run(args.campaign, args.out))
        return 0
    with tempfile.TemporaryDirectory(prefix="brake_sim_bench_sweep_") as tmp:
        print(run(args.campaign, Path(tmp)))
    return 0
