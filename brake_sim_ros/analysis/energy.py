"""Energy balance of a recorded run: what was supplied against what was spent or is left."""

from __future__ import annotations

from brake_sim_ros.model import layout as L
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.trajectory import SampleBlock


def energy_residual(block: SampleBlock, params: BrakeParameters) -> tuple[float, float]:
    """Energy balance at the last sample, J.

    Initial kinetic energy + actuator work = friction work + coupling-damper and contact
    losses + energy absorbed when the brake locks + what remains (kinetic energy of the four
    bodies, elastic energy of the coupling and of the contacts, ``k_c eps^2 / 2`` for
    ``eps > 0``).

    Returns:
        (supplied - spent, J; initial kinetic energy of flywheel and drum, J).
    """
    d = params.driveline
    r = block.data[-1]
    c = L.COL
    e0 = 0.5 * (d.flywheel_inertia_kg_m2 + d.drum_inertia_kg_m2) * d.initial_speed_rad_s**2
    i_s = params.shoe.inertia_about_pivot_kg_m2
    kinetic = (
        0.5 * d.flywheel_inertia_kg_m2 * r[c["flywheel_speed_rad_s"]] ** 2
        + 0.5 * d.drum_inertia_kg_m2 * r[c["drum_speed_rad_s"]] ** 2
        + 0.5 * i_s * (r[c["left_speed_rad_s"]] ** 2 + r[c["right_speed_rad_s"]] ** 2)
    )
    k_c = params.contact_stiffness_n_per_m
    potential = 0.5 * d.coupling_stiffness_n_m_per_rad * (
        r[c["flywheel_angle_rad"]] - r[c["drum_angle_rad"]]
    ) ** 2 + sum(0.5 * k_c * max(r[c[f"{s}_indentation_m"]], 0.0) ** 2 for s in ("left", "right"))
    supplied = e0 + r[c["actuation_work_j"]]
    spent = (
        r[c["friction_work_j"]]
        + r[c["coupling_damper_loss_j"]]
        + r[c["contact_loss_j"]]
        + r[c["lock_loss_j"]]
        + kinetic
        + potential
    )
    return float(supplied - spent), float(e0)
