"""Print the figures of the hydraulic line's defects (air in the line, a leak) quoted in
``docs/model.md`` ("The line's defects"), from the runs ``tests/model/test_line_defects.py``
checks and the hand laws beside them: the air's compliance against the circuit's, the
pressure's time constant on a small step, the time to half pressure of an application, a
leak's held pressure and time constant, and the pedal pulsation of an oval drum (order 2 of
the line pressure, 50 um) with each defect. Usage (a minute once the kernels are compiled)::

    PYTHONPATH=. .venv/bin/python scripts/line_defects_figures.py
"""

from __future__ import annotations

import math

import numpy as np

from brake_sim_ros.analysis.energy import line_pressure_pa
from brake_sim_ros.model.actuation import ForceProfile
from brake_sim_ros.model.defects import Defects, DrumDefect, DrumHarmonic, LineDefect
from brake_sim_ros.model.service import ATMOSPHERIC_PA
from tests.model.test_hydraulics import PULSE_S, SETTLE_S, SIDES, _held, _order, _tip_travel
from tests.model.test_hydraulics import _stepper as stepper_with
from tests.model.test_line_defects import AREA, RESIDUAL_PA, STOPS, C, R, _run, _time_constant


def _air_compliance(ml: float, pa: float) -> float:
    return ml * 1e-6 * ATMOSPHERIC_PA / (ATMOSPHERIC_PA + pa) ** 2


def _air() -> None:
    for bar in (0.7, 10.0, 35.0):
        print(f"1 ml of air at {bar:g} bar: {_air_compliance(1.0, bar * 1e5) / C:.3g} C")
    source = 21.0 / AREA
    middle = source - 0.3 * (source - RESIDUAL_PA)
    for ml in (0.0, 0.5, 1.0, 2.0):
        hand = R * (C + _air_compliance(ml, middle) + STOPS)
        block, pressure = _run(
            ForceProfile.constant(21.0), LineDefect(air_in_line_ml=ml), 2.6 * hand
        )
        tau = _time_constant(block.time_s, source - pressure)
        print(
            f"{ml:g} ml, 20 -> 21 N step: time constant {tau * 1e3:.1f} ms (hand {hand * 1e3:.1f})"
        )
    ramp = ForceProfile((0.0, 0.02), (0.0, 1000.0))
    for ml in (0.0, 0.5, 1.0, 2.0):
        block, pressure = _run(ramp, LineDefect(air_in_line_ml=ml), 0.2)
        t = block.time_s[np.flatnonzero(pressure >= 0.5 * 1000.0 / AREA)[0]]
        print(f"{ml:g} ml, 1000 N in 20 ms: half the static pressure at {t * 1e3:.1f} ms")


def _leak() -> None:
    for pct in (0.0, 10.0, 20.0, 40.0):
        s = pct / 100.0
        _block, pressure = _run(ForceProfile.constant(1000.0), LineDefect(line_leak_pct=pct), 0.5)
        held = (1.0 - s) * 1000.0 / AREA
        block, low = _run(ForceProfile.constant(40.0), LineDefect(line_leak_pct=pct), 0.3)
        tau = _time_constant(block.time_s, (1.0 - s) * 40.0 / AREA - low)
        print(
            f"leak {pct:g} %: 1000 N held {pressure[-1] / 1e5:.3f} bar (hand {held / 1e5:.3f});"
            f" 40 N time constant {tau * 1e3:.2f} ms (hand {R * (C + STOPS) * (1 - s) * 1e3:.2f})"
        )


def _pulsation(force_n: float) -> None:
    drum = DrumDefect((DrumHarmonic(2, 50.0, 0.0),))
    for label, line in (
        ("sound line", LineDefect()),
        ("1 ml of air", LineDefect(air_in_line_ml=1.0)),
        ("20 % leak", LineDefect(line_leak_pct=20.0)),
    ):
        stepper = stepper_with(_held(force_n), Defects(drum=drum, line=line))
        block = stepper.run(PULSE_S)
        w = block.time_s >= SETTLE_S
        phi, t = block["drum_angle_rad"][w], block.time_s[w]
        pressure = line_pressure_pa(block, stepper.packed_parameters)[w]
        travel = sum(_tip_travel(side, block[f"{side}_angle_rad"][w]) for side in SIDES)
        p_amp, u_amp = abs(_order(pressure, phi, t, 2)), abs(_order(travel, phi, t, 2))
        omega = 2.0 * float(np.mean(block["drum_speed_rad_s"][w]))
        # |P/U| of C' p' = -p / R' - A U': C' with the air at the mean pressure, R' = R (1 - s)
        r_eq = R * (1.0 - line.line_leak_pct / 100.0)
        c_eq = C + _air_compliance(line.air_in_line_ml, float(np.mean(pressure)))
        gain = AREA * omega * r_eq / math.sqrt(1.0 + (omega * r_eq * c_eq) ** 2)
        print(
            f"{force_n:g} N, 50 um oval, {label}: mean {np.mean(pressure) / 1e5:.2f} bar,"
            f" order-2 pressure {p_amp / 1e5:.4f} bar"
            f" (hand from the tips' U {gain * u_amp / 1e5:.4f})"
        )


if __name__ == "__main__":
    _air()
    _leak()
    _pulsation(1000.0)
    _pulsation(200.0)
