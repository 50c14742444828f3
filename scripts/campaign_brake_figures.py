"""Print the figures that explain why the baselines' scores change from the study brake to
the service brake (``docs/benchmarks.md``, the reference campaign's scores and the
detectability floor on both brakes): the symmetric stop (1300 N, 100 km/h) at the
campaigns' 5120 Hz, 2 s, healthy and with one defect at its service limit, on each brake
(a seized adjuster, the service brake's own kind, on the service brake only).
Per run: the left shoe's impacts at the application (count, first and largest peak of the
normal force, first contact), the drum speed's order-2 line after 1.2 s (the quiet sliding
the orders baseline judges on the tone ring) and the left piston's order-2 force line (the
line pressure's pulsation, which the service brake's hydraulics carry). Usage (seconds once
the kernels are compiled)::

    PYTHONPATH=. .venv/bin/python scripts/campaign_brake_figures.py
"""

from __future__ import annotations

from importlib import resources

import numpy as np

from brake_sim_ros.scenarios import parse_scenario
from brake_sim_ros.scenarios.loader import BUILTIN_PACKAGE
from brake_sim_ros.stream.run import run_scenario

RATE_HZ = 5120.0
DURATION_S = 2.0
SLIDING_FROM_S = 1.2
DEFECTS = {
    "healthy": "",
    "drum_out_of_round 150 um": (
        "[defects.drum]\nharmonics = [{ order = 2, amplitude_um = 150, phase_deg = 0 }]\n"
    ),
    "lining_wear 3.4 mm (left)": "[defects.left]\nlining_wear_mm = 3.4\n",
    "initial_angle -2 deg (left)": "[defects.left]\ninitial_angle_deg = -2.0\n",
    "adjuster_seized 1 mm (left)": "[defects.left]\nadjuster_seized_mm = 1.0\n",
}
# the service brake's own kinds (the study brake refuses them): run on it only
SERVICE_ONLY = {"adjuster_seized 1 mm (left)"}


def _order2(values: np.ndarray, angle_rad: np.ndarray) -> float:
    """Amplitude of the order-2 line of ``values`` (its quadratic trend removed)."""
    t = np.arange(values.size)
    x = values - np.polyval(np.polyfit(t, values, 2), t)
    return float(2.0 * abs(np.mean(x * np.exp(-2j * angle_rad))))


def main() -> None:
    symmetric = resources.files(BUILTIN_PACKAGE).joinpath("symmetric.toml").read_text("utf-8")
    for brake in ("study", "service"):
        for name, table in DEFECTS.items():
            if brake == "study" and name in SERVICE_ONLY:
                continue
            text = symmetric.replace('name = "symmetric"', f'name = "s"\nbrake = "{brake}"')
            text = text.replace("sample_rate_hz = 25600.0", f"sample_rate_hz = {RATE_HZ}")
            run = run_scenario(parse_scenario(text + "\n" + table, name), duration_s=DURATION_S)
            s = run.samples
            t = np.asarray(s["time_s"])
            speed = np.asarray(s["drum_speed_rad_s"])
            angle = np.cumsum(speed) / RATE_HZ
            on = t > SLIDING_FROM_S
            force = np.asarray(s["left_actuation_force_n"])
            left = run.metrics.left
            print(
                f"{brake:7s} {name:28s} left impacts {len(left.impact_peaks_n)}, first"
                f" {left.impact_peaks_n[0]:.0f} N, largest {max(left.impact_peaks_n):.0f} N,"
                f" first contact {left.onsets_s[0]:.3f} s; drum speed order 2"
                f" {1e3 * _order2(speed[on], angle[on]):.1f} mrad/s; piston force order 2"
                f" {_order2(force[on], angle[on]):.1f} N"
            )


if __name__ == "__main__":
    main()
