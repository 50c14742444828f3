"""Work-precision plot (PNG, log-log): error against CPU time per simulated second."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

# errors below this are drawn on the floor (a log axis has no zero)
ERROR_FLOOR = 1e-9
_PANELS = (
    ("err_first_peak", "first-impact peak pivot force", 0.01),
    ("err_period", "impact period T", 0.01),
    ("err_stop_time", "stopping time", 0.001),
)


def plot_work_precision(rows, path: Path) -> Path:
    """One line per scheme in each panel; dashed lines: the 1 % / 0.1 % targets and 100x
    real time. ``rows``: WorkPrecisionRow objects."""
    schemes = list(dict.fromkeys(r.scheme for r in rows))
    fig, axes = plt.subplots(1, len(_PANELS), figsize=(15, 5), sharex=True)
    markers = "osD^v<>ph*"
    for ax, (key, title, target) in zip(axes, _PANELS, strict=True):
        for i, scheme in enumerate(schemes):
            pts = sorted(
                (r.cpu_s_per_sim_s, getattr(r, key))
                for r in rows
                if r.scheme == scheme and not math.isnan(getattr(r, key))
            )
            if not pts:
                continue
            ax.loglog(
                [p[0] for p in pts],
                [max(p[1], ERROR_FLOOR) for p in pts],
                marker=markers[i % len(markers)],
                label=scheme,
            )
        ax.axhline(target, color="k", ls="--", lw=0.8)
        ax.axvline(0.01, color="grey", ls=":", lw=0.8)
        ax.set_title(f"{title} (target {100 * target:g} %)")
        ax.set_xlabel("CPU s per simulated s (dotted: 100x real time)")
        ax.set_ylabel("relative error")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle("Work-precision, symmetric event: lower left is better")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
