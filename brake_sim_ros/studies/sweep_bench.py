"""Benchmark of ``brake-sim sweep``:
``brake-sim bench sweep [--campaign NAME] [--no-dask] [--out DIR]``.

Sweeps one campaign (default: the built-in ``demo``; ``short``: :data:`SHORT_CAMPAIGN`,
this benchmark's own campaign of 0.5 s runs, where the parent's work per run weighs
most) three times into fresh directories: a local pool of 1 worker, of 2 workers, and
(unless ``--no-dask``) a Dask ``LocalCluster`` of 2 single-threaded worker processes.
Prints, per configuration: wall time (the pool's includes forking its workers; the
pool's fork server and the cluster are started before the clock, their start times
printed apart), runs per hour, simulated seconds per wall second, the CPU seconds spent
in runs, the sweeping process's own work per run (wall time not waiting for a worker,
and its CPU time: :class:`~brake_sim_ros.datasets.sweep.SweepSummary`), and the largest
peak resident memory of a worker process; then the speed-up and scaling efficiency from
1 to 2 workers (rate at 2 / (2 x rate at 1)), the load average, and whether the datasets
are the same bytes (every file but the manifest's cost column).
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import pyarrow.parquet as pq

from brake_sim_ros.campaigns import load_campaign
from brake_sim_ros.campaigns.campaign import Campaign
from brake_sim_ros.campaigns.loader import parse_campaign
from brake_sim_ros.command_line import Parser
from brake_sim_ros.datasets.sweep import SweepSummary, start_pool_server, sweep
from brake_sim_ros.datasets.sweep_output import DONE_DIR, MANIFEST_NAME
from brake_sim_ros.datasets.threads import limit_threads

# 3 units x (every catalogue defect at two severities + healthy): short runs, one force
SHORT_CAMPAIGN = """
name = "short"
description = "bench sweep: every catalogue defect at two severities and healthy, 0.5 s runs"
base = "symmetric"
seed = 31
units = 3
[outputs]
duration_s = 0.5
sample_rate_hz = 5120.0
[[axes]]
defects = "all"
severities = [0.5, 1.0]
healthy = true
"""


def bench_campaign(name: str) -> Campaign:
    """``short`` (:data:`SHORT_CAMPAIGN`), else a built-in campaign or a .toml path."""
    if name == "short":
        return parse_campaign(SHORT_CAMPAIGN, "bench sweep's short campaign")
    return load_campaign(name)


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
        f"  parent {1e3 * summary.parent_s / summary.runs:5.1f} ms/run busy,"
        f" {1e3 * summary.parent_cpu_s / summary.runs:5.1f} ms/run CPU"
        f"  peak RSS/worker {rss_mb:6.0f} MB"
    )


def run(campaign_name: str, out: Path, *, dask: bool = True) -> str:
    campaign = bench_campaign(campaign_name)
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
    if dask:
        lines.extend(_dask(campaign, out / "dask-2"))
    one = results["local pool, 1 worker"][0]
    two = results["local pool, 2 workers"][0]
    efficiency = (one.wall_s / two.wall_s) / 2.0
    lines.append(
        f"  scaling 1 -> 2 workers: {one.wall_s / two.wall_s:.2f}x faster, efficiency"
        f" {100 * efficiency:.0f} %"
    )
    others = [out / "pool-2", *([out / "dask-2"] if dask else [])]
    same = all(_same(out / "pool-1", d) for d in others)
    lines.append(f"  load average after: {os.getloadavg()[0]:.1f} (1 min)")
    lines.append(
        f"  the {1 + len(others)} datasets are "
        + ("the same bytes (but the manifest's cost column)" if same else "NOT the same bytes")
    )
    return "\n".join(lines)


def _dask(campaign: Campaign, directory: Path) -> list[str]:
    """The campaign swept on a Dask LocalCluster of 2 single-threaded processes."""
    from distributed import LocalCluster

    start = time.perf_counter()
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        started = time.perf_counter() - start
        summary, outcomes = sweep(
            campaign, directory, scheduler=cluster.scheduler_address, quiet=True
        )
    rss = max(o.peak_rss_mb for o in outcomes.values())
    return [
        _line("Dask LocalCluster, 2 processes", summary, rss),
        f"    (the cluster started in {started:.1f} s, before the clock)",
    ]


def main(argv: list[str] | None = None) -> int:
    parser = Parser(prog="brake-sim bench sweep", description=__doc__.split("\n")[0])
    parser.add_argument(
        "--campaign",
        default="demo",
        help="built-in name or .toml (default demo); short: 135 runs of 0.5 s",
    )
    parser.add_argument("--no-dask", action="store_true", help="only the local pool")
    parser.add_argument("--out", type=Path, help="keep the three datasets under this new directory")
    args = parser.parse_args(argv)
    if args.out is not None:
        args.out.mkdir(parents=False, exist_ok=False)
        print(run(args.campaign, args.out, dask=not args.no_dask))
        return 0
    with tempfile.TemporaryDirectory(prefix="brake_sim_bench_sweep_") as tmp:
        print(run(args.campaign, Path(tmp), dask=not args.no_dask))
    return 0
