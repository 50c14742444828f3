"""Hash a run's outputs, to show that a change keeps the numbers bit for bit.

Run it before and after the change (same machine, same Python and numba) and compare the
lines: ``PYTHONPATH=. .venv/bin/python scripts/hash_outputs.py > hashes.txt``.

Each line is one run, stepped in chunks as the node and ``bench cycle`` step it: the
SHA-256 (first 24 hex digits) of every sample column of every row, and with sensors of
every output series (times, values, fault labels), the tone ring's edges and the
structure's outputs. The runs: ``urban`` and ``symmetric`` with their default sensors;
``symmetric`` with a faulted sensor set (every fault kind, a decimated IMU, a load pin) in
chunks of 77 samples; the published cases, the downhill runs (thermal, wear), every
fixed-step scheme, one shoe removed, an oval drum and the urban cycle on a drum with a
flat (physics only). The drive cycles (``urban``, the downhill runs) ran on the study
brake until they moved to the service brake (issue 28): their lines keep their labels and
meaning on the study brake (``tests/study_cycles.py``: the files with ``brake = "study"``).
Then the service brake: the built-in cycles as they ship (urban with its default sensors),
20 s of urban with every fixed-step scheme, three applications and releases (shoes leaving
and landing on their rest stops) on a line with air and a leak, a stop on a wet road, and
the lining over its arc (``distributed_lining``): 14 s of urban with both RK4 schemes, the
applications, and a stop on a drum with a flat.
``--quick``: the first three runs only.

Without the ROS message package: the stepper and the sensor bank are built as
:mod:`brake_sim_ros.stream.build` builds them.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib

import numpy as np

from brake_sim_ros.model.assembly import ModelOptions
from brake_sim_ros.scenarios import Scenario, load_scenario, parse_scenario
from brake_sim_ros.sensing.sensors import SensorBank, SensorSet
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from tests.sample_blocks import faulted_set  # the sensor set tests/sensing/test_sensors.py runs
from tests.study_cycles import on_study_brake, study_text

OVAL = (
    'name = "oval"\nduration_s = 7.5\n[[defects.drum.harmonics]]\norder = 2\n'
    "amplitude_um = 50.0\nphase_deg = 0.0\n"
)
CYCLES = ("urban", "downhill", "downhill_fade", "downhill_wear")  # the built-in drive cycles
# three applications to 1000 N per shoe and their releases, 0.6 s apart: the shoes leave
# their rest stops, brake, return and land on them (tests/model/test_service_brake.py)
_KNOTS = (
    "times_s = [0.0, 0.1, 0.15, 0.25, 0.27, 0.7, 0.75, 0.85, 0.87, 1.3, 1.35, 1.45, 1.47]\n"
    "forces_n = [0.0, 0.0, 1000.0, 1000.0, 0.0, 0.0, 1000.0, 1000.0, 0.0, 0.0, 1000.0,"
    " 1000.0, 0.0]\n"
)
SERVICE_APPLICATIONS = (
    'name = "applications"\nbrake = "service"\nduration_s = 1.9\n[actuation]\n'
    f'profile = "piecewise"\n[actuation.left]\n{_KNOTS}[actuation.right]\n{_KNOTS}'
    "[defects.line]\nair_in_line_ml = 1.0\nline_leak_pct = 20.0\n"
)
SERVICE_WET = 'name = "wet"\nbrake = "service"\nroad_friction = 0.4\n'
LINED = "\n[parameters.service]\ndistributed_lining = true\n"
FLAT = (
    "\n[defects.drum]\nflat_depth_um = 40.0\nflat_width_deg = 20.0\n"
    "[[defects.drum.harmonics]]\norder = 3\namplitude_um = 20.0\nphase_deg = 10.0\n"
)


def run_hash(
    label: str,
    scenario: Scenario,
    chunk: int,
    *,
    sensors: SensorSet | None = None,
    scheme: str | None = None,
    options: ModelOptions | None = None,
    duration_s: float | None = None,
) -> str:
    """One line: ``label``, rows, columns and the hashes of the samples (and sensors)."""
    setup = scenario.setup
    if options is not None:
        setup = dataclasses.replace(setup, options=options)
    stepper = FixedStepStepper(
        setup,
        scenario.sample_period_s,
        scheme=scheme or scenario.solver.fixed_step_scheme,
        max_step_s=scenario.solver.max_step_s,
    )
    bank = None if sensors is None else SensorBank(sensors, scenario.sample_rate_hz, scenario.seed)
    duration = scenario.duration_s if duration_s is None else duration_s
    total = round(duration / stepper.sample_period_s)
    samples, measured = hashlib.sha256(), hashlib.sha256()
    columns = 0
    while stepper.sample_index < total:
        block = stepper.advance(min(chunk, total - stepper.sample_index))
        samples.update(np.ascontiguousarray(block.data).tobytes())
        columns = block.data.shape[1]
        if bank is None:
            continue
        frame = bank.advance(block)
        for name, series in frame.series.items():
            measured.update(name.encode())
            for values in (series.time_s, series.values, series.fault_label):
                measured.update(np.ascontiguousarray(values).tobytes())
        for name, edges in frame.edges_s.items():
            measured.update(name.encode() + edges.tobytes())
        measured.update(np.ascontiguousarray(frame.structure).tobytes())
    line = f"{label} ({stepper.scheme}, chunk {chunk}): {total} rows x {columns}"
    line += f" samples {samples.hexdigest()[:24]}"
    if bank is not None:
        line += f" sensors {measured.hexdigest()[:24]}"
    return line


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the sensor runs only")
    args = parser.parse_args()
    urban, symmetric = on_study_brake("urban"), load_scenario("symmetric")
    print(run_hash("urban + default sensors", urban, 2560, sensors=urban.sensors), flush=True)
    print(run_hash("symmetric + default sensors", symmetric, 2560, sensors=symmetric.sensors))
    print(run_hash("symmetric + faulted sensors", symmetric, 77, sensors=faulted_set()))
    if args.quick:
        return
    for name in ("case1_left_pivot_out", "case5_left_tilted", "case7_left_actuation"):
        print(run_hash(name, load_scenario(name), 1000), flush=True)
    for name in CYCLES[1:]:
        print(run_hash(name, on_study_brake(name), 1000), flush=True)
    for name, scenario in (("symmetric", symmetric), ("urban 20 s", urban)):
        for scheme in ("rk4", "rk4-located", "semi-implicit-euler"):
            print(run_hash(name, scenario, 1000, scheme=scheme, duration_s=20.0), flush=True)
        for shoe in ("left", "right"):
            one = ModelOptions(shoes=(shoe,))
            label = f"{name}, {shoe} shoe only"
            print(run_hash(label, scenario, 1000, options=one, duration_s=20.0), flush=True)
    print(run_hash("oval drum", parse_scenario(OVAL), 1000), flush=True)
    flat = parse_scenario(study_text("urban") + FLAT)
    print(run_hash("urban, drum with a flat", flat, 1000), flush=True)
    service_hashes()


def service_hashes() -> None:
    """The service brake's lines: the built-in cycles as they ship (urban with its default
    sensors), urban with every scheme, applications and releases on a line with defects, a
    stop on a wet road."""
    urban = load_scenario("urban")
    assert urban.setup.params.brake == "service"
    print(run_hash("urban (service) + default sensors", urban, 2560, sensors=urban.sensors))
    for name in CYCLES[1:]:
        print(run_hash(f"{name} (service)", load_scenario(name), 1000), flush=True)
    for scheme in ("rk4", "rk4-located", "semi-implicit-euler"):
        print(run_hash("urban 20 s, service brake", urban, 1000, scheme=scheme, duration_s=20.0))
    applications = parse_scenario(SERVICE_APPLICATIONS)
    label = "service brake, 3 applications, air and leak"
    print(run_hash(label, applications, 77, sensors=applications.sensors), flush=True)
    print(run_hash("service brake, wet road stop", parse_scenario(SERVICE_WET), 1000))
    lined_hashes()


def lined_hashes() -> None:
    """The service brake with its lining over the arc: urban with both RK4 schemes, the
    applications, a stop on a drum with a flat."""
    lined = parse_scenario(load_scenario("urban").text + LINED)
    for scheme in ("rk4-located", "rk4"):
        label = "urban 14 s, service brake, lining over its arc"
        print(run_hash(label, lined, 1000, scheme=scheme, duration_s=14.0), flush=True)
    label = "service brake, 3 applications, lining over its arc"
    print(run_hash(label, parse_scenario(SERVICE_APPLICATIONS + LINED), 77), flush=True)
    flat = parse_scenario('name = "flat"\nbrake = "service"\n' + FLAT + LINED)
    label = "service brake, drum with a flat, lining over its arc"
    print(run_hash(label, flat, 1000, duration_s=2.0))


if __name__ == "__main__":
    main()
