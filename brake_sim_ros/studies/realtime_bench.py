"""``brake-sim bench realtime``: worst-case wall cost of one streaming chunk.

Runs a scenario through the streaming stepper in chunks, as the ROS node does (default:
the scenario's sample rate, 25.6 kHz, and 256 samples per chunk = the node's 100 Hz chunk
rate), times every
``advance`` call with the monotonic performance counter, and prints the distribution
(median, p99, p99.9, max) per regime of the chunk (impacting, contact, stopped, free)
and overall, against the chunk's wall period at real-time factor 1 and the stepper's
share of it (:data:`brake_sim_ros.solvers.realtime.STEPPER_SHARE`). Then the
start-up calibration the node runs, with its verdict.
"""

from __future__ import annotations

import time

import numpy as np

from brake_sim_ros.command_line import Parser
from brake_sim_ros.model import layout as L
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.solvers.realtime import (
    STEPPER_SHARE,
    CostStats,
    calibrate_chunk_cost,
    check_realtime,
)
from brake_sim_ros.stream import parameters as ros_params
from brake_sim_ros.stream.build import stepper_for


def _regime_of(block) -> str:
    regimes = block["regime"]
    if np.any(regimes == L.REGIME_IMPACTING):
        return "impacting"
    if np.any(regimes == L.REGIME_CONTACT):
        return "contact"
    if np.all(regimes == L.REGIME_STOPPED):
        return "stopped"
    return "free"


def main(argv: list[str] | None = None) -> int:
    parser = Parser(prog="brake-sim bench realtime", description=__doc__)
    parser.add_argument("--scenario", default="symmetric")
    parser.add_argument("--chunk-samples", type=int, default=256, help="samples per chunk")
    parser.add_argument("--repeats", type=int, default=4, help="whole events to run")
    parser.add_argument("--real-time-factor", type=float, default=1.0)
    parser.add_argument("--preset", help="solver preset (default: the scenario's)")
    args = parser.parse_args(argv)
    scenario = load_scenario(args.scenario).with_solver(preset=args.preset)
    stepper = stepper_for(scenario)
    dt = stepper.sample_period_s
    n = args.chunk_samples
    period = n * dt / args.real_time_factor
    budget = STEPPER_SHARE * period
    by_regime: dict[str, list[float]] = {}
    chunks = round(scenario.duration_s / dt) // n
    stepper.advance(1)  # load the compiled kernel
    for _ in range(args.repeats):
        stepper.reset()
        for _ in range(chunks):
            t0 = time.perf_counter()
            block = stepper.advance(n)
            cost = time.perf_counter() - t0
            by_regime.setdefault(_regime_of(block), []).append(cost)
    print(
        f"scenario {scenario.name}: {stepper.describe_step()}; {n} samples per chunk,"
        f" {args.repeats} events of {scenario.duration_s:g} s; chunk wall period at"
        f" real_time_factor {args.real_time_factor:g}: {1e6 * period:.0f} us, stepper share"
        f" {100 * STEPPER_SHARE:.0f} % = {1e6 * budget:.0f} us"
    )
    print()
    print("regime | chunks | median (us) | p99 (us) | p99.9 (us) | max (us) | max / budget")
    print("---|---|---|---|---|---|---")
    everything = [c for costs in by_regime.values() for c in costs]
    rows = [(name, by_regime[name]) for name in sorted(by_regime)] + [("all", everything)]
    for name, costs in rows:
        s = CostStats.of(np.asarray(costs))
        print(
            f"{name} | {s.n_chunks} | {1e6 * s.median_s:.1f} | {1e6 * s.p99_s:.1f} |"
            f" {1e6 * s.p999_s:.1f} | {1e6 * s.max_s:.1f} | {s.max_s / budget:.3f}"
        )
    overall = CostStats.of(np.asarray(everything))
    print(
        f"\nper sample: median {1e9 * overall.median_s / n:.0f} ns,"
        f" worst {1e9 * overall.max_s / n:.0f} ns; the worst chunk allows real_time_factor up to"
        f" {STEPPER_SHARE * n * dt / overall.max_s:.3g}, the median up to"
        f" {STEPPER_SHARE * n * dt / overall.median_s:.3g}"
    )
    t0 = time.perf_counter()
    force = ros_params.auto_max_actuation_force(scenario.setup)  # the node's default
    cal = calibrate_chunk_cost(stepper.fresh(), n, force_n=force)
    wall = time.perf_counter() - t0
    verdict = check_realtime(
        cal.median_s,
        sample_period_s=dt,
        chunk_samples=n,
        real_time_factor=args.real_time_factor,
        label=f"scenario '{scenario.name}'",
    )
    print(
        f"start-up calibration: {cal.n_chunks} chunks in {1e3 * wall:.1f} ms of wall time"
        f" (stepper construction included), driven at {force:g} N, median"
        f" {1e6 * cal.median_s:.1f} us per chunk ({cal.median_s / overall.median_s:.2f} x the"
        " event's median)"
    )
    print(f"verdict: {'ok' if verdict.ok else 'REFUSE'}: {verdict.message}")
    return 0
