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
one when the difference exceeds three times the spread over noise seeds and 1 % of the
symmetric value. The model is deterministic and has one brake, so the spread is sensor
noise only: this says what the signal carries, not that a detector would generalise to
another brake (no unit-to-unit scatter is modelled).
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy import signal

from brake_sim_ros.model.sensors import SensorBank, SensorFrame, SensorSet
from brake_sim_ros.model.structure import Structure
from brake_sim_ros.model.trajectory import SampleBlock
from brake_sim_ros.scenarios import builtin_names, load_scenario
from brake_sim_ros.stream.run import run_scenario
from brake_sim_ros.studies.core_bench import _best_cpu

NOISE_BAND_HZ = (850.0, 4600.0)  # drum brake noise (TESTBED.md)
IMPACT_WINDOW_S = (0.2, 0.4)
AXES_CHANNELS = ("backing_plate_accel_x", "backing_plate_accel_y")


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


def _features(
    frame: SensorFrame, noise_rms: dict[str, float], sensors: SensorSet
) -> dict[str, float]:
    """First-impact time (ms, either axis), band rms over the impacts per axis (m/s^2) and
    clipped samples (both axes)."""
    transducers = {c.name: c.transducer for c in sensors.channels}
    out: dict[str, float] = {"first impact ms": np.inf, "clipped": 0.0}
    for name in AXES_CHANNELS:
        s = frame[name]
        fs = 1.0 / float(s.time_s[1] - s.time_s[0])
        above = np.flatnonzero(np.abs(s.values) > 10.0 * noise_rms[name])
        if above.size:
            out["first impact ms"] = min(out["first impact ms"], 1e3 * s.time_s[above[0]])
        window = (s.time_s >= IMPACT_WINDOW_S[0]) & (s.time_s < IMPACT_WINDOW_S[1])
        sos = signal.butter(4, NOISE_BAND_HZ, btype="bandpass", fs=fs, output="sos")
        band = signal.sosfiltfilt(sos, s.values[window])
        out[f"band rms {name[-1]}"] = float(np.sqrt(np.mean(band**2)))
        t = transducers[name]
        at_range = (s.values >= t.range_max - t.adc_step) | (s.values <= t.range_min)
        out["clipped"] += float(np.count_nonzero(at_range))
    return out


# a band level must differ by more than this to count (an assumed stop-to-stop repeatability
# of impact-band levels on one brake; not measured here: the model has no such scatter)
BAND_REPEATABILITY = 0.05


def cases(duration_s: float, seeds: int) -> None:
    sensors = SensorSet()
    names = ["symmetric"] + [n for n in builtin_names() if n.startswith("case")]
    quiet: dict[str, float] = {}
    table: dict[str, list[dict[str, float]]] = {}
    period_ms = 0.0
    for name in names:
        scenario = load_scenario(name)
        samples = run_scenario(scenario, duration_s=duration_s).samples
        period_ms = 1e3 * samples.sample_period_s
        rate = scenario.sample_rate_hz
        frames = [SensorBank(sensors, rate, seed).advance(samples) for seed in range(seeds)]
        if not quiet:  # the noise rms before any force, from the healthy brake
            for ch in AXES_CHANNELS:
                s = frames[0][ch]
                quiet[ch] = float(np.std(s.values[s.time_s < IMPACT_WINDOW_S[0]]))
        table[name] = [_features(f, quiet, sensors) for f in frames]
    keys = list(table["symmetric"][0])
    mean = {n: {k: float(np.mean([r[k] for r in rows])) for k in keys} for n, rows in table.items()}
    spread = {k: max(float(np.std([r[k] for r in rows])) for rows in table.values()) for k in keys}
    base = mean["symmetric"]
    print(
        f"\ncases over {duration_s:g} s, {seeds} noise seeds, default sensor set (noise rms"
        f" x {quiet[AXES_CHANNELS[0]]:.4f}, y {quiet[AXES_CHANNELS[1]]:.4f} m/s^2); band"
        f" {NOISE_BAND_HZ[0]:g}-{NOISE_BAND_HZ[1]:g} Hz over {IMPACT_WINDOW_S[0]:g}-"
        f"{IMPACT_WINDOW_S[1]:g} s"
    )
    print(
        f"* separates from symmetric: first impact by > 2 samples and 3 seed spreads; band"
        f" rms by > {100 * BAND_REPEATABILITY:g} % and 3 seed spreads"
    )
    header = (
        "case",
        "first impact ms",
        "d ms",
        "band rms x",
        "d %",
        "band rms y",
        "d %",
        "clipped",
    )
    print(f"{header[0]:<24}" + "".join(f"{h:>16}" for h in header[1:]))
    for name in names:
        m = mean[name]
        d_first = m["first impact ms"] - base["first impact ms"]
        first_sep = abs(d_first) > max(2 * period_ms, 3 * spread["first impact ms"])
        cells = [f"{m['first impact ms']:>16.2f}", f"{d_first:>15.2f}{'*' if first_sep else ' '}"]
        for axis in ("x", "y"):
            k = f"band rms {axis}"
            rel = m[k] / base[k] - 1.0
            sep = abs(rel) > BAND_REPEATABILITY and abs(m[k] - base[k]) > 3 * spread[k]
            cells += [f"{m[k]:>16.2f}", f"{100 * rel:>15.1f}{'*' if sep else ' '}"]
        cells.append(f"{m['clipped']:>16.0f}")
        print(f"{name:<24}" + "".join(cells))
    print(
        "seed spread (largest std over cases): " + ", ".join(f"{k} {spread[k]:.3g}" for k in keys)
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="brake-sim bench sensors", description=__doc__)
    parser.add_argument("--scenario", default="symmetric")
    parser.add_argument("--duration", type=float, default=None, help="s (default: scenario's)")
    parser.add_argument("--chunk", type=int, default=256, help="samples per streaming chunk")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--case-duration", type=float, default=0.6, help="s per case")
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--no-cases", action="store_true", help="cost only")
    args = parser.parse_args(argv)
    cost(args.scenario, args.duration, args.chunk, args.repeats)
    if not args.no_cases:
        cases(args.case_duration, args.seeds)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
