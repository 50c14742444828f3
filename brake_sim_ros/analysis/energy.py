"""Energy bookkeeping of a recorded run: what the model stores, spends and is supplied.

The state carries four energy quadratures integrated with the motion (layout.Y_*):
friction work, coupling-damper loss, contact (Kelvin-Voigt) loss and actuator work; the
stepper adds the kinetic energy removed when the brake locks (``lock_loss_j``). Between
any two samples of one run

    stored(first) + actuator work = stored(last) + friction + damper + contact + lock losses

where ``stored`` is the kinetic energy of flywheel, drum and shoes (about their pivots)
plus the elastic energy of the coupling spring and of the contacts (``k_c eps^2 / 2``
while the lining penetrates). The residual of that identity is the integration error of
the whole event; it can fail, since the quadratures and the motion are independent sums.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from brake_sim_ros.model import layout as L
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.trajectory import SampleBlock

SIDES = ("left", "right")
_LOSSES = ("friction_work_j", "coupling_damper_loss_j", "contact_loss_j", "lock_loss_j")


@dataclass(frozen=True)
class EnergyBalance:
    """Energy books between the first and the last sample of a block, J.

    Attributes:
        stored_start_j: kinetic + elastic energy at the first sample.
        stored_end_j: kinetic + elastic energy at the last sample.
        supplied_j: actuator work done between them.
        spent_j: friction, coupling-damper, contact and lock losses between them.
        residual_j: ``stored_start + supplied - stored_end - spent`` (0 for exact books).
    """

    stored_start_j: float
    stored_end_j: float
    supplied_j: float
    spent_j: float
    residual_j: float

    @property
    def turnover_j(self) -> float:
        """Energy that entered the books: what was stored at the start plus what was supplied."""
        return self.stored_start_j + abs(self.supplied_j)


def stored_energy_j(row: np.ndarray, params: BrakeParameters) -> float:
    """Kinetic plus elastic energy of one sample row (layout.COLUMNS), J."""
    d = params.driveline
    c = L.COL
    i_s = params.shoe.inertia_about_pivot_kg_m2
    kinetic = (
        0.5 * d.flywheel_inertia_kg_m2 * row[c["flywheel_speed_rad_s"]] ** 2
        + 0.5 * d.drum_inertia_kg_m2 * row[c["drum_speed_rad_s"]] ** 2
        + 0.5 * i_s * (row[c["left_speed_rad_s"]] ** 2 + row[c["right_speed_rad_s"]] ** 2)
    )
    twist = row[c["flywheel_angle_rad"]] - row[c["drum_angle_rad"]]
    k_c = params.contact_stiffness_n_per_m
    elastic = 0.5 * d.coupling_stiffness_n_m_per_rad * twist**2 + sum(
        0.5 * k_c * max(float(row[c[f"{s}_indentation_m"]]), 0.0) ** 2 for s in SIDES
    )
    return float(kinetic + elastic)


def energy_balance(block: SampleBlock, params: BrakeParameters) -> EnergyBalance:
    """Energy books of ``block`` (one run, samples in order) for the model ``params``.

    Raises:
        ValueError: for an empty block.
    """
    if len(block) == 0:
        raise ValueError("energy_balance needs at least one sample")
    first, last = block.data[0], block.data[-1]
    c = L.COL
    start = stored_energy_j(first, params)
    end = stored_energy_j(last, params)
    supplied = float(last[c["actuation_work_j"]] - first[c["actuation_work_j"]])
    spent = float(sum(last[c[name]] - first[c[name]] for name in _LOSSES))
    return EnergyBalance(
        stored_start_j=start,
        stored_end_j=end,
        supplied_j=supplied,
        spent_j=spent,
        residual_j=start + supplied - end - spent,
    )
