"""Physical parameters of the drum brake: frozen dataclasses, SI units in every name.

Frame ``brake_backing_plate``: origin at the drum centre, x to the right, y up, z out of
the wheel toward the viewer. Drum and flywheel angles are positive counter-clockwise
about +z. The drum turns counter-clockwise (positive speed) in the nominal event, which
makes the left shoe the leading (self-energising) shoe when its pivot is at the bottom.

Shoe geometry is given for the LEFT shoe in its symmetric rest position; the right shoe
is its mirror image about the y axis. A shoe angle is positive when the shoe turns
outward, toward the drum (left shoe counter-clockwise, right shoe clockwise).

Values given by the published study (MODEL.md "Known parameters") are marked
``[published]``. Every other value is a modelling choice made once, for the symmetric
case and the three calibration cases together, with its reason next to it. This module
is the single place where they live; scenarios override them, nothing else does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from typing import Any

from brake_sim_ros.errors import ParameterError


def _require(condition: bool, name: str, value: Any, allowed: str) -> None:
    if not condition:
        raise ParameterError(f"parameter {name}={value!r} is invalid: allowed {allowed}")


def _finite(obj: Any) -> None:
    for f in fields(obj):
        value = getattr(obj, f.name)
        if isinstance(value, float | int) and not isinstance(value, bool):
            _require(math.isfinite(value), f.name, value, "a finite number")


@dataclass(frozen=True)
class DrivelineParameters:
    """Flywheel (vehicle inertia share), drum, and the torsional coupling between them."""

    flywheel_inertia_kg_m2: float = 17.1  # [published]
    drum_inertia_kg_m2: float = 0.041  # [published]
    coupling_stiffness_n_m_per_rad: float = 1835.0  # [published] wheel, tyre and hub
    coupling_damping_n_m_s_per_rad: float = 5.0  # [published]
    initial_speed_rad_s: float = 103.5  # [published] 100 km/h, flywheel and drum alike

    def __post_init__(self) -> None:
        _finite(self)
        _require(
            self.flywheel_inertia_kg_m2 > 0,
            "flywheel_inertia_kg_m2",
            self.flywheel_inertia_kg_m2,
            "> 0",
        )
        _require(self.drum_inertia_kg_m2 > 0, "drum_inertia_kg_m2", self.drum_inertia_kg_m2, "> 0")
        _require(
            self.coupling_stiffness_n_m_per_rad > 0,
            "coupling_stiffness_n_m_per_rad",
            self.coupling_stiffness_n_m_per_rad,
            "> 0",
        )
        _require(
            self.coupling_damping_n_m_s_per_rad >= 0,
            "coupling_damping_n_m_s_per_rad",
            self.coupling_damping_n_m_s_per_rad,
            ">= 0",
        )
        _require(
            abs(self.initial_speed_rad_s) <= 400.0,
            "initial_speed_rad_s",
            self.initial_speed_rad_s,
            "|speed| <= 400 rad/s (about 260 km/h)",
        )


@dataclass(frozen=True)
class ShoeGeometry:
    """Rigid-shoe geometry of the LEFT shoe at rest; the right shoe mirrors it about y.

    Angles are polar angles in the backing-plate frame, degrees, measured
    counter-clockwise from +x (180 deg points left).
    """

    drum_radius_m: float = 0.180  # [published]
    # Pivot 150 mm from the drum centre, 10 deg left of bottom dead centre: a typical
    # anchor-pin position for a 360 mm drum. It sets the normal-force moment arm
    # (about 150 mm at the centre of contact pressure). The angle also sets which way a
    # radial pivot shift moves the shoe (toward its heel); see lining_end_deg.
    pivot_radius_m: float = 0.150
    pivot_polar_angle_deg: float = 261.0
    # Running clearance between lining and drum at rest. Calibrated (with the shoe
    # inertia and peak actuation force) so that the first impact happens at 56 N of
    # actuation; the study's case 5 (+79.7 % peak force for a 2 deg tilt) independently
    # implies an angular gap of about 1.4 deg, i.e. 3-4 mm at a 150 mm pivot radius.
    # That is a worn, badly adjusted brake rather than a new one (0.3-0.5 mm).
    running_clearance_m: float = 0.00373
    # Lining arc: from 125 deg (toe, upper end) to 195 deg (heel, next to the pivot).
    # A radial pivot shift moves the shoe along the pivot's radius, toward its heel, so
    # the heel position sets how much a +3 % shift closes the gap (case 1: first impact
    # at 42 N published, about 45 N here); the toe stays clear of the drum when the pivot
    # moves 3 % inward (case 2). 70 deg of arc, within the usual 70-120 deg.
    lining_start_deg: float = 125.0
    lining_end_deg: float = 195.0
    # Lining (friction material) width along the drum axis: the Hertzian contact length.
    lining_width_m: float = 0.045
    # Shoe tip where the wheel cylinder pushes, horizontally outward.
    tip_x_m: float = -0.030
    tip_y_m: float = 0.140
    # Shoe mass and mass centre: web, table and lining as a 150 deg arc at 160 mm
    # (centroid 118 mm from the drum centre) with the heavier heel end toward the pivot.
    # Inertia about the pivot pin: 0.020 kg m^2 about the mass centre (radius of
    # gyration 130 mm) plus m d^2 = 0.030 kg m^2. Together with the clearance and the
    # peak actuation force it puts the first impact at 56 N.
    mass_kg: float = 1.2
    mass_centre_x_m: float = -0.115
    mass_centre_y_m: float = -0.020
    inertia_about_pivot_kg_m2: float = 0.050

    def __post_init__(self) -> None:
        _finite(self)
        r = self.drum_radius_m
        _require(0.05 <= r <= 0.5, "drum_radius_m", r, "0.05 to 0.5 m")
        _require(
            0.2 * r <= self.pivot_radius_m < r,
            "pivot_radius_m",
            self.pivot_radius_m,
            f"0.2 x drum radius to < drum radius ({0.2 * r:.4g} to {r:.4g} m)",
        )
        _require(
            0.0 < self.running_clearance_m < 0.1 * r,
            "running_clearance_m",
            self.running_clearance_m,
            f"> 0 and < 10 % of the drum radius ({0.1 * r:.4g} m)",
        )
        _require(
            90.0 < self.lining_start_deg < self.lining_end_deg < 270.0,
            "lining_start_deg",
            (self.lining_start_deg, self.lining_end_deg),
            "90 < lining_start_deg < lining_end_deg < 270 (the left half of the drum)",
        )
        _require(
            self.lining_end_deg - self.lining_start_deg <= 150.0,
            "lining_end_deg",
            self.lining_end_deg,
            "an arc of at most 150 deg",
        )
        _require(
            0.005 <= self.lining_width_m <= 0.2,
            "lining_width_m",
            self.lining_width_m,
            "5 to 200 mm",
        )
        _require(
            math.hypot(self.tip_x_m, self.tip_y_m) < r,
            "tip_x_m/tip_y_m",
            (self.tip_x_m, self.tip_y_m),
            "a point inside the drum",
        )
        _require(self.mass_kg >= 0, "mass_kg", self.mass_kg, ">= 0")
        _require(
            self.inertia_about_pivot_kg_m2 > 0,
            "inertia_about_pivot_kg_m2",
            self.inertia_about_pivot_kg_m2,
            "> 0",
        )
        gx = self.mass_centre_x_m - self.pivot_xy_m[0]
        gy = self.mass_centre_y_m - self.pivot_xy_m[1]
        arm2 = gx * gx + gy * gy
        _require(
            self.inertia_about_pivot_kg_m2 >= self.mass_kg * arm2,
            "inertia_about_pivot_kg_m2",
            self.inertia_about_pivot_kg_m2,
            f">= mass x (mass-centre distance from pivot)^2 = {self.mass_kg * arm2:.4g}"
            " kg m^2 (parallel-axis theorem)",
        )

    @property
    def pivot_xy_m(self) -> tuple[float, float]:
        """Left pivot position in the backing-plate frame, m."""
        a = math.radians(self.pivot_polar_angle_deg)
        return (self.pivot_radius_m * math.cos(a), self.pivot_radius_m * math.sin(a))


@dataclass(frozen=True)
class ContactParameters:
    """Hertzian line contact between lining and drum, Kelvin-Voigt normal force."""

    # Grey cast-iron drum.
    drum_youngs_modulus_pa: float = 110e9
    drum_poisson_ratio: float = 0.26
    # Organic friction lining in compression (literature range 0.3-5 GPa); the lining,
    # not the steel table, is what touches the drum.
    shoe_youngs_modulus_pa: float = 1.0e9
    shoe_poisson_ratio: float = 0.25
    # Contact damping. About 10 % of critical for the shoe's effective mass on the
    # contact stiffness, a coefficient of restitution near 0.7 at the first impact.
    damping_n_s_per_m: float = 1800.0

    def __post_init__(self) -> None:
        _finite(self)
        for name in ("drum_youngs_modulus_pa", "shoe_youngs_modulus_pa"):
            _require(
                1e6 <= getattr(self, name) <= 1e13, name, getattr(self, name), "1e6 to 1e13 Pa"
            )
        for name in ("drum_poisson_ratio", "shoe_poisson_ratio"):
            _require(0.0 <= getattr(self, name) < 0.5, name, getattr(self, name), "0 <= nu < 0.5")
        _require(self.damping_n_s_per_m >= 0, "damping_n_s_per_m", self.damping_n_s_per_m, ">= 0")

    @property
    def equivalent_modulus_pa(self) -> float:
        """E_eq = [(1 - nu_d^2)/E_d + (1 - nu_s^2)/E_s]^-1, Pa."""
        return 1.0 / (
            (1.0 - self.drum_poisson_ratio**2) / self.drum_youngs_modulus_pa
            + (1.0 - self.shoe_poisson_ratio**2) / self.shoe_youngs_modulus_pa
        )


@dataclass(frozen=True)
class FrictionParameters:
    """Coulomb friction smoothed near zero sliding speed: Ff = mu Fn tanh(v / v_s)."""

    # Calibrated for the published 6.6 s stop; within the 0.3-0.45 usual for organic
    # linings on cast iron.
    coefficient: float = 0.285
    # Smoothing width of the sign function, m/s of sliding speed. Below it the law is a
    # viscous damper (slope mu Fn / v_s), which sets the stiffness near standstill and
    # is also the speed at which the drum is declared at rest and locked.
    smoothing_speed_m_s: float = 0.02

    def __post_init__(self) -> None:
        _finite(self)
        _require(0.0 <= self.coefficient <= 1.0, "coefficient", self.coefficient, "0 to 1")
        _require(
            1e-5 <= self.smoothing_speed_m_s <= 1.0,
            "smoothing_speed_m_s",
            self.smoothing_speed_m_s,
            "1e-5 to 1 m/s",
        )


@dataclass(frozen=True)
class BrakeParameters:
    """Everything the physics needs apart from defects and actuation."""

    driveline: DrivelineParameters = field(default_factory=DrivelineParameters)
    shoe: ShoeGeometry = field(default_factory=ShoeGeometry)
    contact: ContactParameters = field(default_factory=ContactParameters)
    friction: FrictionParameters = field(default_factory=FrictionParameters)

    @property
    def contact_stiffness_n_per_m(self) -> float:
        """Hertzian line contact: k_c = (pi/4) E_eq l_c, N/m."""
        return math.pi / 4.0 * self.contact.equivalent_modulus_pa * self.shoe.lining_width_m

    def with_overrides(self, overrides: dict[str, dict[str, Any]]) -> BrakeParameters:
        """Return a copy with ``{"group": {"name": value}}`` overrides applied."""
        groups = {}
        for group_name, values in overrides.items():
            group = getattr(self, group_name)
            groups[group_name] = replace(group, **values)
        return replace(self, **groups)


PARAMETER_GROUPS: dict[str, type] = {
    "driveline": DrivelineParameters,
    "shoe": ShoeGeometry,
    "contact": ContactParameters,
    "friction": FrictionParameters,
}
