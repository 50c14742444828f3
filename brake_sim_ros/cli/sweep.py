"""``brake-sim sweep`` and ``dataset``: a campaign run into a labelled Parquet dataset, and
what such a dataset holds."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from brake_sim_ros.cli.common import Command


def cmd_sweep(args: argparse.Namespace) -> int:
    """``brake-sim sweep CAMPAIGN --out DIR``: the campaign checked and planned before the
    directory is made; then every run, resuming a sweep of the same campaign there."""
    from brake_sim_ros.campaigns import load_campaign
    from brake_sim_ros.datasets.executors import check_workers
    from brake_sim_ros.datasets.sweep import sweep

    if args.workers is not None:
        check_workers(args.workers)
    campaign = load_campaign(args.campaign)
    summary, outcomes = sweep(
        campaign, Path(args.out), workers=args.workers, scheduler=args.scheduler, quiet=args.quiet
    )
    print(summary.describe(Path(args.out)))
    if summary.failed:
        first = next(o for o in outcomes.values() if o.status == "failed")
        print(
            f"brake-sim: error: {summary.failed} run(s) failed (errors in the manifest), the"
            f" first: {first.run_id}: {first.error}",
            file=sys.stderr,
        )
        return 1
    return 0


def cmd_dataset(args: argparse.Namespace) -> int:
    """``brake-sim dataset info DIR``: class balance per split, after the leakage and
    damage checks (non-zero exit with one line on either)."""
    from brake_sim_ros.datasets.reader import info_text, open_dataset

    print(info_text(open_dataset(args.directory)))
    return 0


def sweep_options(p: argparse.ArgumentParser) -> None:
    """``sweep``'s description and options."""
    p.description = (
        "Run every run of a campaign into DIR: manifest.parquet, samples/run=*/"
        " (Parquet, hive-partitioned), campaign.lock. Running it again resumes: finished runs"
        " whose files check out are skipped. DIR must be new, empty, or this campaign's."
    )
    p.add_argument(
        "campaign", help="built-in campaign name (demo, reference, reference_study) or .toml path"
    )
    p.add_argument("--out", required=True, metavar="DIR", help="output directory")
    p.add_argument(
        "--workers", type=int, metavar="N", help="local worker processes (default: every core)"
    )
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on an existing Dask cluster (tcp://host:8786) whose workers share DIR",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_sweep)


def dataset_options(p: argparse.ArgumentParser) -> None:
    """``dataset``'s own commands: ``info``."""
    dataset_sub = p.add_subparsers(dest="dataset_command", required=True)
    q = dataset_sub.add_parser(
        "info", help="runs, units and class balance per split; checks leakage and damage"
    )
    q.add_argument("directory", help="a sweep's output directory")
    q.set_defaults(func=cmd_dataset)


SWEEP = Command(
    "sweep",
    "run a campaign (built-in name or .toml) into a labelled, leak-free Parquet"
    " dataset: brake-sim sweep demo --out DIR",
    sweep_options,
)
DATASET = Command(
    "dataset", "inspect a sweep's dataset: brake-sim dataset info DIR", dataset_options
)
