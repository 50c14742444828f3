"""``brake-sim bench sensors``: cost of the structure and the sensors, and what the measured
acceleration tells of each built-in case.

Part 1, cost: the scenario is run once at the level its fidelity plan chooses (printed);
then the structure alone and the scenario's sensor set (structure included) process its
samples, in one block and in streaming chunks of ``--chunk`` samples, best of
``--repeats``; printed as CPU seconds per simulated second and as a multiple of real time,
beside the physics' own cost, with the total with and without the sensors. A scenario
whose plan has no sensors (``[needs]`` without ``measured_signals``) reports its physics
only: it builds no structure and no sensors.

Part 2, cases: every built-in case is run for ``--case-duration`` seconds and measured by
the default sensor set with ``--seeds`` noise seeds. Features of the backing-plate
accelerations: the first-impact time (first sample above ten times the channel's noise
rms), the rms in the drum-brake noise band 0.85-4.6 kHz over the impacts (0.2-0.4 s) per
axis, and the number of clipped samples. A feature separates a case from the symmetric
one when the difference exceeds three times the spread over noise seeds and a floor (two
samples for the first impact, 5 % for a band level). The features and the rule are
:mod:`brake_sim_ros.analysis.measured_features`, which the validation report uses too.
The model is deterministic and has one brake, so the spread is sensor noise only: this
says what the signal carries, not that a detector would generalise to another brake (no
unit-to-unit scatter is modelled).
"""

from __future__ import annotations

from brake_sim_ros.analysis import measured_features as mf
from brake_sim_ros.command_line import Parser
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.scenarios import builtin_names, load_scenario
from brake_sim_ros.sensing.sensors import SensorBank
from brake_sim_ros.sensing.structure import Structure
from brake_sim_ros.stream.run import run_scenario
from brake_sim_ros.studies.core_bench import _best_cpu


def _chunks(block: SampleBlock, size: int) -> list[SampleBlock]:
    return [
        SampleBlock(
            block.data[i : i + size], block.first_index + i, block.sample_period_s, block.columns
        )
        for i in range(0, len(block), size)
    ]


def cost(scenario_name: str, duration_s: float | None, chunk: int, repeats: int) -> None:
    scenario = load_scenario(scenario_name)
    run = run_scenario(scenario, duration_s=duration_s)
    samples = run.samples
    simulated = len(samples) * samples.sample_period_s
    rate = scenario.sample_rate_hz
    print(
        f"fidelity plan: level {run.plan.level.name}, sensors"
        f" {'on' if run.plan.sensors else 'off'} ({run.plan.reason})"
    )
    if not run.plan.sensors:  # the plan builds no sensor bank: nothing more to pay for
        per = run.cpu_s / simulated
        print(
            f"scenario {scenario.name}: {simulated:g} s simulated, physics"
            f" {per:.5f} CPU s / sim s; no structure, no sensors (add 'measured_signals' to"
            " [needs] outputs to measure their cost)"
        )
        return
    parts = _chunks(samples, chunk)
    # compile and warm up outside the timed region
    SensorBank(scenario.sensors, rate, scenario.seed).advance(parts[0])

    def structure_whole() -> None:
        Structure(scenario.sensors.structure, samples.sample_period_s).advance(samples)

    def structure_chunks() -> None:
        s = Structure(scenario.sensors.structure, samples.sample_period_s)
        for p in parts:
            s.advance(p)

    def sensors_whole() -> None:
        SensorBank(scenario.sensors, rate, scenario.seed).advance(samples)

    def sensors_chunks() -> None:
        bank = SensorBank(scenario.sensors, rate, scenario.seed)
        for p in parts:
            bank.advance(p)

    print(
        f"scenario {scenario.name}: {simulated:g} s simulated at {rate:g} Hz, "
        f"channels {[c.name for c in scenario.sensors.channels]}, "
        f"{len(scenario.sensors.structure.modes)} modes"
    )
    print(f"{'what':<38}{'CPU s / sim s':>15}{'x real time':>14}")
    rows = [("physics (run_scenario, for scale)", run.cpu_s)]
    rows += [
        ("structure, one block", _best_cpu(structure_whole, repeats)),
        (f"structure, chunks of {chunk}", _best_cpu(structure_chunks, repeats)),
        ("sensor set + structure, one block", _best_cpu(sensors_whole, repeats)),
        (f"sensor set + structure, chunks of {chunk}", _best_cpu(sensors_chunks, repeats)),
    ]
    for what, cpu in rows:
        per = cpu / simulated
        print(f"{what:<38}{per:>15.5f}{1.0 / per if per > 0 else float('inf'):>14.0f}")
    physics, streamed = rows[0][1] / simulated, rows[-1][1] / simulated
    print(
        f"physics with the sensors streamed {physics + streamed:.5f} CPU s / sim s, without"
        f" {physics:.5f} (a [needs] without 'measured_signals' saves {streamed:.5f},"
        f" {100 * streamed / physics:.0f} % of the physics)"
    )


def cases(duration_s: float, seeds: int) -> None:
    """Part 2: every built-in case measured by the default sensor set, against the
    symmetric brake (features and rule: :mod:`brake_sim_ros.analysis.measured_features`)."""
    names = ["symmetric"] + [n for n in builtin_names() if n.startswith("case")]
    scenarios = {name: load_scenario(name) for name in names}
    samples = {
        name: run_scenario(s, duration_s=duration_s).samples for name, s in scenarios.items()
    }
    result = mf.measure_cases(
        samples,
        "symmetric",
        sample_rate_hz=scenarios["symmetric"].sample_rate_hz,
        seeds=range(seeds),
    )
    print(f"\ncases over {duration_s:g} s; " + mf.describe(result) + "\n")
    print(mf.markdown_table(result))
    print("\n" + "\n".join(mf.verdict_lines(result)))


def main(argv: list[str] | None = None) -> int:
    parser = Parser(prog="brake-sim bench sensors", description=__doc__)
    parser.add_argument("--scenario", default="symmetric")
    parser.add_argument("--duration", type=float, default=None, help="s (default: scenario's)")
    parser.add_argument("--chunk", type=int, default=256, help="samples per streaming chunk")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--case-duration", type=float, default=mf.DEFAULT_DURATION_S, help="s per case"
    )
    parser.add_argument("--seeds", type=int, default=mf.DEFAULT_SEEDS)
    parser.add_argument("--no-cases", action="store_true", help="cost only")
    args = parser.parse_args(argv)
    cost(args.scenario, args.duration, args.chunk, args.repeats)
    if not args.no_cases:
        cases(args.case_duration, args.seeds)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
