"""The 10,000-run campaign, swept and scored: ``brake-sim bench fleet [--full] [--out DIR]``.

:data:`CAMPAIGN_FILE` (``fleet10k``, on the service brake: every defect kind it carries
but the pivot radius at three severities and a healthy brake, eight drawn forces, twenty
units; 11,680 runs of 1.2 s at 25.6 kHz keeping the default sensors' measured channels)
is swept on a local pool, then the ``impact``
baseline (the best of the reference campaign's scores) is fitted on its train split and
scored on its test split. Prints the wall time of each phase, runs per second, the disk
the dataset takes and the score's headline figures.

Without ``--full`` a slice runs: the same file with its first ``--units`` units (default
8) and ``--draws`` forces (default 1): 584 runs of the same length, rate, columns, defects
and severities. Its figures are then extrapolated to the whole campaign at the slice's
rate per run, and printed as an extrapolation.
"""

from __future__ import annotations

import dataclasses
import os
import tempfile
import time
from pathlib import Path

from brake_sim_ros.campaigns import load_campaign
from brake_sim_ros.campaigns.axes import condition_points
from brake_sim_ros.campaigns.campaign import Campaign
from brake_sim_ros.command_line import Parser
from brake_sim_ros.datasets.executors import check_workers
from brake_sim_ros.datasets.sweep import start_pool_server, sweep
from brake_sim_ros.errors import BrakeSimError

CAMPAIGN_FILE = Path(__file__).with_name("fleet10k.toml")
DETECTOR = "impact"


def run_count(campaign: Campaign) -> int:
    """How many runs ``campaign`` has, without planning them (held-out rules skip some
    runs on non-test units: those are counted by planning)."""
    if campaign.held_out:
        return len(campaign.runs())
    points = condition_points(
        campaign.axes, campaign.draw_method, campaign.draw_count, campaign.seed
    )
    return len(points) * len(campaign.unit_ids)


def _disk_bytes(root: Path) -> int:
    return sum(p.stat().st_size for p in root.rglob("*") if p.is_file() and not p.is_symlink())


# the smallest slice whose train split gives the baseline its three healthy training stops
MIN_UNITS = 5


def sliced(campaign: Campaign, units: int, draws: int) -> Campaign:
    """``campaign`` on its first ``units`` units with ``draws`` drawn points."""
    if not MIN_UNITS <= units <= len(campaign.unit_ids):
        raise BrakeSimError(
            f"bench fleet --units {units}: allowed {MIN_UNITS} to {len(campaign.unit_ids)}"
            f" (fewer leave the {DETECTOR} baseline under three healthy training stops)"
        )
    if not 1 <= draws <= campaign.draw_count:
        raise BrakeSimError(f"bench fleet --draws {draws}: allowed 1 to {campaign.draw_count}")
    return dataclasses.replace(campaign, unit_ids=campaign.unit_ids[:units], draw_count=draws)


def _score(directory: Path) -> tuple[float, str]:
    """Fit the baseline on train, score it on test: (wall s, one line of figures)."""
    from brake_sim_ros.datasets.reader import open_dataset
    from brake_sim_ros.detection import evaluate
    from brake_sim_ros.detection.registry import make_detector

    start = time.perf_counter()
    dataset = open_dataset(directory)
    detector = make_detector(DETECTOR)
    windows = evaluate.fit(detector, dataset, "train")
    score = evaluate.score(detector, dataset, "test")
    took = time.perf_counter() - start
    d, hi = score["detection"], score["health_index"]
    auroc = hi.get("auroc")
    line = (
        f"{DETECTOR} fitted on train ({windows} windows), scored on test: {score['runs']} runs,"
        f" detected {d['detected']} of {d['defective_runs']} defective, window AUROC "
        + ("undefined" if auroc is None else f"{auroc:.3f}")
    )
    return took, line


def run(campaign: Campaign, full_runs: int, out: Path, workers: int) -> str:
    """Sweep and score ``campaign`` into ``out``; the report's lines."""
    lines = [
        f"brake-sim bench fleet: {CAMPAIGN_FILE.name}, on {os.cpu_count()} cores, {workers}"
        f" workers; load average before {os.getloadavg()[0]:.1f} (other jobs slow every figure)"
    ]
    start = time.perf_counter()
    start_pool_server()
    lines.append(f"  pool's fork server started in {time.perf_counter() - start:.1f} s")
    start = time.perf_counter()
    summary, _ = sweep(campaign, out, workers=workers, quiet=True)
    swept = time.perf_counter() - start
    disk = _disk_bytes(out)
    lines.append(
        f"  sweep: {summary.runs} runs ({summary.failed} failed) in {swept:.1f} s wall"
        f" ({summary.runs / swept:.2f} runs/s; planning and the parent's own work"
        f" {summary.parent_s:.1f} s, {1e3 * summary.parent_s / summary.runs:.1f} ms/run);"
        f" {summary.cpu_s:.0f} s CPU in runs; disk {disk / 1e6:.0f} MB"
        f" ({disk / summary.runs / 1e3:.0f} kB/run)"
    )
    scored, figures = _score(out)
    lines.append(f"  score: {scored:.1f} s wall; {figures}")
    total = swept + scored
    lines.append(f"  total {total:.1f} s wall ({summary.runs / total:.2f} runs/s swept and scored)")
    factor = full_runs / summary.runs
    if summary.runs != full_runs:
        lines.append(
            f"  EXTRAPOLATED to all {full_runs} runs at this slice's rate per run (not"
            f" measured): sweep {swept * factor / 60:.0f} min, score {scored * factor / 60:.0f}"
            f" min, total {total * factor / 60:.0f} min; disk {disk * factor / 1e9:.1f} GB"
        )
    # the CPU the runs took is what a machine free of other jobs would spend on them
    bound = factor * max(summary.cpu_s / workers, summary.parent_s)
    lines.append(
        f"  the runs' CPU time over {workers} workers, for all {full_runs} runs:"
        f" {bound / 60:.0f} min (the sweep's floor on a machine free of other jobs;"
        " EXTRAPOLATED where a slice ran)"
    )
    lines.append(f"  load average after: {os.getloadavg()[0]:.1f} (1 min)")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = Parser(prog="brake-sim bench fleet", description=__doc__.split("\n")[0])
    parser.add_argument("--full", action="store_true", help="every run of the campaign")
    parser.add_argument("--units", type=int, default=8, help="slice: units (default 8)")
    parser.add_argument("--draws", type=int, default=1, help="slice: drawn forces (default 1)")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--out", type=Path, help="keep the dataset in this new directory")
    args = parser.parse_args(argv)
    check_workers(args.workers)
    campaign = load_campaign(CAMPAIGN_FILE)
    full_runs = run_count(campaign)
    if not args.full:
        campaign = sliced(campaign, args.units, args.draws)
    if args.out is not None:
        if args.out.exists():
            raise BrakeSimError(f"bench fleet --out {args.out} exists: give a new path")
        print(run(campaign, full_runs, args.out, args.workers))
        return 0
    with tempfile.TemporaryDirectory(prefix="brake_sim_bench_fleet_") as tmp:
        print(run(campaign, full_runs, Path(tmp) / "fleet", args.workers))
    return 0
