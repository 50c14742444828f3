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
    # The calibration (brake_sim_ros/studies/calibration.py) chose the values below once, for
    # the symmetric brake and cases 1, 5 and 7 together, within what a leading-trailing drum
    # brake of this size allows: pins on an anchor at the bottom, tips at one wheel cylinder
    # at the top. How the shoe sits between its pin and its piston, and what a pivot
    # defect does to it: brake_sim_ros.model.placement.place_shoe.
    #
    # Pivot pin 148 mm from the drum centre, 25 deg left of bottom dead centre (x = -63 mm:
    # two pins 125 mm apart on one anchor plate). The shoe first touches the
    # drum 90 deg from the pin (at 155 deg), where the normal force's arm is the whole pin
    # radius. The pin's polar angle decides how much a radial pin shift moves the lining:
    # only its part across the tip-pin line turns the shoe (about the tip), and a pin at the
    # bottom moves mostly along that line. 245 deg is the calibration's bound: the pivot
    # cases ask for the largest effect (validation report, notes on case 1).
    pivot_radius_m: float = 0.148
    pivot_polar_angle_deg: float = 245.0
    # Running clearance between lining and drum at rest. Together with the pin radius it
    # is the angular gap the shoe turns through before it strikes (1.35 deg); case 5
    # (+79.7 % peak force for a 2 deg tilt) sets that gap, and with the shoe's inertia it
    # puts the first impact at 56 N of the ramp. 3.5 mm is a worn, badly adjusted brake
    # rather than a new one (0.3-0.5 mm), as the study's gap implies.
    running_clearance_m: float = 0.0035
    # Lining arc: from 115 deg (toe, 15 deg past the tip) to 195 deg (heel, 50 deg short of
    # the pin): 80 deg of the usual 70-120, centred near where the shoe first touches
    # (155 deg), so that the contact stays on the lining for every defect of the study.
    lining_start_deg: float = 115.0
    lining_end_deg: float = 195.0
    # Lining (friction material) width along the drum axis: the Hertzian contact length.
    lining_width_m: float = 0.045
    # Shoe tip where the wheel-cylinder piston pushes, horizontally outward: 27 mm left of
    # the axis (a 54 mm cylinder between the two tips), 150 mm up, just inside the shoe's
    # web. The calibration's bound: a higher tip (farther from the pin) makes a pin shift
    # turn the shoe more.
    tip_x_m: float = -0.027
    tip_y_m: float = 0.150
    # Shoe mass and mass centre: web, table and lining as a uniform arc at 150 mm from the
    # pin (245 deg) to the tip (100 deg), centroid (-112, +15) mm, moved 16 mm toward the
    # heavier heel end (the anchor end of the web). Inertia about the pin: the arc's own
    # 0.0153 kg m^2 about its mass centre (radius of gyration 98 mm) plus m d^2 =
    # 0.0341 kg m^2. With the clearance it puts the first impact at 56 N.
    mass_kg: float = 1.6
    mass_centre_x_m: float = -0.120
    mass_centre_y_m: float = 0.0
    inertia_about_pivot_kg_m2: float = 0.0494

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
    # Contact damping. About 11 % of critical for the shoe's effective mass at the contact
    # (inertia / pin radius^2 = 2.3 kg) on the contact stiffness (3.7e7 N/m): a coefficient
    # of restitution near 0.7 at the first impact.
    damping_n_s_per_m: float = 2000.0

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

# Running clearance of the service brake, a shoe, at the lining: workshop specifications
# give about 0.6 mm on the drum's diameter (0.3 mm a shoe), which a self-adjuster holds as
# the lining wears (TESTBED figures for the service brake). The study brake's is 3.5 mm
# (ShoeGeometry.running_clearance_m), as its calibration needs.
SERVICE_RUNNING_CLEARANCE_M = 0.0003

# Bore of the wheel cylinder, m: 19.05 mm (3/4 in), a common passenger-car rear drum size
# (TESTBED). Written once: the service brake's pistons (ServiceBrakeParameters), the cycle's
# pressures (model/cycle.py) and the line-pressure sensor (sensing/kinds.py) read it here.
WHEEL_CYLINDER_BORE_M = 0.01905
# The road's friction coefficient by default (TyreParameters.road_friction, the scenario's
# top-level ``road_friction``): a locked tyre sliding on dry asphalt, and on wet asphalt
# (the figures a scenario names in the docs). Sliding (locked-wheel) coefficients of car
# tyres: dry asphalt about 0.7-0.85, wet 0.45-0.6 (Burckhardt's asphalt curves at 100 %
# slip give 0.76 dry and 0.51 wet, as tabulated in Kiencke and Nielsen, *Automotive
# Control Systems*, 2nd ed. 2005, ch. 7; skid-test tables of accident reconstruction
# agree). Their peaks are about 1.5 times these (below).
DRY_ROAD_FRICTION = 0.8
WET_ROAD_FRICTION = 0.5
# The limits of a road's sliding friction: glare ice (about 0.05) to a dry, high-grip
# surface (1.2).
ROAD_FRICTION_RANGE = (0.05, 1.2)
_G = 9.80665  # standard gravity, m/s^2 (model/vehicle.py GRAVITY_M_S2)


@dataclass(frozen=True)
class TyreParameters:
    """The service brake's tyre between vehicle (flywheel) and wheel (drum): a lumped
    LuGre law with the road's Stribeck curve (model/tyre.py). Its presliding stiffness
    replaces the study brake's torsional coupling (DrivelineParameters' coupling
    stiffness and damping are not read on the service brake).

    The friction coefficients are the road's: ``road_friction`` the sliding one (a locked
    tyre's at speed), ``road_friction x peak_ratio`` the peak (at zero slip speed). The
    LuGre coefficients are per newton of the wheel's load, as in Canudas-de-Wit et al.
    (2003).
    """

    # The road's sliding (locked-wheel) friction coefficient: dry asphalt by default
    # (DRY_ROAD_FRICTION, sources there). The scenario's ``road_friction`` sets it.
    road_friction: float = DRY_ROAD_FRICTION
    # Peak over sliding friction: Burckhardt's asphalt curves peak at 1.17 (dry) and 0.80
    # (wet) at 13-17 % slip against 0.76 and 0.51 locked: 1.54 and 1.57; 1.5 for both.
    # The lumped law puts its peak at zero slip speed (the breakaway of a held tyre).
    peak_ratio: float = 1.5
    # Stribeck curve: the friction falls from its peak to the sliding value over slip
    # speeds of a few m/s. Estimate: at 100 km/h Burckhardt's peaks lie at 3.6-4.7 m/s of
    # slip speed; 3 m/s with an exponent of 1 (an exponential) leaves 5 % of the peak's
    # excess at 9 m/s, so a locked tyre from highway speed slides at the sliding value
    # until the last few m/s.
    stribeck_speed_m_s: float = 3.0
    stribeck_exponent: float = 1.0
    # Presliding stiffness of the tread, 1/m (sigma0, N/m per N of load): Canudas-de-Wit
    # et al. (2003), the lumped model's parameters (sigma0 40 1/m, sigma1 4.9487 s/m,
    # sigma2 0.0018 s/m). On this wheel's 2328 N (237 kg, the mass the published flywheel
    # inertia stands for at the 0.268 m rolling radius, times g) it is 93 kN/m, 6710 N
    # m/rad between flywheel and drum (3.7 times the study's coupling of 1835 N m/rad);
    # the dry road's peak (1.2) deflects it 30 mm.
    presliding_stiffness_per_m: float = 40.0
    # Damping ratio of the vehicle's presliding mode (the vehicle on its held tyres,
    # ``sqrt(sigma0 g)`` = 19.8 rad/s, 3.2 Hz, whatever the load): 1, critical, so a car
    # that stops does not rock on its tyres (the study's coupling rocks at 0.014) and
    # returns to rest the fastest without overshoot. sigma1 = 2 zeta sqrt(sigma0 / g) =
    # 4.04 s/m (Canudas-de-Wit et al.'s 4.95 s/m is zeta = 1.22).
    presliding_damping_ratio: float = 1.0
    # Viscous term sigma2, s/m per N of load: 0. The sliding coefficient is a locked
    # tyre's as measured, speed dependence included (the Stribeck curve carries it); the
    # paper's 0.0018 s/m would add 0.05 to it at 100 km/h.
    viscous_s_per_m: float = 0.0

    def __post_init__(self) -> None:
        _finite(self)
        lo, hi = ROAD_FRICTION_RANGE
        _require(
            lo <= self.road_friction <= hi, "road_friction", self.road_friction, f"{lo:g} to {hi:g}"
        )
        for name, low, high in TYRE_LIMITS:
            value = getattr(self, name)
            _require(low <= value <= high, name, value, f"{low:g} to {high:g}")

    @property
    def peak_friction(self) -> float:
        """The road's peak friction coefficient (at zero slip speed)."""
        return self.road_friction * self.peak_ratio

    @property
    def presliding_damping_s_per_m(self) -> float:
        """sigma1, s/m per N of load: ``2 zeta sqrt(sigma0 / g)``."""
        return 2.0 * self.presliding_damping_ratio * math.sqrt(self.presliding_stiffness_per_m / _G)


# (field, low, high) of TyreParameters besides the road friction
TYRE_LIMITS: tuple[tuple[str, float, float], ...] = (
    ("peak_ratio", 1.0, 3.0),
    ("stribeck_speed_m_s", 0.1, 50.0),
    ("stribeck_exponent", 0.25, 4.0),
    ("presliding_stiffness_per_m", 1.0, 1000.0),
    ("presliding_damping_ratio", 0.05, 10.0),
    ("viscous_s_per_m", 0.0, 0.1),
)


@dataclass(frozen=True)
class ServiceBrakeParameters:
    """What the service brake adds to the study's core: a return spring per shoe, acting
    at the tip along the wheel-cylinder axis, that holds the shoe on a one-sided rest stop
    against the line's residual pressure (model/service.py).

    The spring pulls the tip inward with ``preload + rate x u`` (``u``: the tip's outward
    travel along the cylinder axis from its rest place, m); the stop is a contact
    (Kelvin-Voigt, pushing only while the shoe presses on it, never pulling) placed so that
    the healthy shoe rests on it at its rest angle; the wheel cylinder never pushes less
    than the residual pressure's force. A ``return_spring_weakening`` of ``w`` % scales
    every force of the spring by ``1 - w/100``: past ``1 - residual/preload`` (67 %) the
    spring no longer holds the shoe on its stop and the residual force drags it on the drum.
    """

    # Preload of the shoe's return spring at the tip, N. Estimate, kept from the study
    # brake's weak-spring defect (model/actuation.py RETURN_SPRING_PRELOAD_N) so that a
    # weakening means the same on both brakes: three times the residual force.
    return_spring_preload_n: float = 60.0
    # Rate of the return spring at the tip, N/m. Estimate: a coiled shoe return spring of
    # about 10 N/mm; the tip travels about 0.6 mm to close the 0.3 mm clearance, so the
    # spring's force grows by about 10 % of its preload before the lining touches.
    return_spring_rate_n_per_m: float = 10_000.0
    # Force of the residual line pressure on the wheel-cylinder piston, N: a check valve
    # keeps 0.5-1 bar in a drum brake's lines to seal the cups; 0.7 bar on a 19.05 mm
    # (3/4 in) bore is 20 N (model/actuation.py RESIDUAL_FORCE_N, the same figure). The
    # cylinder's force never falls below it.
    residual_force_n: float = 20.0
    # Stiffness of the rest stop (the shoe's web on the adjuster and anchor), N/m at the
    # tip. Estimate: steel on steel through the web, 1e7 N/m; the healthy preload's net
    # 40 N compresses it by 4 um. Its mode with the shoe's inertia at the tip (0.61 kg) is
    # at 644 Hz, level with the lining contact's (645 Hz: 3.7e7 N/m on 2.26 kg), so the
    # stop does not lower the physics step (solvers/stability.py includes its mode).
    stop_stiffness_n_per_m: float = 1.0e7
    # Damping of the rest stop, N s/m: 20 % of critical on the shoe's inertia at the tip
    # (estimate: a steel contact with the hold-down spring's friction), a coefficient of
    # restitution near 0.5 when the returning shoe lands.
    stop_damping_n_s_per_m: float = 1000.0
    # The hydraulic circuit (model/service.py): one wheel cylinder, two pistons of this bore,
    # fed through the line from the master cylinder. Bore: WHEEL_CYLINDER_BORE_M.
    wheel_cylinder_bore_m: float = WHEEL_CYLINDER_BORE_M
    # Compliance of the circuit seen from the wheel cylinder, m^3/Pa: the fluid it takes in
    # per pascal (hoses, line, fluid, the other wheel of the circuit, and the pedal, booster
    # and the driver's leg reflected through the master cylinder). Estimate from pedal feel:
    # a car's pedal travels about 0.85 mm per bar past its dead travel (30 mm for 35 bar)
    # at a pedal ratio of 3.5 on a 20.6 mm master cylinder (3.3 cm^2): 0.08 cm^3 per bar.
    # The hydraulic stiffness at a tip, A^2/C = 1.0e5 N/m, is 0.3 % of the lining contact's
    # (3.7e7 N/m) and 1 % of the rest stop's: the shoe follows the drum and pushes the fluid.
    line_compliance_m3_per_pa: float = 8.0e-13
    # Flow resistance of the line, Pa s/m^3, set for the pressure's rise time constant
    # R C = 30 ms: first-order models of a car's brake pressure build-up at the wheel use
    # 20-50 ms. The laminar resistance of 3 m of 3.2 mm steel line with fluid of 12 mPa s
    # (128 mu l / pi d^4) is 1.4e10 Pa s/m^3; the hose, the master cylinder's ports and the
    # valves make up the rest (stated estimate). The same resistance meters the fluid the
    # return springs push back on release (model/service.py).
    line_resistance_pa_s_per_m3: float = 3.75e10
    # The lining over its arc (model/lining.py), an elastic foundation ``(E/t) (delta + tau
    # delta')``. E, Pa, estimate: organic linings compress at 100-500 MPa in friction
    # materials' compressibility tests (SAE J2468, ISO 6310); the low end of the study
    # contact's 0.3-5 GPa, whose higher figures are bending and tensile moduli. t, m: car
    # drum linings are 4-6 mm new. tau, s, estimate: 10 % of critical at the shoe's mode
    # on its whole arc (2.6 kHz), ``2 zeta / omega``, as the study contact's 11 %.
    lining_modulus_pa: float = 3.0e8
    lining_thickness_m: float = 0.005
    lining_damping_time_s: float = 1.2e-5
    # False (until the service brake's figures are re-measured with the arc: docs/model.md):
    # the study brake's point contact (Hertzian line) in place of the arc.
    distributed_lining: bool = False
    # The tyre between vehicle and wheel (model/tyre.py), with the road's friction.
    tyre: TyreParameters = field(default_factory=TyreParameters)

    def __post_init__(self) -> None:
        _finite(self)
        _require(
            0.005 <= self.wheel_cylinder_bore_m <= 0.05,
            "wheel_cylinder_bore_m",
            self.wheel_cylinder_bore_m,
            "5 to 50 mm",
        )
        _require(
            1e-16 <= self.line_compliance_m3_per_pa <= 1e-10,
            "line_compliance_m3_per_pa",
            self.line_compliance_m3_per_pa,
            "1e-16 to 1e-10 m^3/Pa",
        )
        _require(
            1e7 <= self.line_resistance_pa_s_per_m3 <= 1e14,
            "line_resistance_pa_s_per_m3",
            self.line_resistance_pa_s_per_m3,
            "1e7 to 1e14 Pa s/m^3",
        )
        _require(
            0.0 < self.return_spring_preload_n <= 2000.0,
            "return_spring_preload_n",
            self.return_spring_preload_n,
            "> 0 and at most 2000 N",
        )
        _require(
            0.0 <= self.return_spring_rate_n_per_m <= 1e6,
            "return_spring_rate_n_per_m",
            self.return_spring_rate_n_per_m,
            "0 to 1e6 N/m",
        )
        _require(
            0.0 <= self.residual_force_n < self.return_spring_preload_n,
            "residual_force_n",
            self.residual_force_n,
            f">= 0 and below the spring's preload ({self.return_spring_preload_n:g} N),"
            " or a healthy spring could not hold the shoe on its stop",
        )
        _require(
            1e5 <= self.stop_stiffness_n_per_m <= 1e9,
            "stop_stiffness_n_per_m",
            self.stop_stiffness_n_per_m,
            "1e5 to 1e9 N/m",
        )
        for name, low, high, allowed in (
            ("lining_modulus_pa", 1e6, 1e11, "1e6 to 1e11 Pa"),
            ("lining_thickness_m", 0.001, 0.02, "1 to 20 mm"),
            ("lining_damping_time_s", 0.0, 1e-3, "0 to 1e-3 s"),
        ):
            value = getattr(self, name)
            _require(low <= value <= high, name, value, allowed)
        _require(
            self.stop_damping_n_s_per_m >= 0.0,
            "stop_damping_n_s_per_m",
            self.stop_damping_n_s_per_m,
            ">= 0",
        )

    @property
    def piston_area_m2(self) -> float:
        """Area of one wheel-cylinder piston, m^2: ``pi bore^2 / 4``."""
        return math.pi * self.wheel_cylinder_bore_m**2 / 4.0

    @property
    def lining_foundation_pa_per_m(self) -> float:
        """The lining's foundation modulus ``k_w = E / t``, Pa/m (pressure per metre of
        penetration)."""
        return self.lining_modulus_pa / self.lining_thickness_m

    @property
    def line_time_constant_s(self) -> float:
        """The line pressure's rise time constant ``R C``, s."""
        return self.line_resistance_pa_s_per_m3 * self.line_compliance_m3_per_pa

    @property
    def hold_weakening_pct(self) -> float:
        """The weakening (%) past which the spring no longer holds the shoe on its stop
        against the residual force: ``100 (1 - residual / preload)``."""
        return 100.0 * (1.0 - self.residual_force_n / self.return_spring_preload_n)


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
        shoe = replace(ShoeGeometry(), running_clearance_m=SERVICE_RUNNING_CLEARANCE_M)
        return cls(shoe=shoe, service=ServiceBrakeParameters())

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
