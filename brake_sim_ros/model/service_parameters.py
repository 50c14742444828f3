"""The service brake's parameters: its running clearance, wheel cylinder, hydraulic
circuit, return springs and rest stops, lining, and the tyre with the road's friction
(frozen dataclasses, SI units in every name; model/service.py and model/tyre.py use them).

Every value is a stated estimate with its source next to it; scenarios override them,
nothing else does. The study brake's core (:mod:`brake_sim_ros.model.parameters`) holds
the rest and carries these as ``BrakeParameters.service``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from brake_sim_ros.model.parameter_checks import require as _require
from brake_sim_ros.model.parameter_checks import require_finite as _finite

# Running clearance of the service brake, a shoe, at the lining: workshop specifications
# give about 0.6 mm on the drum's diameter (0.3 mm a shoe), which a self-adjuster holds as
# the lining wears (TESTBED figures for the service brake). The study brake's is 3.63 mm
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
# The closed bounds of the service brake's fields that are checked alone (field, low,
# high, what the refusal says is allowed): its adjuster's step and its lining over the arc.
SERVICE_LIMITS: tuple[tuple[str, float, float, str], ...] = (
    ("adjuster_step_m", 1e-6, 1e-3, "1 um to 1 mm"),
    ("lining_modulus_pa", 1e6, 1e11, "1e6 to 1e11 Pa"),
    ("lining_thickness_m", 0.001, 0.02, "1 to 20 mm"),
    ("lining_damping_time_s", 0.0, 1e-3, "0 to 1e-3 s"),
)
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
    # False (the service brake's figures hold with the arc, but it runs the urban cycle at 4x
    # real time, not 30x: docs/model.md): the study brake's point contact (Hertzian line).
    distributed_lining: bool = False
    # The self-adjuster (model/adjuster.py): a ratchet strut between the shoes at the wheel
    # cylinder, as leading-trailing rear drums with the cylinder at the top carry (the
    # Lucas-Girling and VW quadrant struts: a toothed quadrant on the leading shoe's web
    # engages the strut and turns by a tooth when the shoe's travel on application exceeds
    # the free play of its slot, which is set to the travel of the running clearance). The
    # running clearance a tooth takes up at the lining, m. Estimate: a tooth lengthens the
    # strut by about 0.2 mm, 0.1 mm at each tip, and the tip travels about twice the
    # clearance it closes (0.6 mm for 0.3 mm: return_spring_rate_n_per_m), so 0.05 mm.
    adjuster_step_m: float = 5.0e-5
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
        for name, low, high, allowed in SERVICE_LIMITS:
            value = getattr(self, name)
            _require(low <= value <= high, name, value, allowed)
        _require(
            0.0 <= self.stop_damping_n_s_per_m <= 1e5,
            "stop_damping_n_s_per_m",
            self.stop_damping_n_s_per_m,
            "0 to 1e5 N s/m (twice the critical damping of the stiffest stop on the shoe)",
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
