"""Print why the impact baseline finds a seized adjuster of 1 mm in only half of the
detectability study's runs (``docs/benchmarks.md``, "The floor on the service brake").

1. On the symmetric stop (service brake, 5120 Hz, 2 s) at the study's two forces, the left
   adjuster seized by 0 to 1 mm: when the line pressure first reaches the impact
   baseline's trigger (``impact.APPLY_BAR``; the pistons' mean force over their area, the
   model's pressure, not the noisy measured channel) and when each shoe first touches,
   against the end of the baseline's event window (``N_BINS - PRE_BINS`` bins after the
   trigger).
2. Given the study's dataset directory, each seized test run's largest impact health
   index at 0.75 and 1 mm, by force, against the threshold the study sets
   (:mod:`brake_sim_ros.studies.detectability`). Usage (a minute once the kernels are
   compiled; the second part needs ``brake-sim bench detectability --out DIR``)::

    PYTHONPATH=. .venv/bin/python scripts/seized_impact_window.py [DIR]
"""

from __future__ import annotations

import sys
from importlib import resources

import numpy as np

from brake_sim_ros.datasets import open as open_dataset
from brake_sim_ros.detection import evaluate, impact
from brake_sim_ros.detection.registry import make_detector
from brake_sim_ros.model.service_parameters import ServiceBrakeParameters
from brake_sim_ros.scenarios import parse_scenario
from brake_sim_ros.scenarios.loader import BUILTIN_PACKAGE
from brake_sim_ros.stream.run import run_scenario
from brake_sim_ros.studies import detectability as study

SEIZED_MM = (0.0, 0.5, 0.75, 1.0)


def _timings() -> None:
    symmetric = resources.files(BUILTIN_PACKAGE).joinpath("symmetric.toml").read_text("utf-8")
    area = ServiceBrakeParameters().piston_area_m2
    window_s = (impact.N_BINS - impact.PRE_BINS) * impact.BIN_S
    print(f"impact's event window ends {window_s * 1e3:.1f} ms after its trigger")
    for force in study.FORCES:
        for mm in SEIZED_MM:
            text = symmetric.replace('name = "symmetric"', 'name = "s"\nbrake = "service"')
            text = text.replace(
                "sample_rate_hz = 25600.0", f"sample_rate_hz = {study.SAMPLE_RATE_HZ}"
            )
            text = text.replace("peak_force_n = 1300.0", f"peak_force_n = {force}")
            seized = f"\n[defects.left]\nadjuster_seized_mm = {mm}\n" if mm else ""
            run = run_scenario(parse_scenario(text + seized, "s"), duration_s=2.0)
            s = run.samples
            t = np.asarray(s["time_s"])
            pistons = np.asarray(s["left_actuation_force_n"]) + np.asarray(
                s["right_actuation_force_n"]
            )
            trigger = t[np.flatnonzero(0.5 * pistons / area >= impact.APPLY_BAR * 1e5)[0]]
            left, right = run.metrics.left.onsets_s[0], run.metrics.right.onsets_s[0]
            print(
                f"{force:g} N, left seized {mm:g} mm: trigger {trigger:.4f} s; first touch"
                f" {(left - trigger) * 1e3:.1f} ms (left), {(right - trigger) * 1e3:.1f} ms"
                " (right) after it"
            )


def _indices(where: str) -> None:
    dataset = open_dataset(where)
    info = {r["run_id"]: r for r in dataset.manifest.to_pylist()}
    detector = make_detector("impact")
    evaluate.fit(detector, dataset, "train")
    threshold = study.thresholds(detector, dataset, 0.01)
    print(f"impact threshold {threshold:.3f}")
    found: dict[tuple[float, float], list[float]] = {}
    for run_id in dataset.runs("test"):
        row = info[run_id]
        if row["defect_kind"] != "adjuster_seized" or row["defect_severity"] < 0.75:
            continue
        assessed = evaluate.assess_run(detector, evaluate.read_run(dataset, run_id), 0.1)
        key = (float(row["defect_severity"]), float(row["peak_force_n"]))
        found.setdefault(key, []).append(max(a.health_index for a in assessed))
    for (mm, force), values in sorted(found.items()):
        print(f"seized {mm:g} mm at {force:g} N: largest index {np.round(sorted(values), 2)}")


if __name__ == "__main__":
    _timings()
    if len(sys.argv) > 1:
        _indices(sys.argv[1])
