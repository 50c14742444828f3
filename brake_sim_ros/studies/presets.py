"""``brake-sim bench presets``: each preset's errors over onset phases, at the scenario's
sample rate, against the reference sampled on the same grid.

Where the first contact onset falls inside a physics step changes the first-impact error of
a scheme, most of all of a first-order one: a bound measured at one onset phase can be a
lucky one. The symmetric event is run with the actuation ramp's start moved by 0, 8, 16, 24
and 32 us (five phases across one 39 us sample interval), each preset and the DOP853
reference on the same grid, and the largest error of each metric over the phases is what
``solvers/presets.py`` bounds. Errors as ``analysis.comparison`` defines them (relative,
worse shoe).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from brake_sim_ros.analysis.impacts import event_metrics
from brake_sim_ros.command_line import Parser
from brake_sim_ros.model.actuation import Actuation, ForceProfile
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.solvers.presets import PRESETS
from brake_sim_ros.stream.build import stepper_for
from brake_sim_ros.stream.run import run_scenario
from brake_sim_ros.studies.work_precision import compare

SHIFTS_S = (0.0, 8e-6, 16e-6, 24e-6, 32e-6)
METRICS = ("err_first_peak", "err_period", "err_stop_time", "err_contact_force")


def phase_errors(shifts_s: tuple[float, ...] = SHIFTS_S) -> dict[str, np.ndarray]:
    """Errors of each preset, shape (len(shifts_s), len(METRICS)), on the symmetric event."""
    base = load_scenario("symmetric")
    ramp = base.setup.actuation.left
    start, full = ramp.times_s[1], ramp.times_s[2]
    out = {name: np.zeros((len(shifts_s), len(METRICS))) for name in PRESETS}
    for k, shift in enumerate(shifts_s):
        profile = ForceProfile.ramp(ramp.peak_n, start + shift, full + shift)
        setup = dataclasses.replace(base.setup, actuation=Actuation(profile, profile))
        scenario = dataclasses.replace(base, setup=setup)
        reference = run_scenario(scenario.with_solver(method="reference"))
        for name, preset in PRESETS.items():
            run = scenario.with_solver(preset=name)
            stepper = stepper_for(run)
            samples = stepper.run(run.duration_s)
            metrics = event_metrics(samples, stop_time_s=stepper.stop_time_s)
            row = compare(preset.scheme, name, samples, metrics, reference.metrics, run, 1.0, 1.0)
            out[name][k] = [getattr(row, m) for m in METRICS]
            print(
                f"ramp +{shift * 1e6:4.0f} us  {name:9s}"
                + "".join(f"  {m[4:]} {getattr(row, m):.2e}" for m in METRICS),
                flush=True,
            )
    return out


def main(argv: list[str] | None = None) -> int:
    parser = Parser(prog="brake-sim bench presets", description=__doc__)
    parser.parse_args(argv)
    errors = phase_errors()
    print("\nlargest over the phases, against each preset's bound:")
    for name, e in errors.items():
        preset = PRESETS[name]
        bounds = (
            preset.max_err_first_peak,
            preset.max_err_period,
            preset.max_err_stop_time,
            preset.max_err_contact_force,
        )
        cells = [
            f"{m[4:]} {w:.2e} (<= {b:g}{'' if w <= b else ' EXCEEDED'})"
            for m, w, b in zip(METRICS, e.max(axis=0), bounds, strict=True)
        ]
        print(f"  {name:9s} " + ", ".join(cells))
    return 0
