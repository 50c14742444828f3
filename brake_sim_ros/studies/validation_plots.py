"""Plots of the validation report, in the manner of the study's figures (PNG, matplotlib)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from brake_sim_ros.recording.output import replace_output

MAX_POINTS = 20_000


def _decimate(t: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Min/max decimation that keeps peaks visible."""
    if t.size <= MAX_POINTS:
        return t, y
    n = MAX_POINTS // 2
    edges = np.linspace(0, t.size, n + 1).astype(int)
    tt = np.empty(2 * n)
    yy = np.empty(2 * n)
    for i in range(n):
        seg = y[edges[i] : edges[i + 1]]
        tseg = t[edges[i] : edges[i + 1]]
        lo, hi = int(np.argmin(seg)), int(np.argmax(seg))
        a, b = sorted((lo, hi))
        tt[2 * i], yy[2 * i] = tseg[a], seg[a]
        tt[2 * i + 1], yy[2 * i + 1] = tseg[b], seg[b]
    return tt, yy


def plot_validation(base, runs, out_dir: Path) -> list[Path]:
    """Write the report's figures; returns their paths."""
    paths = []
    b = base.samples
    t = b.time_s

    fig, ax = plt.subplots(figsize=(9, 4.5))
    for side, colour in (("left", "C3"), ("right", "C0")):
        ax.plot(
            *_decimate(t, b.pivot_force_magnitude(side)),
            colour,
            lw=0.7,
            label=f"{side} ({'leading' if side == 'left' else 'trailing'}) shoe",
        )
    ax.set(
        xlabel="time (s)",
        ylabel="|pivot force| (N)",
        title="Symmetric brake: pivot force over the braking event",
    )
    ax.legend()
    ax.grid(alpha=0.3)
    paths.append(_save(fig, out_dir / "pivot_forces_event.png"))

    fig, ax = plt.subplots(figsize=(9, 4.5))
    zoom = (t >= 0.2) & (t <= 0.35)
    for side, colour in (("left", "C3"), ("right", "C0")):
        ax.plot(t[zoom], b.pivot_force_magnitude(side)[zoom], colour, lw=0.8, label=f"{side} shoe")
    ax.set(xlabel="time (s)", ylabel="|pivot force| (N)", title="Symmetric brake: impacting regime")
    ax.legend()
    ax.grid(alpha=0.3)
    paths.append(_save(fig, out_dir / "pivot_forces_impacting.png"))

    fig, axes = plt.subplots(4, 2, figsize=(12, 12), sharex=True)
    for ax, run in zip(axes.flat, runs, strict=True):
        s = run.result.samples
        zoom_b = (t >= 0.2) & (t <= 0.35)
        ts = s.time_s
        zoom_s = (ts >= 0.2) & (ts <= 0.35)
        ax.plot(
            t[zoom_b], b.pivot_force_magnitude(run.shoe)[zoom_b], "0.6", lw=0.8, label="symmetric"
        )
        ax.plot(
            ts[zoom_s],
            s.pivot_force_magnitude(run.shoe)[zoom_s],
            "C3",
            lw=0.8,
            label=f"case {run.case}",
        )
        ax.set_title(f"case {run.case}: {run.scenario} ({run.shoe} shoe)", fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("time (s)")
    for ax in axes[:, 0]:
        ax.set_ylabel("|pivot force| (N)")
    paths.append(_save(fig, out_dir / "defects_vs_symmetric.png"))

    fig, ax = plt.subplots(figsize=(9, 4.5))
    ax.plot(*_decimate(t, b["drum_speed_rad_s"]), "C2", lw=0.8, label="drum")
    ax.plot(*_decimate(t, b["flywheel_speed_rad_s"]), "k--", lw=0.8, label="flywheel")
    ax.set(xlabel="time (s)", ylabel="speed (rad/s)", title="Symmetric brake: drum speed")
    ax.legend()
    ax.grid(alpha=0.3)
    paths.append(_save(fig, out_dir / "drum_speed.png"))
    return paths


def plot_pivot_sweep(sweep: dict, out_dir: Path) -> Path:
    """First-impact figures against the pivot-radius change of each shoe (the report's
    ``pivot_sweep`` figures): three panels, changes in % against the symmetric brake."""
    panels = (
        ("first_impact_peak_fr_n", "first-impact peak |F_r| change (%)"),
        ("period_s", "impact period T change (%)"),
        ("first_impact_actuation_n", "actuation at first impact change (%)"),
    )
    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    for ax, (key, label) in zip(axes, panels, strict=True):
        for side, colour in (("left", "C3"), ("right", "C0")):
            sw = sweep[side]
            ax.plot(
                sw["pivot_radius_change_pct"],
                sw["change_pct"][key],
                "o-",
                color=colour,
                label=f"{side} ({'leading' if side == 'left' else 'trailing'}) shoe",
            )
        ax.axhline(0.0, color="0.6", lw=0.6)
        ax.axvline(0.0, color="0.6", lw=0.6)
        ax.set(xlabel="pivot radius change (%)", ylabel=label)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle("Pivot-location sweep: first impact of the shoe whose pin moves")
    return _save(fig, out_dir / "pivot_sweep.png")


def _save(fig, path: Path) -> Path:
    fig.tight_layout()
    replace_output(path, lambda tmp: fig.savefig(tmp, format="png", dpi=110))
    plt.close(fig)
    return path
