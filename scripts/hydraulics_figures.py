"""Print the service brake's hydraulic figures quoted in ``docs/model.md`` ("The service
brake", hydraulics), from the runs ``tests/model/test_hydraulics.py`` checks: the circuit's
constants, the pressure's rise on a step below the springs' preload, the static pressure of
a held force, and the pedal pulsation of an oval drum (order 2 at 0, 25, 50 and 100 um)
beside its hand calculations. Usage (half a minute once the kernels are compiled)::

    PYTHONPATH=. .venv/bin/python scripts/hydraulics_figures.py
"""

from __future__ import annotations

import math

import numpy as np

from brake_sim_ros.analysis.energy import line_pressure_pa
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import contact_arms
from brake_sim_ros.model.defects import Defects, DrumDefect, DrumHarmonic
from tests.model.test_hydraulics import (  # the runs and hand laws the tests check
    AREA,
    PULSE_FORCE_N,
    PULSE_S,
    SERVICE,
    SETTLE_S,
    SIDES,
    C,
    R,
    _circuit_gain,
    _held,
    _order,
    _stepper,
    _tip_travel,
)


def _circuit() -> None:
    print(f"piston area A: {AREA * 1e6:.1f} mm^2; R C: {R * C * 1e3:.1f} ms")
    print(
        f"stiffness at a tip A^2/C: {AREA**2 / C:.3g} N/m"
        f" ({100 * AREA**2 / C / SERVICE.contact_stiffness_n_per_m:.2f} % of the contact's)"
    )


def _rise() -> None:
    stepper = _stepper(_held(40.0))
    block = stepper.run(3 * R * C)
    gap = 40.0 / AREA - line_pressure_pa(block, stepper.packed_parameters)
    w = (gap < 0.8 * gap[0]) & (gap > 0.1 * gap[0])
    tau = -1.0 / np.polyfit(block.time_s[w], np.log(gap[w]), 1)[0]
    print(f"40 N step (shoes on their stops): time constant {tau * 1e3:.2f} ms")
    stepper = _stepper(_held(1000.0))
    stepper.run(15 * R * C)
    p = stepper.state[L.Y_LINE_PRESSURE]
    print(f"1000 N held 15 R C: {p / 1e5:.4f} bar, F/A {1000.0 / AREA / 1e5:.4f} bar")


def _pulsation() -> None:
    p0 = _stepper(_held(PULSE_FORCE_N)).packed_parameters
    levers = [contact_arms(p0, L.P_SHOE_BASE + i * L.SHOE_STRIDE, 0.0) for i in range(2)]
    print(f"levers q/d: {', '.join(f'{a.actuation_arm_m / a.normal_arm_m:.3f}' for a in levers)}")
    for runout in (0.0, 25.0, 50.0, 100.0):
        drum = DrumDefect((DrumHarmonic(2, runout, 0.0),)) if runout else DrumDefect()
        stepper = _stepper(_held(PULSE_FORCE_N), Defects(drum=drum))
        block = stepper.run(PULSE_S)
        w = block.time_s >= SETTLE_S
        phi, t = block["drum_angle_rad"][w], block.time_s[w]
        pressure = line_pressure_pa(block, stepper.packed_parameters)[w]
        travel = sum(_tip_travel(side, block[f"{side}_angle_rad"][w]) for side in SIDES)
        p_amp = abs(_order(pressure, phi, t, 2))
        u_amp = abs(_order(travel, phi, t, 2))
        omega = 2.0 * float(np.mean(block["drum_speed_rad_s"][w]))
        angles = [
            float(np.mean(np.arctan2(block[f"{s}_contact_y_m"][w], block[f"{s}_contact_x_m"][w])))
            for s in SIDES
        ]
        hand_u = abs(
            sum(
                runout * 1e-6 * a.actuation_arm_m / a.normal_arm_m * np.exp(2j * alpha)
                for a, alpha in zip(levers, angles, strict=True)
            )
        )
        print(
            f"{runout:5.1f} um at {omega / (2 * math.pi):.1f} Hz: order-2 pressure"
            f" {p_amp / 1e5:.4f} bar (from U {_circuit_gain(omega) * u_amp / 1e5:.4f}, from the"
            f" levers {_circuit_gain(omega) * hand_u / 1e5:.4f}); tips' U {u_amp * 1e6:.2f} um"
            f" (levers {hand_u * 1e6:.2f} um)"
        )


if __name__ == "__main__":
    _circuit()
    _rise()
    _pulsation()
