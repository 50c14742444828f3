"""Severity sweep of drum ovality: the pivot-force line at twice the rotation frequency.

``python -m brake_sim_ros.studies.drum_defect`` (or ``brake-sim bench drum``) runs the
published event with an oval drum (order 2) of 0, 10, 25, 50, 100 and 150 um (healthy to
the top of the service range, ``TESTBED.md``) and prints, per severity, the amplitude of
the order-2 line (``2 f_rot``) of each shoe's pivot-force magnitude and of its x and y
components over the contact regime with the actuation held (0.8-1.9 s), by order analysis
on the drum angle (:mod:`brake_sim_ros.analysis.orders`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from brake_sim_ros.analysis.orders import order_amplitude
from brake_sim_ros.command_line import Parser
from brake_sim_ros.model.defects import Defects, DrumDefect
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.solvers.fixed_step import FixedStepStepper

SEVERITIES_UM = (0.0, 10.0, 25.0, 50.0, 100.0, 150.0)
WINDOW_S = (0.8, 1.9)
STEP_S = 4e-5


@dataclass(frozen=True)
class SweepRow:
    """One severity: amplitude of the order-``k`` line per shoe, N.

    Attributes:
        amplitude_um: the drum harmonic's amplitude, um.
        rotation_hz: mean drum rotation frequency over the window, Hz (the line sits at
            ``order`` times it).
        magnitude_n, fx_n, fy_n: per shoe (``SIDES`` order), the line of ``|F_pivot|``,
            ``F_x`` and ``F_y``, N.
    """

    amplitude_um: float
    rotation_hz: float
    magnitude_n: tuple[float, ...]
    fx_n: tuple[float, ...]
    fy_n: tuple[float, ...]


def sweep(
    severities_um: tuple[float, ...] = SEVERITIES_UM, order: int = 2, phase_deg: float = 0.0
) -> list[SweepRow]:
    """Run the published event up to ``WINDOW_S[1]`` per severity; the order lines."""
    rows = []
    for amplitude in severities_um:
        defects = Defects(drum=DrumDefect.from_orders((order, amplitude, phase_deg)))
        block = FixedStepStepper(BrakeSetup(defects=defects), STEP_S).run(WINDOW_S[1])
        t = block.time_s
        angle = block["drum_angle_rad"]

        def line(signal: np.ndarray, t: np.ndarray = t, angle: np.ndarray = angle) -> float:
            return order_amplitude(t, angle, signal, order, WINDOW_S)

        fx = [block[f"{s}_pivot_fx_n"] for s in SIDES]
        fy = [block[f"{s}_pivot_fy_n"] for s in SIDES]
        m = (t >= WINDOW_S[0]) & (t < WINDOW_S[1])
        rows.append(
            SweepRow(
                amplitude_um=amplitude,
                rotation_hz=float(block["drum_speed_rad_s"][m].mean() / (2 * np.pi)),
                magnitude_n=tuple(line(np.hypot(x, y)) for x, y in zip(fx, fy, strict=True)),
                fx_n=tuple(line(x) for x in fx),
                fy_n=tuple(line(y) for y in fy),
            )
        )
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = Parser(prog="brake-sim bench drum", description=__doc__.splitlines()[0])
    parser.add_argument("--order", type=int, default=2, help="harmonic order k (default 2)")
    parser.add_argument(
        "--severities",
        type=float,
        nargs="+",
        default=list(SEVERITIES_UM),
        help="amplitudes, um (default: 0 10 25 50 100 150)",
    )
    args = parser.parse_args(argv)
    rows = sweep(tuple(args.severities), args.order)
    k = args.order
    print(
        f"drum harmonic of order {k}: pivot-force line at {k} f_rot, N (order analysis over"
        f" {WINDOW_S[0]}-{WINDOW_S[1]} s of the published event, actuation held)"
    )
    head = "  ".join(f"{s} |F|    {s} Fx    {s} Fy" for s in SIDES)
    print(f"{'a_k um':>7}  {'k f_rot Hz':>10}  {head}")
    for r in rows:
        cells = "  ".join(
            f"{r.magnitude_n[i]:>{len(s) + 4}.3f}  {r.fx_n[i]:>{len(s) + 3}.3f}"
            f"  {r.fy_n[i]:>{len(s) + 3}.3f}"
            for i, s in enumerate(SIDES)
        )
        print(f"{r.amplitude_um:>7g}  {k * r.rotation_hz:>10.2f}  {cells}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
