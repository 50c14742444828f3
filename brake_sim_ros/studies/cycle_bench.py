"""``brake-sim bench cycle``: a drive cycle's cost offline, and its energy books.

The cycle scenario (default ``urban``) on its brake or the one ``--brake`` names (study or
service: the scenario with its top-level ``brake`` key set so) at its preset (``--preset``,
default the scenario's: balanced) is stepped in chunks of ``--chunk-s`` simulated seconds,
recording every sample, and its default sensor set (structure and channels, carrying their
state from chunk to chunk as the node's measured stream does) processes every chunk; memory
stays bounded by a chunk. Printed, best of ``--repeats`` (process CPU time, one core; the
runs with and without sensors alternate, so a change of the machine's load hits both): the
physics alone and physics plus sensors as multiples of real time, the latter split into the
stepping, the sensors and the rest (the loop's own work; the benchmark's own records of
segments are not counted), and each run's figure; then the issue's figure on one line (the
cycle with the default sensors: its target, 30x real time, and its goal, 50x, each met or
not), the stops and phases the cycle went
through, and the energy books over the whole cycle (drive work in against the losses, road
load and the change of stored energy; :func:`brake_sim_ros.analysis.energy.energy_balance`);
and what the vehicle costs per sample where the shoes ride free (4 s without braking,
recording every sample): the published model, the same with a ``[vehicle]`` (road load), and
with a ``[cycle]`` (road load and the controller), on the ``--brake`` named.
"""

from __future__ import annotations

import math
import time

import numpy as np

from brake_sim_ros.analysis.energy import energy_balance
from brake_sim_ros.command_line import Parser
from brake_sim_ros.model.parameters import BRAKES
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.scenarios import load_scenario, on_brake, parse_scenario
from brake_sim_ros.solvers.realtime import MAX_CHUNK_SAMPLES
from brake_sim_ros.stream.build import sensor_bank_for, stepper_for

TARGET_RTF = 30.0
GOAL_RTF = 50.0  # with the default sensors (issue 31)
CHUNK_RANGE_S = (0.001, 1.0)  # simulated s per chunk: the node's 10 ms lies inside
MAX_REPEATS = 20
# free-rolling runs for the vehicle's cost: no brake force, shoes off the drum
_FREE = 'name = "free"\n[actuation]\npeak_force_n = 0.0\n'
_OVERHEAD_CASES = (
    ("published model", _FREE),
    ("with [vehicle] (road load)", _FREE + "[vehicle]\n"),
    (
        "with [cycle] (road load, controller)",
        'name = "free"\n[parameters.driveline]\ninitial_speed_rad_s = 0.0\n'
        '[[cycle.segments]]\nkind = "accelerate"\nkmh = 100.0\n',
    ),
)


def _run(scenario, chunk_samples: int, with_sensors: bool):
    """CPU seconds of one chunked run (whole, stepping, sensors), the first and last
    sample, and the segments seen."""
    stepper = stepper_for(scenario)
    bank = sensor_bank_for(scenario) if with_sensors else None
    total = round(scenario.duration_s / stepper.sample_period_s)
    first = last = None
    segments: list[float] = []
    stepping = sensing = bookkeeping = 0.0
    clock = time.process_time
    start = clock()
    while stepper.sample_index < total:
        t0 = clock()
        block = stepper.advance(min(chunk_samples, total - stepper.sample_index))
        t1 = clock()
        stepping += t1 - t0
        if bank is not None:
            bank.advance(block)
            sensing += clock() - t1
        t2 = clock()  # the benchmark's own records, not the run's work: not counted
        if first is None:
            first = SampleBlock(block.data[:1].copy(), 0, block.sample_period_s)
        seen = np.unique(block["cycle_segment"])
        segments.extend(s for s in seen if s not in segments)
        last = block
        bookkeeping += clock() - t2
    cpu = clock() - start - bookkeeping
    end = SampleBlock(last.data[-1:].copy(), total - 1, last.sample_period_s)
    return (cpu, stepping, sensing), SampleBlock.concatenate([first, end]), segments


def main(argv: list[str] | None = None) -> int:
    parser = Parser(prog="brake-sim bench cycle", description=__doc__)
    parser.add_argument("--scenario", default="urban")
    parser.add_argument(
        "--brake", choices=BRAKES, default=None, help="the brake (default the scenario's)"
    )
    parser.add_argument("--preset", default=None, help="solver preset (default the scenario's)")
    parser.add_argument("--chunk-s", type=float, default=0.1, help="simulated s per chunk")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    if not (math.isfinite(args.chunk_s) and CHUNK_RANGE_S[0] <= args.chunk_s <= CHUNK_RANGE_S[1]):
        parser.error(
            f"--chunk-s {args.chunk_s!r}: allowed {CHUNK_RANGE_S[0]:g} to {CHUNK_RANGE_S[1]:g} s"
        )
    if not 1 <= args.repeats <= MAX_REPEATS:
        parser.error(f"--repeats {args.repeats}: allowed 1 to {MAX_REPEATS}")
    scenario = load_scenario(args.scenario)
    if args.brake is not None:
        scenario = on_brake(scenario, args.brake)
    scenario = scenario.with_solver(preset=args.preset)
    if scenario.setup.cycle is None:
        parser.error(f"scenario {scenario.name!r} has no [cycle]: allowed a cycle scenario")
    stepper = stepper_for(scenario)
    chunk = max(1, round(args.chunk_s / stepper.sample_period_s))
    if chunk > MAX_CHUNK_SAMPLES:  # a block's memory: the stream's own bound
        parser.error(
            f"--chunk-s {args.chunk_s:g}: {chunk} samples at {scenario.sample_rate_hz:g} Hz;"
            f" allowed at most {MAX_CHUNK_SAMPLES} samples a chunk"
        )
    stepper.advance(10)  # compile, or load the compiled kernel from the cache
    duration = scenario.duration_s
    print(
        f"scenario {scenario.name}, {scenario.setup.params.brake} brake, preset"
        f" {scenario.solver.preset}: {stepper.describe_step()}"
    )
    print(f"  {duration:g} s cycle in chunks of {chunk} samples, best of {args.repeats}")
    cases = (("physics", False), ("physics + default sensors", True))
    runs: dict[str, list[tuple[float, float, float]]] = {label: [] for label, _ in cases}
    for _ in range(args.repeats):  # alternated: a change of load hits both alike
        for label, with_sensors in cases:
            times, ends, segments = _run(scenario, chunk, with_sensors)
            runs[label].append(times)
    books = energy_balance(ends, scenario.setup.params, packed=stepper.packed_parameters)
    kinds = scenario.setup.cycle.phase_names(np.array(segments))
    best = {label: min(times) for label, times in runs.items()}  # by the whole run's CPU
    for label, (cpu, stepping, sensing) in best.items():
        split = ""
        if sensing > 0.0:
            split = (
                f" (stepping {stepping:.2f} s, sensors {sensing:.2f} s, the rest"
                f" {cpu - stepping - sensing:.2f} s)"
            )
        spread = ", ".join(f"{duration / times[0]:.1f}" for times in runs[label])
        print(
            f"  {label}: {cpu:.2f} s CPU, {duration / cpu:.1f}x real time{split};"
            f" each run: {spread}x"
        )
    rtf = duration / best[cases[1][0]][0]
    verdict = "met" if rtf >= TARGET_RTF else "NOT met"
    goal = "met" if rtf >= GOAL_RTF else "not met"
    print(
        f"  {scenario.name} cycle, {scenario.setup.params.brake} brake, preset"
        f" {scenario.solver.preset}, default sensors:"
        f" {rtf:.1f}x real time (target >= {TARGET_RTF:.0f}x: {verdict};"
        f" goal >= {GOAL_RTF:.0f}x: {goal})"
    )
    stops = sum(k.endswith(":brake") for k in kinds)
    print(f"  phases: {len(kinds)} ({stops} brake segments): {' '.join(kinds)}")
    drive = float(ends["drive_work_j"][-1])
    print(
        f"  energy books: drive work in {drive:.1f} J, friction"
        f" {float(ends['friction_work_j'][-1]):.1f} J, road load"
        f" {float(ends['road_load_work_j'][-1]):.1f} J, stored at the end"
        f" {books.stored_end_j:.3f} J; residual {books.residual_j:.2e} J"
        f" ({abs(books.residual_j) / max(books.turnover_j, 1e-300):.1e} of the energy in)"
    )
    print("  cost per sample with the shoes off the drum (4 s, recording every sample):")
    for label, text in _OVERHEAD_CASES:
        scenario = parse_scenario(text)
        if args.brake is not None:
            scenario = on_brake(scenario, args.brake)
        scenario = scenario.with_solver(preset=args.preset)
        n = round(4.0 / scenario.sample_period_s)
        best = float("inf")
        for _ in range(args.repeats):
            stepper = stepper_for(scenario)
            stepper.advance(1)
            start = time.process_time()
            stepper.advance(n)
            best = min(best, time.process_time() - start)
        print(f"    {label}: {1e9 * best / n:.0f} ns")
    return 0
