"""Print when a seized adjuster's shoe first touches the drum and the piston's force then
(``docs/scenarios.md``, ``brake-sim severity`` on the service brake).

The published event on the service brake (``brake-sim severity``'s base), the left
adjuster seized by 0 to 1 mm in the severity sweep's steps: the first sample with a
normal force on the left lining, the left piston's force there, and the severity study's
own figure (the actuation at the first impact); then, for 1 mm, the piston's force every
4 ms while the shoe travels (its ripple). Usage (seconds once the kernels are compiled)::

    PYTHONPATH=. .venv/bin/python scripts/seized_first_touch.py
"""

from __future__ import annotations

import numpy as np

from brake_sim_ros.model.defects import Defects
from brake_sim_ros.stream.run import run_scenario
from brake_sim_ros.studies.severity import base_scenario

SEIZED_MM = (0.0, 0.2, 0.4, 0.5, 0.6, 0.8, 1.0)
DURATION_S = 0.45  # past every first touch of the published event


def _run(mm: float):
    scenario = base_scenario("service").with_defects(Defects.single("adjuster_seized", "left", mm))
    return run_scenario(scenario, duration_s=DURATION_S)


def main() -> None:
    for mm in SEIZED_MM:
        run = _run(mm)
        b = run.samples
        first = int(np.argmax(b["left_normal_force_n"] > 0.0))
        print(
            f"seized {mm:.1f} mm: first touch at {1e3 * b.time_s[first]:.2f} ms, piston force"
            f" {b['left_actuation_force_n'][first]:.1f} N (severity's first-impact actuation"
            f" {run.metrics.left.first_impact_actuation_n:.1f} N)"
        )
    b = _run(1.0).samples
    times = np.arange(0.240, 0.321, 0.004)
    rows = np.searchsorted(b.time_s, times)
    print("seized 1.0 mm, piston force while the shoe travels (ms: N):")
    print(
        "  "
        + ", ".join(
            f"{1e3 * t:.0f}: {b['left_actuation_force_n'][i]:.1f}"
            for t, i in zip(times, rows, strict=True)
        )
    )


if __name__ == "__main__":
    main()
