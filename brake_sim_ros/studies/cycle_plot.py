"""A drive cycle at a glance: speed, line pressure and an acceleration over the whole cycle,
with its phases shaded (the README's figure).

``python -m brake_sim_ros.studies.cycle_plot [--scenario urban] [--out docs/urban_cycle.png]``

The cycle is stepped in 0.1 s chunks and its default sensors measure every chunk (as the
node's measured stream does), so memory stays bounded by a chunk; the plot keeps the
vehicle speed (km/h) and the measured line pressure (bar) at 100 Hz and the backing-plate
acceleration as its peak magnitude per 10 ms (its 25.6 kHz samples would not show on a
page). Needs matplotlib.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from brake_sim_ros.command_line import Parser
from brake_sim_ros.model.cycle import KMH_PER_M_S
from brake_sim_ros.recording.output import replace_output
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.stream.build import sensor_bank_for, stepper_for

# phase kind -> shade colour
PHASE_COLOURS = {
    "accelerate": "#a6d96a",
    "cruise": "#ffffbf",
    "brake": "#f46d43",
    "hold": "#fdae61",
    "release": "#abd9e9",
    "drag": "#d7191c",
    "end": "#eeeeee",
}


def cycle_traces(scenario_name: str, window_s: float = 0.01) -> dict[str, np.ndarray]:
    """Per window of ``window_s``: time (s), speed (km/h), measured line pressure (bar),
    peak |acceleration| of the first accelerometer (m/s^2), cycle segment; and the phase
    kinds by segment (``kinds``)."""
    scenario = load_scenario(scenario_name)
    stepper = stepper_for(scenario)
    bank = sensor_bank_for(scenario)
    if bank is None or scenario.setup.cycle is None:
        raise SystemExit(f"scenario {scenario_name!r}: allowed a [cycle] scenario with sensors")
    radius = scenario.setup.vehicle.wheel_radius_m
    per = max(1, round(window_s / stepper.sample_period_s))
    chunk = per * 10
    total = round(scenario.duration_s / stepper.sample_period_s)
    out: dict[str, list[np.ndarray]] = {k: [] for k in ("t", "kmh", "bar", "accel", "seg")}
    accel_unit = pressure_unit = None
    while stepper.sample_index < total:
        block = stepper.advance(min(chunk, total - stepper.sample_index))
        frame = bank.advance(block)
        n = len(block) // per * per
        if n == 0:
            break
        out["t"].append(block.time_s[:n:per])
        out["kmh"].append(block["flywheel_speed_rad_s"][:n:per] * radius * KMH_PER_M_S)
        out["seg"].append(block["cycle_segment"][:n:per])
        for series in frame.series.values():
            if series.unit == "bar" and pressure_unit in (None, series.name):
                pressure_unit = series.name
                out["bar"].append(np.interp(block.time_s[:n:per], series.time_s, series.values))
            if series.unit == "m/s^2" and accel_unit in (None, series.name):
                accel_unit = series.name
                values = np.abs(series.values)
                k = len(values) * per // len(block)  # this channel's samples per window
                k = max(1, k)
                m = len(values) // k * k
                out["accel"].append(values[:m].reshape(-1, k).max(axis=1)[: n // per])
    traces = {k: np.concatenate(v) for k, v in out.items()}
    traces["names"] = np.array([pressure_unit or "", accel_unit or ""])
    traces["kinds"] = np.array([*scenario.setup.cycle.kinds, "end"])
    return traces


def plot_cycle(traces: dict[str, np.ndarray], path: Path, title: str) -> Path:
    """Three panels over the whole cycle, the phases shaded; written to ``path`` (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = traces["t"]
    fig, axes = plt.subplots(3, 1, figsize=(11, 7), sharex=True)
    panels = (
        ("kmh", "vehicle speed (km/h)"),
        ("bar", f"line pressure (bar)\n{traces['names'][0]}"),
        ("accel", f"|acceleration| peak per 10 ms\n(m/s^2) {traces['names'][1]}"),
    )
    seg = traces["seg"]
    edges = np.flatnonzero(np.diff(seg)) + 1
    starts = np.concatenate([[0], edges])
    ends = np.concatenate([edges, [len(seg)]])
    seen = set()
    for ax, (key, label) in zip(axes, panels, strict=True):
        n = min(len(t), len(traces[key]))
        for a, b in zip(starts, ends, strict=True):
            kind = str(traces["kinds"][int(seg[a])]) if seg[a] >= 0 else "end"
            ax.axvspan(
                t[a],
                t[min(b, len(t) - 1)],
                color=PHASE_COLOURS[kind],
                alpha=0.6,
                lw=0,
                label=kind if kind not in seen and ax is axes[0] else None,
            )
            seen.add(kind)
        ax.plot(t[:n], traces[key][:n], color="k", lw=0.8)
        ax.set_ylabel(label, fontsize=8)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=7, ncol=len(seen))
    axes[-1].set_xlabel("time (s)")
    fig.suptitle(title)
    fig.tight_layout()
    replace_output(path, lambda tmp: fig.savefig(tmp, format="png", dpi=100))
    plt.close(fig)
    return path


def main(argv: list[str] | None = None) -> int:
    parser = Parser(description=__doc__)
    parser.add_argument("--scenario", default="urban")
    parser.add_argument("--out", type=Path, default=Path("docs/urban_cycle.png"))
    args = parser.parse_args(argv)
    traces = cycle_traces(args.scenario)
    path = plot_cycle(traces, args.out, f"{args.scenario} cycle: phases shaded")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
