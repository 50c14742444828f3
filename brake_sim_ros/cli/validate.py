"""``brake-sim validate``: the validation study's cases against their published figures,
and its report."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from brake_sim_ros.cli.common import Command


def cmd_validate(args: argparse.Namespace) -> int:
    from brake_sim_ros.studies.validation import write_report

    out = Path(args.out)
    _fig, check_list = write_report(
        out,
        Path(args.json) if args.json else None,
        progress=lambda name: print(f"running {name}", file=sys.stderr),
    )
    passed = sum(c.passed for c in check_list)
    limits = sum(bool(c.model_limit) for c in check_list)
    for c in check_list:
        why = f" [beyond the model: {c.model_limit}]" if c.model_limit else ""
        print(
            f"{'ok  ' if c.passed else 'MISS'} {c.what}: published {c.published},"
            f" model {c.model} ({c.difference}){why}"
        )
    print(
        f"{passed}/{len(check_list)} checks within their bands"
        + (f", {limits} beyond the model (see the report's notes)" if limits else "")
        + f"; report: {out / 'report.md'}"
    )
    return 0


def validate_options(p: argparse.ArgumentParser) -> None:
    """``validate``'s options."""
    p.add_argument("--out", default="out/validation", help="report directory")
    p.add_argument("--json", help="also write the figures as JSON to this file")
    p.set_defaults(func=cmd_validate)


VALIDATE = Command(
    "validate", "run the study's cases and write the validation report", validate_options
)
