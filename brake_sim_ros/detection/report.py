"""A scoring report (``brake-sim score DIR --report OUT``): each detector's score JSON and
the figures of the issue, as files for a directory (the CLI writes them, each whole, never
through a link, replaced on a rerun):

* ``score-<detector>.json``: :func:`brake_sim_ros.detection.evaluate.score`'s JSON (its
  module documents the schema);
* ``roc.png``: every detector's ROC curve of its health index over the windows (from the
  JSON's ``health_index.roc``), the AUROC in the legend;
* ``delays.png``: each detector's detection delays over the defective runs it detected,
  one box per detector, with the count detected of defective runs;
* ``confusion-<detector>.png``: the isolation matrix (rows true class, columns diagnosed,
  each row as fractions of its windows) of each detector that diagnoses.
"""

from __future__ import annotations

import io
import json
from collections.abc import Sequence

import numpy as np


def _safe(name: str) -> str:
    """A detector's name as a file name part (``module:Class`` -> ``module_Class``)."""
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in name)


def report_files(scores: Sequence[dict]) -> dict[str, bytes]:
    """The report of ``scores`` (one per detector): file name -> content (JSON text,
    PNG images), in order. Nothing is written here: the caller writes each file whole
    (``brake-sim score --report`` through ``recording.output``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    files: dict[str, bytes] = {}
    for score in scores:
        text = json.dumps(score, indent=1, sort_keys=True) + "\n"
        files[f"score-{_safe(score['detector'])}.json"] = text.encode()

    def png(fig) -> bytes:
        buffer = io.BytesIO()
        fig.savefig(buffer, format="png", dpi=100)
        plt.close(fig)
        return buffer.getvalue()

    fig, ax = plt.subplots(figsize=(5.5, 5))
    ax.plot([0, 1], [0, 1], color="0.7", lw=0.8, ls="--")
    for s in scores:
        roc = s["health_index"]["roc"]
        auroc = s["health_index"]["auroc"]
        label = f"{s['detector']} (AUROC {'undefined' if auroc is None else f'{auroc:.3f}'})"
        ax.plot(roc["fpr"], roc["tpr"], label=label)
    ax.set_xlabel("false positive rate (healthy windows)")
    ax.set_ylabel("true positive rate (defective windows)")
    ax.set_title(f"ROC of the health index, split {scores[0]['split'] if scores else ''}")
    ax.legend(fontsize=8, loc="lower right")
    ax.grid(alpha=0.3)
    files["roc.png"] = png(fig)

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
    hold = scores[0]["hold_s"] if scores else ""
    ax.set_ylabel(f"delay from onset to held alarm (s), hold {hold} s")
    ax.set_title("Detection delays")
    ax.grid(alpha=0.3, axis="y")
    files["delays.png"] = png(fig)

    for s in scores:
        iso = s["isolation"]
        if iso is None:
            continue
        classes = iso["classes"]
        m = np.asarray(iso["matrix"], dtype=np.float64)
        keep = m.sum(axis=1) > 0  # rows: the true classes present
        rows = m[keep] / m[keep].sum(axis=1, keepdims=True)
        fig, ax = plt.subplots(figsize=(4.0 + 0.35 * len(classes), 0.35 * int(keep.sum()) + 2.5))
        image = ax.imshow(rows, cmap="Blues", vmin=0.0, vmax=1.0, aspect="auto")
        ax.set_xticks(range(len(classes)), classes, rotation=90, fontsize=7)
        true_classes = [c for c, k in zip(classes, keep, strict=True) if k]
        ax.set_yticks(range(len(true_classes)), true_classes, fontsize=7)
        ax.set_xlabel("diagnosed")
        ax.set_ylabel("true")
        ax.set_title(f"{s['detector']}: isolation (fraction of each true class's windows)")
        fig.colorbar(image, ax=ax)
        fig.tight_layout()
        files[f"confusion-{_safe(s['detector'])}.png"] = png(fig)
    return files
