"""Print the figures of the service brake's self-adjuster and a seized adjuster quoted in
``docs/model.md`` ("The self-adjuster and a seized adjuster"), from the runs
``tests/model/test_adjuster.py`` checks: the clearance at rest with a worn lining (healthy
and seized adjuster), and for one application (2000 N a shoe in 1 ms, held) the first
contact's delay, the hand model's, the flow-limited ``A du R / p_s`` and the hardest
normal force within 2 ms of the touch, at each seized severity. Within a run
(``tests/model/test_adjuster_ratchet.py``): the clearance at rest after each of eight
applications while the lining wears with its friction work, with the ratchet and with the
adjuster seized; and ``downhill_wear`` (the left lining's wear, the take-up and the
clearance it would rest at, at the end, and when the lining reaches its 3.4 mm limit),
healthy and seized. Usage (a minute or two once the kernels are compiled)::

    PYTHONPATH=. .venv/bin/python scripts/adjuster_figures.py
"""

from __future__ import annotations

import numpy as np

from brake_sim_ros.analysis.energy import line_pressure_pa
from brake_sim_ros.model.catalogue import KIND_BY_NAME
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.service_parameters import SERVICE_RUNNING_CLEARANCE_M
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.stream.build import stepper_for
from tests.model import test_adjuster as T
from tests.model import test_adjuster_ratchet as R


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


def _within_run() -> None:
    runs = {"ratchet": R._run(R.WORK), "seized": R._run(R._seized_text())}
    for name, (scenario, _stepper, block) in runs.items():
        rows = [R._row_before(block, t) for t in R._rests(R.WORK_STARTS, scenario.duration_s)]
        wear = ", ".join(f"{block['left_lining_wear_m'][r] * 1e3:.3f}" for r in rows)
        gap = ", ".join(f"{-block['left_indentation_m'][r] * 1e3:.3f}" for r in rows)
        print(f"eight applications, {name}: wear at rest {wear} mm; clearance at rest {gap} mm")


def _downhill_wear() -> None:
    limit = KIND_BY_NAME["lining_wear"].service_limit
    base = load_scenario("downhill_wear")
    stated = base.setup.defects  # both linings' wear, growing with their work
    seized = ShoeDefect(lining_wear_mm=stated.left.lining_wear_mm, adjuster_seized_mm=R.SEIZED_MM)
    variants = {
        "ratchet": base,
        f"seized {R.SEIZED_MM:g} mm": base.with_defects(
            Defects(left=seized, right=stated.right, growth=stated.growth)
        ),
    }
    for name, scenario in variants.items():
        stepper = stepper_for(scenario)
        block = stepper.run(scenario.duration_s, record_every=256)
        wear = block["left_lining_wear_m"]
        worn = wear >= limit * 1e-3
        reached = f"{block.time_s[np.argmax(worn)]:.2f}" if worn[-1] else "never"
        taken, pending = stepper.adjuster_takeup_m[0], stepper.adjuster_pending_m[0]
        rest = SERVICE_RUNNING_CLEARANCE_M + wear[-1] - taken - pending
        if name != "ratchet":
            rest += R.SEIZED_MM * 1e-3
        print(
            f"downhill_wear, {name}: left wear at the end {wear[-1] * 1e3:.3f} mm, taken up"
            f" {taken * 1e3:.2f} mm, pending {pending * 1e3:.2f} mm, clearance it rests at"
            f" {rest * 1e3:.3f} mm; the {limit:g} mm limit reached at {reached} s"
        )


if __name__ == "__main__":
    _clearances()
    _delays()
    _within_run()
    _downhill_wear()
