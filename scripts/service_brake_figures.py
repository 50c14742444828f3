"""Print the service brake's figures quoted in ``docs/model.md`` ("The service brake").

The brake applied three times, 0.6 s apart (1000 N per shoe in 50 ms, held 100 ms,
released in 20 ms, from 100 km/h) as ``tests/model/test_service_brake.py`` runs it: each
application's first contact after its start, each release's instant the shoes leave the
drum, their flight from the drum to the stop (the springs pushing the fluid back through
the line) and the time to rest on the stop for good; the drag of a spring weakened past
its hold point with no actuation; the energy books. Usage (a minute once the kernels are compiled)::

    PYTHONPATH=. .venv/bin/python scripts/service_brake_figures.py
"""

from __future__ import annotations

import math

import numpy as np

from brake_sim_ros.analysis.energy import energy_balance
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import contact_arms
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.stream.build import stepper_for
from tests.model.test_service_brake import (  # the runs and hand bounds the tests check
    APPLY_S,
    FLIGHT_ALLOWANCE,
    HOLD_S,
    IDLE,
    SIDES,
    _flight,
    _flights,
    _leave_window,
    _settle_bound,
    _soft_tip,
    _three_applications,
    _tip_mass,
)


def _brake() -> None:
    params = BrakeParameters.of_brake("service")
    spec = params.service
    p = stepper_for(parse_scenario(IDLE)).packed_parameters
    arms = contact_arms(p, L.P_SHOE_BASE, 0.0)
    mass = params.shoe.inertia_about_pivot_kg_m2 / arms.actuation_arm_m**2
    stop_hz = math.sqrt(spec.stop_stiffness_n_per_m / mass) / (2 * math.pi)
    print(f"shoe inertia at the tip I/q^2: {mass:.3f} kg (q = {arms.actuation_arm_m * 1e3:.1f} mm)")
    print(
        f"rest stop mode: {stop_hz:.0f} Hz; hold point: {spec.hold_weakening_pct:.1f} % weakening"
    )


def _applications() -> None:
    scenario = parse_scenario(_three_applications())
    stepper = stepper_for(scenario)
    block = stepper.run(scenario.duration_s)
    t = block.time_s
    for side in SIDES:
        touching = block[f"{side}_normal_force_n"] > 0.0
        delays = [t[np.flatnonzero(touching & (t >= t0))[0]] - t0 for t0 in APPLY_S]
        flights, tip = _flights(block, scenario.setup.params, side, ShoeDefect())
        spec, mass = scenario.setup.params.service, _tip_mass(tip)
        shown = ", ".join(f"{d * 1e3:.3f}" for d in delays)
        print(f"{side}: first contact after each application: {shown} ms")
        soft = _soft_tip(scenario)
        for k, (leave, gap, cylinder, _speed, land, settled) in enumerate(flights):
            release = APPLY_S[k] + 0.05 + HOLD_S
            early, late = _leave_window(cylinder, soft)
            hand = _flight(
                cylinder, spec.return_spring_preload_n, spec.return_spring_rate_n_per_m, 2
            )
            slow = FLIGHT_ALLOWANCE * hand
            print(
                f"{side}: leaves the drum {(leave - release) * 1e3:.2f} ms after the release"
                f" starts (hand {early * 1e3:.2f} to {late * 1e3:.2f}) at {cylinder:.1f} N of"
                f" cylinder force, flight to the stop {(land - leave) * 1e3:.3f} ms (hand"
                f" {hand * 1e3:.3f}), on it for good {(settled - leave) * 1e3:.2f} ms after"
                f" leaving (hand bound {_settle_bound(mass, gap, slow) * 1e3:.2f})"
            )
    books = energy_balance(block, scenario.setup.params, packed=stepper.packed_parameters)
    print(f"energy books: residual {books.residual_j:.3g} J of {books.turnover_j:.6g} J")


def _drag() -> None:
    for pct in (100.0, 85.0):
        scenario = parse_scenario(IDLE).with_defects(
            Defects(left=ShoeDefect(return_spring_weakening_pct=pct))
        )
        block = stepper_for(scenario).run(scenario.duration_s)
        late = block.time_s > 1.0
        friction = block["left_friction_force_n"][late].mean()
        print(f"spring weakened {pct:g} %, no actuation: left friction {friction:.2f} N")


def main() -> None:
    _brake()
    _applications()
    _drag()


if __name__ == "__main__":
    main()
