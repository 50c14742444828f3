"""Every assessed window of a score, as rows a user can take further, and the score's
figures over each held-out rule's runs apart from the rest of the split.

``brake-sim score --windows FILE.parquet`` writes :func:`windows_table`: one row per
assessed window, in run order, with the columns of :data:`COLUMNS`; any metric can be
computed from it (the score's AUROC is scikit-learn's over ``health_index`` against
``defective``).

:func:`headline_figures` is the one rule for the score's headline figures over some runs
and their windows: the whole split's (:func:`.evaluate.score`) and, in the score JSON's
``held_out`` list (:func:`held_out_figures`), per held-out rule of the dataset
(``[[split.held_out]]``: values run on test units only, since a detector is judged on what
it never saw) those over the runs the rule matches and over the rest of the split.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from brake_sim_ros.detection import metrics

# column -> (pyarrow type name, meaning)
COLUMNS: dict[str, tuple[str, str]] = {
    "run_id": ("string", "the run (the manifest's run_id)"),
    "unit_id": ("string", "the brake unit"),
    "sample_index": ("int64", "the run's index of the window's last sample"),
    "time_s": ("float64", "the time of that sample, s"),
    "health_index": ("float64", "the detector's health index (1 = its alarm threshold)"),
    "alarm": ("bool_", "the detector's alarm"),
    "diagnosis": ("string", "kind:location the detector diagnosed (null: none)"),
    "severity": ("float64", "its severity estimate, in the kind's unit (NaN: none)"),
    "rul_s": ("float64", "its remaining-useful-life forecast, s (NaN: none)"),
    "defective": ("bool_", "truth at the window's last sample: a defect is active"),
    "defects": ("string", "the active defects there, kind:location, space-separated"),
    "class": ("string", "the first active defect's kind:location, or healthy"),
}


def window_rows(
    run_id: str,
    unit_id: str,
    found: Sequence[Any],
    times: np.ndarray,
    active: Sequence[Sequence[str]],
    classes: Sequence[str],
) -> list[dict[str, Any]]:
    """The rows of one run's assessments ``found`` (their sample times ``times`` and, at
    each, the active defects and the class)."""
    rows = []
    for a, t, defects, cls in zip(found, times, active, classes, strict=True):
        d = a.diagnosis
        rows.append(
            {
                "run_id": run_id,
                "unit_id": unit_id,
                "sample_index": int(a.sample_index),
                "time_s": float(t),
                "health_index": float(a.health_index),
                "alarm": bool(a.alarm),
                "diagnosis": None if d is None else f"{d.kind}:{d.location}",
                "severity": float("nan") if d is None else float(d.severity),
                "rul_s": float(a.rul_s),
                "defective": bool(defects),
                "defects": " ".join(defects),
                "class": cls,
            }
        )
    return rows


def windows_table(rows: Sequence[Mapping[str, Any]]) -> Any:
    """The rows as a pyarrow table of :data:`COLUMNS` (each column's meaning in its field
    metadata)."""
    import pyarrow as pa

    fields = [
        pa.field(name, getattr(pa, kind)(), metadata={"description": what})
        for name, (kind, what) in COLUMNS.items()
    ]
    schema = pa.schema(fields)
    return pa.table({f.name: pa.array([r[f.name] for r in rows], f.type) for f in fields}, schema)


def headline_figures(runs: Sequence[Mapping[str, Any]], rows: Sequence[Mapping[str, Any]]) -> dict:
    """The headline figures over some runs (their score ``per_run`` entries) and their
    windows (:func:`window_rows`): ``runs``, ``windows``, ``detection`` (a run is defective
    from its onset; detected when it has a delay), ``false_alarms`` (over the healthy
    time) and ``health_index`` (AUROC and AUPRC, defective windows positive). The one rule
    for the whole split's figures (:func:`.evaluate.score`) and a held-out rule's."""
    delays = [r["delay_s"] for r in runs if r["onset_s"] is not None]
    detected = [d for d in delays if d is not None]
    count = sum(r["false_alarms"] for r in runs)
    hours = sum(r["healthy_s"] for r in runs) / 3600.0
    y = np.array([r["defective"] for r in rows], dtype=bool)
    h = np.array([r["health_index"] for r in rows], dtype=np.float64)
    return {
        "runs": len(runs),
        "windows": int(y.size),
        "detection": {
            "defective_runs": len(delays),
            "detected": len(detected),
            "missed": len(delays) - len(detected),
            "median_delay_s": float(np.median(detected)) if detected else None,
        },
        "false_alarms": {
            "count": count,
            "healthy_hours": hours,
            "per_hour": count / hours if hours > 0 else None,
        },
        "health_index": {
            "auroc": metrics.auroc(y, h) if y.size else None,
            "auprc": metrics.auprc(y, h) if y.size else None,
        },
    }


def held_out_figures(
    rules: Sequence[Any],
    columns: Mapping[str, Mapping[str, Any]],
    per_run: Sequence[Mapping[str, Any]],
    rows: Sequence[Mapping[str, Any]],
) -> list[dict]:
    """Per rule (the dataset's ``HeldOut`` rules, :attr:`SweepDataset.held_out`): ``rule``
    (column, values, minimum, maximum), ``held_out`` (the figures over
    the runs it matches) and ``rest`` (over the split's other runs); ``columns`` is each
    run's manifest row by run id."""
    out = []
    for rule in rules:
        held = {r["run_id"] for r in per_run if rule.matches(columns.get(r["run_id"], {}))}
        out.append(
            {
                "rule": {
                    "column": rule.column,
                    "values": list(rule.values),
                    "minimum": rule.minimum,
                    "maximum": rule.maximum,
                },
                "held_out": headline_figures(
                    [r for r in per_run if r["run_id"] in held],
                    [w for w in rows if w["run_id"] in held],
                ),
                "rest": headline_figures(
                    [r for r in per_run if r["run_id"] not in held],
                    [w for w in rows if w["run_id"] not in held],
                ),
            }
        )
    return out
