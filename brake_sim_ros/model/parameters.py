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
from dataclasses import dataclass, field, replace
from typing import Any

from brake_sim_ros.model.parameter_checks import require as _require
from brake_sim_ros.model.parameter_checks import require_finite as _finite
from brake_sim_ros.model.service_parameters import (
    SERVICE_RUNNING_CLEARANCE_M,
    ServiceBrakeParameters,
)


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


# Pose rules: which three contacts hold a shoe at rest (model/placement.py place_shoe).
# "tip-abutment": the tip held both ways by the piston, the heel in a seat open along the
# tip-pin line; "eye-piston": the heel in an eye on its pin, the tip on the piston's stop.
POSES: tuple[str, ...] = ("tip-abutment", "eye-piston")
# The parameters whose values are names, not numbers ("group.field"), and the names allowed
# (a scenario's [parameters.<group>], the node's parameters, a recording's model).
NAMED_FIELDS: dict[str, tuple[str, ...]] = {"shoe.pose": POSES}


@dataclass(frozen=True)
class ShoeGeometry:
    """Rigid-shoe geometry of the LEFT shoe at rest; the right shoe mirrors it about y.

    Angles are polar angles in the backing-plate frame, degrees, measured
    counter-clockwise from +x (180 deg points left).
    """

    drum_radius_m: float = 0.180  # [published]
    # The study brake's shoe: a geometry of the calibration's space (leading-trailing,
    # pins at the bottom, tips at one wheel cylinder at the top;
    # brake_sim_ros/studies/calibration.py) drawn by the pose-rule study
    # (brake_sim_ros/studies/pose_rule_study.py --sample 1500, seed 28) that puts the
    # symmetric brake and cases 1, 5 and 7 in their published bands with the heel in an eye
    # on its pin, rounded. How the shoe sits and what a moved pin does to it: ``pose`` and
    # brake_sim_ros.model.placement.place_shoe.
    #
    # Pivot pin 134 mm from the drum centre, 22 deg left of bottom dead centre (x = -50 mm:
    # two pins 100 mm apart on one anchor plate). The shoe first touches the drum near
    # 159 deg, about 90 deg from the pin, where the normal force's arm is nearly the whole pin
    # radius.
    pivot_radius_m: float = 0.134
    pivot_polar_angle_deg: float = 248.0
    # Running clearance between lining and drum at rest. With the pin radius it is the
    # angular gap the shoe turns through before it strikes (1.55 deg); case 5 (+79.7 % peak
    # force for a 2 deg tilt) sets that gap, and with the shoe's inertia it puts the first
    # impact at 55 N of the ramp. 3.63 mm is a worn, badly adjusted brake rather than a new
    # one (0.3-0.5 mm), as the study's gap implies.
    running_clearance_m: float = 0.00363
    # Lining arc: from 114.4 deg (toe, 15 deg past the tip) to 198 deg (heel, 50 deg short
    # of the pin): 84 deg of the usual 70-120, around where the shoe first touches.
    lining_start_deg: float = 114.4
    lining_end_deg: float = 198.0
    # Lining (friction material) width along the drum axis: the Hertzian contact length.
    lining_width_m: float = 0.045
    # Shoe tip where the wheel-cylinder piston pushes, horizontally outward: 21 mm left of
    # the axis (a 42 mm cylinder between the two tips), 127 mm up, inside the shoe's web.
    tip_x_m: float = -0.021
    tip_y_m: float = 0.127
    # Shoe mass and mass centre (web, table and lining): 1.26 kg at (-109, +13) mm, 150 mm
    # from the pin. Inertia about the pin: 0.0100 kg m^2 about the mass centre (radius of
    # gyration 89 mm) plus m d^2 = 0.0282 kg m^2. With the clearance it puts the first
    # impact at 55 N.
    mass_kg: float = 1.26
    mass_centre_x_m: float = -0.1094
    mass_centre_y_m: float = 0.0132
    inertia_about_pivot_kg_m2: float = 0.0382
    # How the shoe sits between its pin and its piston, which decides where a moved pin
    # puts it (POSES; brake_sim_ros.model.placement.place_shoe). The study's shoe: the heel
    # in an eye on its pin, the tip on the piston held on its stop. With it a 3 % outward
    # pin closes the study's case-1 share of the clearance (the validation report's notes
    # on case 1, where the tip abutment is shown to close too little).
    pose: str = "eye-piston"

    def __post_init__(self) -> None:
        _finite(self)
        _require(self.pose in POSES, "pose", self.pose, f"one of {list(POSES)}")
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
        _require(self.mass_kg > 0, "mass_kg", self.mass_kg, "> 0")
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


# The service brake's shoe (BrakeParameters.of_brake): a leading-trailing brake of the same
# drum with its heels on an anchor at the bottom and its tips at one wheel cylinder at the
# top, the heel in a seat open along the tip-pin line (the tip abutment), at the service
# running clearance (SERVICE_RUNNING_CLEARANCE_M; a self-adjuster keeps it). The layout
# is the one the study brake had until issue 28 took the eye-piston pose for the study:
# * pin 148 mm from the drum centre, 25 deg left of bottom dead centre (x = -63 mm: two
#   pins 125 mm apart on one anchor plate); the shoe first touches the drum 90 deg from
#   the pin (at 155 deg), where the normal force's arm is the whole pin radius;
# * lining from 115 deg (toe, 15 deg past the tip) to 195 deg (heel, 50 deg short of the
#   pin): 80 deg of the usual 70-120;
# * tip 27 mm left of the axis (a 54 mm cylinder between the two tips), 150 mm up;
# * mass 1.6 kg: web, table and lining as a uniform arc at 150 mm from the pin (245 deg)
#   to the tip (100 deg), centroid (-112, +15) mm, moved 16 mm toward the heavier heel
#   end; inertia about the pin: the arc's own 0.0153 kg m^2 about its mass centre (radius
#   of gyration 98 mm) plus m d^2 = 0.0341 kg m^2.
SERVICE_SHOE = ShoeGeometry(
    pivot_radius_m=0.148,
    pivot_polar_angle_deg=245.0,
    running_clearance_m=SERVICE_RUNNING_CLEARANCE_M,
    lining_start_deg=115.0,
    lining_end_deg=195.0,
    tip_x_m=-0.027,
    tip_y_m=0.150,
    mass_kg=1.6,
    mass_centre_x_m=-0.120,
    mass_centre_y_m=0.0,
    inertia_about_pivot_kg_m2=0.0494,
    pose="tip-abutment",
)


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
    # Contact damping. About 6 % of critical for the study shoe's effective mass at the
    # contact (inertia / pin radius^2 = 2.1 kg) on the contact stiffness (3.7e7 N/m): a
    # coefficient of restitution near 0.8 at the first impact. Chosen with the study's
    # shoe (ShoeGeometry), whose first-impact peak and period it sets with the clearance.
    damping_n_s_per_m: float = 1000.0

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


# The service brake's contact: its damping about 11 % of critical for its shoe's effective
# mass at the contact (inertia / pin radius^2 = 2.3 kg) on the contact stiffness
# (3.7e7 N/m), a coefficient of restitution near 0.7 at the first impact.
SERVICE_CONTACT = ContactParameters(damping_n_s_per_m=2000.0)


@dataclass(frozen=True)
class FrictionParameters:
    """Coulomb friction smoothed near zero sliding speed: Ff = mu Fn tanh(v / v_s)."""

    # Calibrated, with the 1300 N peak actuation force, for the published 6.6 s stop: at the
    # low end of the 0.25-0.45 of organic linings on cast iron.
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


# The brakes a scenario chooses from (its top-level key ``brake``): the study's model as
# published and calibrated, and the service brake, the same core with what a drum brake in a
# car has (return springs holding each shoe on its rest stop, a running clearance as
# workshops set it). "study" is the default: the published cases stay on it.
BRAKES: tuple[str, ...] = ("study", "service")
DEFAULT_BRAKE = "study"


@dataclass(frozen=True)
class BrakeParameters:
    """Everything the physics needs apart from defects and actuation.

    ``service``: the service brake's return springs and rest stops
    (:class:`ServiceBrakeParameters`); None for the study brake (the published model).
    """

    driveline: DrivelineParameters = field(default_factory=DrivelineParameters)
    shoe: ShoeGeometry = field(default_factory=ShoeGeometry)
    contact: ContactParameters = field(default_factory=ContactParameters)
    friction: FrictionParameters = field(default_factory=FrictionParameters)
    service: ServiceBrakeParameters | None = None

    @classmethod
    def of_brake(cls, brake: str) -> BrakeParameters:
        """The default parameters of the brake named ``brake`` (:data:`BRAKES`): the study
        brake's, or the service brake's (its springs and stops, and the service running
        clearance)."""
        _require(brake in BRAKES, "brake", brake, f"one of {list(BRAKES)}")
        if brake == "study":
            return cls()
        return cls(shoe=SERVICE_SHOE, contact=SERVICE_CONTACT, service=ServiceBrakeParameters())

    @property
    def brake(self) -> str:
        """The brake these parameters describe: "service" with springs, else "study"."""
        return "study" if self.service is None else "service"

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


# Unit of a field from its name's suffix, longest first ("dimensionless" without one).
UNIT_SUFFIXES: tuple[tuple[str, str], ...] = (
    ("_n_m_s_per_rad", "N m s/rad"),
    ("_n_m_per_rad", "N m/rad"),
    ("_n_s_per_m", "N s/m"),
    ("_n_per_m", "N/m"),
    ("_s_per_m", "s/m"),
    ("_per_m", "1/m"),
    ("_pa_s_per_m3", "Pa s/m^3"),
    ("_m3_per_pa", "m^3/Pa"),
    ("_kg_m2", "kg m^2"),
    ("_rad_s", "rad/s"),
    ("_m_s", "m/s"),
    ("_pct", "%"),
    ("_ms", "ms"),
    ("_hz", "Hz"),
    ("_deg", "deg"),
    ("_kg", "kg"),
    ("_pa", "Pa"),
    ("_mm", "mm"),
    ("_um", "um"),
    ("_m", "m"),
    ("_n", "N"),
)


def unit_of(field_name: str) -> str:
    """The unit a field's name ends in (``tip_x_m`` -> ``m``), or ``dimensionless``."""
    for suffix, unit in UNIT_SUFFIXES:
        if field_name.endswith(suffix):
            return unit
    return "dimensionless"


PARAMETER_GROUPS: dict[str, type] = {
    "driveline": DrivelineParameters,
    "shoe": ShoeGeometry,
    "contact": ContactParameters,
    "friction": FrictionParameters,
}
