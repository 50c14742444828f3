"""Print the figures of the service brake's self-adjuster and a seized adjuster quoted in
``docs/model.md`` ("The self-adjuster and a seized adjuster"), from the runs
``tests/model/test_adjuster.py`` checks: the clearance at rest with a worn lining (healthy
and seized adjuster), and for one application (2000 N a shoe in 1 ms, held) the first
contact's delay, the hand model's, the flow-limited ``A du R / p_s`` and the hardest
normal force within 2 ms of the touch, at each seized severity. Usage (seconds once the
kernels are compiled)::

    PYTHONPATH=. .venv/bin/python scripts/adjuster_figures.py
"""

from __future__ import annotations

import numpy as np

from brake_sim_ros.analysis.energy import line_pressure_pa
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.stream.build import stepper_for
from tests.model import test_adjuster as T


def _clearances() -> None:
    for wear in (0.3, 0.77, 1.0, 2.5):
        healthy = T._gap_at_rest(Defects(left=ShoeDefect(lining_wear_mm=wear)))
        seized = T._gap_at_rest(
            Defects(left=ShoeDefect(lining_wear_mm=wear, adjuster_seized_mm=wear))
        )
        print(
            f"lining wear {wear:g} mm: clearance at rest {healthy * 1e3:.3f} mm (healthy"
            f" adjuster), {seized * 1e3:.3f} mm (seized)"
        )


def _delays() -> None:
    runs = {}
    for mm in T.SEVERITIES_MM:
        shoe = ShoeDefect(adjuster_seized_mm=mm)
        scenario = parse_scenario(T._application()).with_defects(Defects(left=shoe))
        stepper = stepper_for(scenario)
        runs[mm] = (stepper, stepper.run(scenario.duration_s))
    stepper, block = runs[0.0]
    touch = T._first_contact_s(block)
    row = int(np.flatnonzero(block.time_s >= touch)[0])
    u, v, mass = T._left_tip(block, row)
    pressure = float(line_pressure_pa(block, stepper.packed_parameters)[row])
    u0 = T._tip_travel_to_contact(Defects())
    area, r = T.SPEC.piston_area_m2, T.SPEC.line_resistance_pa_s_per_m3
    print(
        f"healthy: both shoes touch {(touch - T.APPLY_S) * 1e3:.3f} ms after the application;"
        f" the tip has travelled {u0 * 1e3:.3f} mm to the drum, at {v:.3f} m/s, line"
        f" {pressure / 1e5:.2f} bar, tip mass {mass:.3f} kg"
    )
    for mm in T.SEVERITIES_MM:
        du = T._tip_travel_to_contact(Defects(left=ShoeDefect(adjuster_seized_mm=mm))) - u0
        first = T._first_contact_s(runs[mm][1])
        t = runs[mm][1].time_s
        hit = runs[mm][1]["left_normal_force_n"][(t >= first) & (t < first + 0.002)].max()
        hand = T._hand_arrival_s((u, v, pressure, mass), u0 + du) if mm else 0.0
        flow = area * du * r / (T.FORCE_N / area)
        print(
            f"seized {mm:g} mm: extra tip travel {du * 1e3:.3f} mm, fluid {area * du * 1e6:.3f}"
            f" ml; first contact {(first - touch) * 1e3:.3f} ms later (hand {hand * 1e3:.3f},"
            f" A du R / p_s {flow * 1e3:.3f}); hardest normal force {hit:.0f} N"
        )


if __name__ == "__main__":
    _clearances()
    _delays()
