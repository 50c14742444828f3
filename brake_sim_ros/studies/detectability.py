"""The detectability floor: per defect kind, the smallest severity the baselines detect on
brakes they were not trained on, at a stated false-alarm rate.

``brake-sim bench detectability --out DIR [--brake B] [--units N] [--duration S]
[--detectors A,B] [--false-alarm F] [--workers N]``

1. A campaign (:func:`campaign_text`, swept into ``DIR``; a rerun resumes it) on the
   ``--brake`` (default ``service``; ``study`` for the study brake's table): every kind
   of that brake's catalogue (the line's on the service brake only) at each of its
   locations, at :data:`FRACTIONS` of its service limit (``brake-sim defects``), one
   defect per run, and a healthy brake; :data:`FORCES` actuation forces (the healthy
   reference needs more than one healthy run per unit); ``--units`` units (default 6),
   whole units to train (2/3) and test (1/3); ``--duration`` s runs (default 2: the order
   detector judges the quiet sliding after the impacts, from about 1.2 s) at 5120 Hz
   keeping the measured channels and the labels only.
2. Each detector (default ``orders``, ``impact`` and ``learned``) is fitted on the train
   units. Its alarm threshold is then set on healthy training data at the stated
   false-alarm rate: the ``1 - F`` quantile (default F = 0.01) of the health index over
   healthy training windows (the detector's own ``healthy_index`` where it keeps one: the
   learned baseline's is out of fold, the impact baseline's is its healthy training stops
   judged out of unit; else its assessments of the healthy training runs).
3. On the test units, a defective run is detected when an alarm is held 0.2 s at or
   after its onset (:mod:`brake_sim_ros.detection.metrics`). The table gives, per kind
   (its locations together) and detector, the detected share at each fraction, and the
   floor: the smallest fraction from which on at least half of the runs are detected at
   every larger fraction too. False alarms per hour of the healthy test runs are printed.
"""

from __future__ import annotations

import math
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

from brake_sim_ros.campaigns.loader import parse_campaign
from brake_sim_ros.command_line import Parser
from brake_sim_ros.datasets import open as open_dataset
from brake_sim_ros.datasets.sweep import sweep
from brake_sim_ros.detection import evaluate, metrics
from brake_sim_ros.detection.registry import make_detector
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.model.catalogue import KIND_BY_NAME, KINDS, brake_kinds
from brake_sim_ros.model.parameters import BRAKES

FRACTIONS = (0.1, 0.2, 0.35, 0.5, 0.75, 1.0)  # of each kind's service limit
FORCES = (1150.0, 1400.0)  # N per shoe, around the published 1300 N
SAMPLE_RATE_HZ = 5120.0
HOLD_S = 0.2
DETECTED_SHARE = 0.5  # a fraction is detected when at least this share of its runs is
DEFAULT_BRAKE = "service"  # the drive cycles' and campaigns' brake; "study" on request
# kinds a brake's campaign leaves out, and why (printed under the table)
LEFT_OUT = {
    "service": {
        "pivot_radius_change": "from half its service limit (+1.5 %, the study's cases on a"
        " 3.63 mm clearance) its lining starts inside the drum of the service brake's 0.3 mm"
        " clearance, which the scenario loader refuses",
    },
    "study": {},
}


def study_kinds(brake: str) -> list[str]:
    """The kinds the study runs on ``brake``: every kind it can carry (the line's on the
    service brake only) but those it leaves out (:data:`LEFT_OUT`)."""
    return [k.name for k in brake_kinds(brake == "service") if k.name not in LEFT_OUT[brake]]


def campaign_text(units: int, duration_s: float, seed: int = 16, brake: str = DEFAULT_BRAKE) -> str:
    """The study's campaign (module docstring) as TOML, on ``brake``."""
    kinds = ", ".join(f'"{k}"' for k in study_kinds(brake))
    fractions = ", ".join(f"{f:g}" for f in FRACTIONS)
    forces = ", ".join(f"{f:g}" for f in FORCES)
    return f"""# brake-sim bench detectability on the {brake} brake: every defect kind it
# carries (but those the study leaves out) at {len(FRACTIONS)} fractions of its service
# limit and a healthy brake, {len(FORCES)} forces, {units} units
name = "detectability"
description = "The detectability floor's study (brake_sim_ros/studies/detectability.py)"
base = "symmetric"
brake = "{brake}"
seed = {seed}
units = {units}

[outputs]
duration_s = {duration_s:g}
sample_rate_hz = {SAMPLE_RATE_HZ:g}
columns = [
    "measured:backing_plate_accel_x [m/s^2]",
    "measured:backing_plate_accel_y [m/s^2]",
    "measured:wheel_speed [1]",
    "measured:wheel_speed_index [1]",
    "measured:line_pressure [bar]",
]

[[axes]]
defects = [{kinds}]
severities = [{fractions}]
healthy = true

[[axes]]
name = "peak_force_n"
key = "actuation.peak_force_n"
values = [{forces}]

[split]
train = 0.67
test = 0.33
"""


def thresholds(detector, dataset, false_alarm: float) -> float:
    """The health index above which ``detector`` (fitted) alarms at the stated rate."""
    healthy = np.asarray(getattr(detector, "healthy_index", np.zeros(0)), dtype=np.float64)
    if healthy.size == 0:  # no kept reference: its assessments of the healthy train runs
        values = []
        for run_id in dataset.runs("train"):
            run = evaluate.read_run(dataset, run_id)
            if run.onset_index is None:
                values += [a.health_index for a in evaluate.assess_run(detector, run, 0.1)]
        healthy = np.asarray(values, dtype=np.float64)
    if healthy.size == 0:
        raise BrakeSimError(f"detector {detector.name}: no healthy training windows")
    return float(np.quantile(healthy, 1.0 - false_alarm))


def run_study(dataset, names: list[str], false_alarm: float) -> dict:
    """Fit, threshold and score each detector (module docstring); the results as data."""
    info = {r["run_id"]: r for r in dataset.manifest.to_pylist()}
    ran = {r["defect_kind"] for r in info.values()} - {"healthy"}
    out: dict = {"false_alarm": false_alarm, "kinds": sorted(ran), "detectors": {}}
    for name in names:
        detector = make_detector(name)
        evaluate.fit(detector, dataset, "train")
        threshold = thresholds(detector, dataset, false_alarm)
        counts: dict[tuple[str, float], list[int]] = defaultdict(lambda: [0, 0])
        fa_count, fa_hours = 0, 0.0
        for run_id in dataset.runs("test"):
            run = evaluate.read_run(dataset, run_id)
            found = evaluate.assess_run(detector, run, 0.1)
            if not found:
                continue
            rows = np.array([a.sample_index for a in found])
            times = run.time_s[rows]
            alarm = np.array([a.health_index >= threshold for a in found])
            kind = info[run_id]["defect_kind"]
            if run.onset_index is None:
                c, h = metrics.false_alarms_per_hour(alarm, times, np.ones_like(alarm), HOLD_S)
                fa_count, fa_hours = fa_count + c, fa_hours + h
                continue
            limit = KIND_BY_NAME[kind].service_limit
            fraction = round(float(info[run_id]["defect_severity"]) / limit, 6)
            onset_s = float(run.time_s[run.onset_index])
            detected = metrics.detection_delay(alarm, times, onset_s, HOLD_S) is not None
            counts[(kind, fraction)][0] += int(detected)
            counts[(kind, fraction)][1] += 1
        out["detectors"][name] = {
            "threshold": threshold,
            "false_alarms": fa_count,
            "healthy_hours": fa_hours,
            "counts": {f"{k}@{f:g}": v for (k, f), v in sorted(counts.items())},
        }
    return out


def floor(shares: dict[float, float]) -> float | None:
    """The smallest fraction from which on every fraction is detected (module docstring)."""
    best = None
    for fraction in sorted(shares, reverse=True):
        if shares[fraction] < DETECTED_SHARE:
            break
        best = fraction
    return best


def table(result: dict, brake: str | None = None) -> str:
    """The markdown table: per kind and detector, the floor and the share at each fraction;
    the kinds ``brake``'s study leaves out (:data:`LEFT_OUT`) named under it."""
    names = list(result["detectors"])
    lines = [
        "| defect (service limit) | detector | floor (fraction, size) | "
        + " | ".join(f"detected at {f:g}" for f in FRACTIONS)
        + " |",
        "|---|---|---|" + "---|" * len(FRACTIONS),
    ]
    # the kinds the campaign ran (a kind it did not run is no row, not "not detected");
    # a result without them: every kind but the service brake's own, unless counted
    carried = {key.split("@")[0] for n in names for key in result["detectors"][n]["counts"]}
    ran = set(result.get("kinds", ())) or {k.name for k in KINDS if not k.service_only}
    for kind in (k for k in KINDS if k.name in ran | carried):
        for name in names:
            counts = result["detectors"][name]["counts"]
            shares, cells = {}, []
            for f in FRACTIONS:
                hit, total = counts.get(f"{kind.name}@{f:g}", (0, 0))
                if total:
                    shares[f] = hit / total
                cells.append(f"{hit}/{total}" if total else "-")
            low = floor(shares)
            where = (
                "not detected"
                if low is None
                else f"{low:g} ({low * kind.service_limit:g} {kind.unit})"
            )
            lines.append(
                f"| {kind.name} ({kind.service_limit:g} {kind.unit}) | {name} | {where} | "
                + " | ".join(cells)
                + " |"
            )
    for name in names:
        d = result["detectors"][name]
        rate = d["false_alarms"] / d["healthy_hours"] if d["healthy_hours"] > 0 else math.nan
        lines.append(
            f"\n{name}: threshold {d['threshold']:.4g} (health index), {d['false_alarms']} false"
            f" alarms in {d['healthy_hours'] * 3600:.1f} s of healthy test runs"
            f" ({rate:.3g} per hour)"
        )
    for kind, why in LEFT_OUT.get(brake, {}).items():
        lines.append(f"\n{kind}: not run on the {brake} brake: {why}")
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    parser = Parser(prog="brake-sim bench detectability", description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="the study's dataset directory")
    parser.add_argument(
        "--brake",
        default=DEFAULT_BRAKE,
        help=f"the brake: {' or '.join(BRAKES)} (default {DEFAULT_BRAKE})",
    )
    parser.add_argument("--units", type=int, default=6, help="units (default 6: 4 train, 2 test)")
    parser.add_argument("--duration", type=float, default=2.0, help="run length, s (default 2)")
    parser.add_argument("--detectors", default="orders,impact,learned", help="comma-separated")
    parser.add_argument(
        "--false-alarm",
        type=float,
        default=0.01,
        help="healthy training windows over the threshold (default 0.01)",
    )
    parser.add_argument("--workers", type=int, default=None, help="local workers")
    args = parser.parse_args(argv)
    if args.brake not in BRAKES:
        raise BrakeSimError(f"--brake {args.brake!r}: allowed one of {list(BRAKES)}")
    if not 3 <= args.units <= 100:
        raise BrakeSimError(f"--units {args.units}: allowed 3 to 100")
    if not 0.5 <= args.duration <= 10.0:
        raise BrakeSimError(f"--duration {args.duration!r}: allowed 0.5 to 10 s")
    if not 0.0 < args.false_alarm < 0.5:
        raise BrakeSimError(f"--false-alarm {args.false_alarm!r}: allowed between 0 and 0.5")
    out = Path(args.out)
    campaign = parse_campaign(
        campaign_text(args.units, args.duration, brake=args.brake), "detectability"
    )
    start = time.monotonic()
    sweep(campaign, out, workers=args.workers)
    swept = time.monotonic() - start
    dataset = open_dataset(out)
    names = [n for n in args.detectors.split(",") if n]
    try:
        result = run_study(dataset, names, args.false_alarm)
    except (ValueError, RuntimeError) as exc:
        raise BrakeSimError(" ".join(str(exc).split())) from None
    print(
        f"detectability on the {args.brake} brake: {len(dataset.runs('train'))} train and"
        f" {len(dataset.runs('test'))} test runs of {args.duration:g} s at"
        f" {SAMPLE_RATE_HZ:g} Hz, {args.units} units, forces"
        f" {', '.join(f'{f:g}' for f in FORCES)} N; swept in {swept:.0f} s, scored in"
        f" {time.monotonic() - start - swept:.0f} s; threshold at {args.false_alarm:g} of"
        f" healthy training windows; a fraction is detected when >= {DETECTED_SHARE:g} of its"
        f" test runs raise an alarm held {HOLD_S:g} s after the onset\n"
    )
    print(table(result, args.brake))
    return 0
