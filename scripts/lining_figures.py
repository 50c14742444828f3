"""Print the figures of the service brake's lining over its arc quoted in ``docs/model.md``
("The lining over its arc"): its stiffness against the point contact's, the step limit
with and without it, and the first application (0 to 1000 N per shoe in 50 ms from
100 km/h, as ``tests/model/test_lining.py`` runs it) with the lining and with the point
contact: landings per shoe, the largest normal force in its first 2 ms of contact and
the energy books. Usage (a minute once the kernels are compiled)::

    PYTHONPATH=. .venv/bin/python scripts/lining_figures.py
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from brake_sim_ros.analysis.energy import energy_balance
from brake_sim_ros.model import layout as L
from brake_sim_ros.model import lining
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.solvers.stability import step_limit
from tests.model.test_lining import _landings, _run


def _stiffness() -> None:
    params = BrakeParameters.of_brake("service")
    g, spec = params.shoe, params.service
    half = math.radians(0.5 * (g.lining_end_deg - g.lining_start_deg))
    kb = (
        spec.lining_foundation_pa_per_m
        * g.lining_width_m
        * (g.drum_radius_m - g.running_clearance_m)
    )
    radial = kb * 2.0 * math.sin(half)
    print(
        f"foundation E/t {spec.lining_foundation_pa_per_m:.3g} Pa/m; {lining.NODES} nodes"
        f" {math.degrees(2 * half) / lining.NODES:.2f} deg apart; node stiffness"
        f" {kb * 2 * half / lining.NODES:.3g} N/m"
    )
    k_c = params.contact_stiffness_n_per_m
    print(
        f"arc's radial stiffness (uniform penetration) {radial:.3g} N/m, against the point"
        f" contact's {k_c:.3g} N/m ({radial / k_c:.1f} x)"
    )
    for distributed in (False, True):
        service = dataclasses.replace(spec, distributed_lining=distributed)
        setup = BrakeSetup(params=dataclasses.replace(params, service=service))
        limit = step_limit(setup, 1000.0)
        print(
            f"step limit, {'lining over its arc' if distributed else 'point contact'}:"
            f" {limit.max_step_s:.3g} s (stability {limit.stability_step_s:.3g} s, fastest"
            f" {limit.fastest_frequency_hz:.0f} Hz, stiffest rate"
            f" {limit.stiffest_rate_per_s:.3g} 1/s)"
        )


def _application() -> None:
    for distributed in (False, True):
        scenario, stepper, block = _run(distributed)
        name = "lining over its arc" if distributed else "point contact"
        books = energy_balance(block, scenario.setup.params, packed=stepper.packed_parameters)
        t = block.time_s
        for side in L.SIDES:
            fn = block[f"{side}_normal_force_n"]
            first = np.flatnonzero(fn > 0.0)[0]
            window = (t >= t[first]) & (t < t[first] + 0.002)
            print(
                f"{name}, {side}: first contact {t[first] * 1e3:.3f} ms, landings"
                f" {_landings(block, side)}, largest normal force in its first 2 ms"
                f" {fn[window].max():.1f} N, at the end {fn[-1]:.1f} N"
            )
        print(f"{name}: energy books close to {books.residual_j:.2g} J of {books.turnover_j:.4g} J")


if __name__ == "__main__":
    _stiffness()
    _application()
