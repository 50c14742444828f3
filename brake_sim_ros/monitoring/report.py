"""A scoring report (``brake-sim score DIR --report OUT``): each detector's score JSON and
the figures of the issue, written to a directory.

Files (each written whole, never through a link, replaced on a rerun):

* ``score-<detector>.json``: :func:`brake_sim_ros.monitoring.evaluate.score`'s JSON (its
  module documents the schema);
* ``roc.png``: every detector's ROC curve of its health index over the windows (from the
  JSON's ``health_index.roc``), the AUROC in the legend;
* ``delays.png``: each detector's detection delays over the defective runs it detected,
  one box per detector, with the count detected of defective runs;
* ``confusion-<detector>.png``: the isolation matrix (rows true class, columns diagnosed,
  each row as fractions of its windows) of each detector that diagnoses.
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from brake_sim_ros.recording.output import OutputError, check_output, replace_output
from brake_sim_ros.recording.records import describe_path


def _safe(name: str) -> str:
    """A detector's name as a file name part (``module:Class`` -> ``module_Class``)."""
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in name)


def check_directory(directory: str | os.PathLike[str]) -> Path:
    """Refuse a report directory that is a link or not a directory (before any work).

    Raises:
        OutputError: in one line.
    """
    out = Path(directory)
    if out.is_symlink():
        raise OutputError(f"--report {describe_path(out)}: a link; allowed a directory path")
    if out.exists() and not out.is_dir():
        raise OutputError(f"--report {describe_path(out)}: not a directory")
    return out


def write_report(scores: Sequence[dict], directory: str | os.PathLike[str]) -> list[Path]:
    """Write the JSON and the figures of ``scores`` (one per detector) into ``directory``
    (made if missing); the files written, in order."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = check_directory(directory)
    names = [f"score-{_safe(s['detector'])}.json" for s in scores]
    for name in [*names, "roc.png", "delays.png"]:
        check_output(out / name, overwrite=True, option="--report")  # before any write
    written = []
    for score, name in zip(scores, names, strict=True):
        text = json.dumps(score, indent=1, sort_keys=True) + "\n"
        written.append(
            replace_output(out / name, lambda tmp, t=text: tmp.write_text(t), option="--report")
        )

    def save(fig, name: str) -> None:
        written.append(
            replace_output(
                out / name, lambda tmp: fig.savefig(tmp, format="png", dpi=100), option="--report"
            )
        )
        plt.close(fig)

    fig, ax = plt.subplots(figsize=(5.5, 5))
    ax.plot([0, 1], [0, 1], color="0.7", lw=0.8, ls="--")
    for s in scores:
        roc = s["health_index"]["roc"]
        auroc = s["health_index"]["auroc"]
        label = f"{s['detector']} (AUROC {'undefined' if auroc is None else f'{auroc:.3f}'})"
        ax.plot(roc["fpr"], roc["tpr"], label=label, drawstyle="default")
    ax.set_xlabel("false positive rate (healthy windows)")
    ax.set_ylabel("true positive rate (defective windows)")
    ax.set_title(f"ROC of the health index, split {scores[0]['split'] if scores else ''}")
    ax.legend(fontsize=8, loc="lower right")
    ax.grid(alpha=0.3)
    save(fig, "roc.png")

    fig, ax = plt.subplots(figsize=(1.6 * max(len(scores), 2) + 2, 4))
    data = [s["detection"]["delays_s"] for s in scores]
    positions = np.arange(1, len(scores) + 1)
    shown = [(p, d) for p, d in zip(positions, data, strict=True) if d]
    if shown:
        ax.boxplot([d for _, d in shown], positions=[p for p, _ in shown], widths=0.5)
    ax.set_xticks(
        positions,
        [
            f"{s['detector']}\n{s['detection']['detected']} of"
            f" {s['detection']['defective_runs']} detected"
            for s in scores
        ],
        fontsize=8,
    )
    ax.set_ylabel(
        f"delay from onset to held alarm (s), hold {scores[0]['hold_s'] if scores else ''} s"
    )
    ax.set_title("Detection delays")
    ax.grid(alpha=0.3, axis="y")
    save(fig, "delays.png")

    for s in scores:
        iso = s["isolation"]
        if iso is None:
            continue
        classes = iso["classes"]
        m = np.asarray(iso["matrix"], dtype=np.float64)
        keep = m.sum(axis=1) > 0  # rows: the true classes present
        rows = m[keep] / m[keep].sum(axis=1, keepdims=True)
        size = 2.5 + 0.35 * len(classes)
        fig, ax = plt.subplots(figsize=(size + 1.5, 0.35 * int(keep.sum()) + 2.5))
        image = ax.imshow(rows, cmap="Blues", vmin=0.0, vmax=1.0, aspect="auto")
        ax.set_xticks(range(len(classes)), classes, rotation=90, fontsize=7)
        ax.set_yticks(
            range(int(keep.sum())), [c for c, k in zip(classes, keep, strict=True) if k], fontsize=7
        )
        ax.set_xlabel("diagnosed")
        ax.set_ylabel("true")
        ax.set_title(f"{s['detector']}: isolation (fraction of each true class's windows)")
        fig.colorbar(image, ax=ax)
        fig.tight_layout()
        name = f"confusion-{_safe(s['detector'])}.png"
        check_output(out / name, overwrite=True, option="--report")
        save(fig, name)
    return written
