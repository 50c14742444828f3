"""The vehicle around the brake: road load on the flywheel (compiled), and its parameters.

The flywheel carries this brake's share of the vehicle's inertia (MODEL.md); the brake
sits on a non-driven axle, so both the traction and the road load reach it through the
vehicle, that is through the flywheel, never through the drum. With the flywheel speed
``w_f`` (rad/s, positive counter-clockwise: forward) the vehicle moves at ``v = w_f r_w``
and the road load on the flywheel is the torque (N m, opposing forward motion)::

    T_road = r_w (m_share g (c_rr cos(a) s(v) + sin(a)) + share rho C_d A v |v| / 2)

* ``m_share = I_f / r_w^2``: the mass the flywheel stands for (so the flywheel inertia is
  written once: a heavier load, ``load_factor``, scales it and the road load with it);
* ``share``: the fraction of the whole vehicle's mass on this flywheel; the drag acts on
  the whole vehicle, this brake's inertia takes its share of it;
* ``a = atan(grade_pct / 100)``: the road's slope, uphill positive (the grade pulls a
  vehicle on a downhill forward, ``sin(a) < 0``);
* ``s(v) = tanh(v / v_r)``: rolling resistance as a smoothed sign, width
  :data:`ROLLING_SMOOTHING_SPEED_M_S`: a stopped vehicle gets no rolling force that could
  push it backwards; below ``v_r`` it acts as a viscous damper. Its stiffness
  ``dT/dw = I_f g c_rr cos(a) / v_r`` (167 N m s for the defaults) gives the flywheel a time
  constant of 0.1 s, far above any physics step.

A drive cycle's hold may change the vehicle's load while it stands (model/cycle.py): a load
factor ``f`` (the vehicle's mass over the mass the packed flywheel inertia stands for)
scales the flywheel inertia and the road-load forces that scale with mass, rolling
resistance and grade (:func:`scale_load`); the aerodynamic drag does not.

No tyre slip, no load transfer between axles. Pure: no files, no transport.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.compiled import JIT
from brake_sim_ros.model.smooth_sign import smooth_sign

GRAVITY_M_S2 = 9.80665  # standard gravity
# Width of the rolling resistance's smoothed sign, m/s (0.036 km/h): well below any speed
# a cycle targets, wide enough that the term stays smooth for the physics step.
ROLLING_SMOOTHING_SPEED_M_S = 0.01
# The published event's speed pair: 103.5 rad/s is 100 km/h, so the rolling radius is
# 27.78 m/s / 103.5 rad/s = 0.268 m (a 195/65 R15 tyre rolls at about 0.30 m; the spec's
# pair is kept, so that km/h and rad/s agree with MODEL.md).
DEFAULT_WHEEL_RADIUS_M = (100.0 / 3.6) / 103.5
# The vehicle load factor's range (a half-empty to a three-times-laden vehicle): the limits
# of a drawn condition (fleet/conditions.py) and of a cycle's per-stop load (model/cycle.py).
LOAD_FACTOR_RANGE = (0.5, 3.0)

# The speed controller's settings by default (a [cycle]'s, and a live drive's): this
# brake's share of the traction (120 N m gives the nominal 17.1 kg m^2 about 1.8 m/s^2)
# and the time constant of its approach to a target speed.
DEFAULT_MAX_DRIVE_TORQUE_N_M = 120.0
DEFAULT_SPEED_TIME_CONSTANT_S = 1.0


@dataclass(frozen=True)
class Vehicle:
    """The vehicle whose inertia share the flywheel is (scenario table ``[vehicle]``).

    Defaults: typical passenger-car values (Gillespie, *Fundamentals of Vehicle
    Dynamics*, ch. 4; Wong, *Theory of Ground Vehicles*, ch. 1 and 3).

    Attributes:
        wheel_radius_m: rolling radius, m (default: the published 103.5 rad/s = 100 km/h).
        mass_share: fraction of the vehicle's mass on this brake's flywheel (one wheel of
            four: 0.25). Sets this brake's share of the aerodynamic drag.
        rolling_resistance: rolling-resistance coefficient ``c_rr`` (car tyres on asphalt
            0.008-0.015; 0.010).
        drag_area_m2: ``C_d A`` of the whole vehicle, m^2 (a compact car: C_d 0.30 x
            A 2.2 m^2 = 0.66).
        air_density_kg_m3: air density, kg/m^3 (ISA sea level, 15 degC: 1.225).
        grade_pct: road grade, % (rise over run, uphill positive in the direction of
            travel; -6 % is a steep mountain-road descent).
        max_drive_torque_n_m: a live drive's largest drive torque on the flywheel, N m
            (this brake's share of the traction; model/cycle.py LiveDrive): a torque
            command above it is refused, the speed controller is clamped to it. A
            ``[cycle]`` has its own (``Cycle.max_drive_torque_n_m``).
        speed_time_constant_s: a live target speed's controller time constant, s (the
            first-order approach of model/cycle.py); a ``[cycle]`` has its own.
    """

    wheel_radius_m: float = DEFAULT_WHEEL_RADIUS_M
    mass_share: float = 0.25
    rolling_resistance: float = 0.010
    drag_area_m2: float = 0.66
    air_density_kg_m3: float = 1.225
    grade_pct: float = 0.0
    max_drive_torque_n_m: float = DEFAULT_MAX_DRIVE_TORQUE_N_M
    speed_time_constant_s: float = DEFAULT_SPEED_TIME_CONSTANT_S

    def __post_init__(self) -> None:
        for name, lo, hi in LIMITS:
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ParameterError(f"vehicle {name} {value!r}: allowed a number")
            if not (math.isfinite(value) and lo <= value <= hi) or (
                name in _POSITIVE and value == 0.0
            ):
                low = f"> {lo:g}" if name in _POSITIVE else f">= {lo:g}"
                raise ParameterError(f"vehicle {name} {value!r}: allowed {low} and <= {hi:g}")

    @property
    def grade_rad(self) -> float:
        return math.atan(self.grade_pct / 100.0)

    def mass_on_flywheel_kg(self, flywheel_inertia_kg_m2: float) -> float:
        """``I_f / r_w^2``: the mass the flywheel stands for, kg."""
        return flywheel_inertia_kg_m2 / self.wheel_radius_m**2


# (field, low, high) of the speed controller's settings: a live drive's here, a cycle's
# in model/cycle.py LIMITS (the same ranges, written here once)
DRIVE_LIMITS: tuple[tuple[str, float, float], ...] = (
    ("max_drive_torque_n_m", 0.0, 10_000.0),
    ("speed_time_constant_s", 0.01, 100.0),
)
# (field, low, high): the model's limits (a wheel from 0.1 to 1 m, a grade up to 30 %)
LIMITS: tuple[tuple[str, float, float], ...] = (
    ("wheel_radius_m", 0.1, 1.0),
    ("mass_share", 0.0, 1.0),
    ("rolling_resistance", 0.0, 0.1),
    ("drag_area_m2", 0.0, 20.0),
    ("air_density_kg_m3", 0.0, 2.0),
    ("grade_pct", -30.0, 30.0),
    *DRIVE_LIMITS,
)
_POSITIVE = frozenset({"wheel_radius_m", "mass_share"})


def pack_vehicle(p: np.ndarray, vehicle: Vehicle) -> None:
    """Write ``vehicle``'s road load into the packed vector ``p`` (layout.P_DRIVEN ...),
    for the flywheel inertia already packed in it; sets P_DRIVEN."""
    mass = vehicle.mass_on_flywheel_kg(float(p[L.P_FLYWHEEL_INERTIA]))
    a = vehicle.grade_rad
    p[L.P_DRIVEN] = 1.0
    p[L.P_WHEEL_RADIUS] = vehicle.wheel_radius_m
    p[L.P_ROLLING_FORCE] = mass * GRAVITY_M_S2 * vehicle.rolling_resistance * math.cos(a)
    p[L.P_GRADE_FORCE] = mass * GRAVITY_M_S2 * math.sin(a)
    p[L.P_DRAG_FACTOR] = vehicle.mass_share * 0.5 * vehicle.air_density_kg_m3 * vehicle.drag_area_m2
    p[L.P_ROLLING_SMOOTHING_SPEED] = ROLLING_SMOOTHING_SPEED_M_S
    p[L.P_DRIVE_TORQUE] = 0.0


@njit(inline="always", **JIT)
def road_load_torque(p, flywheel_speed):
    """Road load on the flywheel at ``flywheel_speed`` (rad/s), N m, opposing forward
    motion (see the module doc); the rule, written once."""
    r = p[L.P_WHEEL_RADIUS]
    v = flywheel_speed * r
    rolling = p[L.P_ROLLING_FORCE] * smooth_sign(v / p[L.P_ROLLING_SMOOTHING_SPEED])
    return r * (rolling + p[L.P_GRADE_FORCE] + p[L.P_DRAG_FACTOR] * v * abs(v))


@njit(inline="always", **JIT)
def scale_load(p, pw, factor):
    """Set in ``pw`` (the kernel's working copy of ``p``) the flywheel inertia and the
    road-load forces that scale with the vehicle's mass (rolling resistance, grade) for the
    load ``factor`` (dimensionless, over ``p``'s); the aerodynamic drag is kept. The rule,
    written once."""
    pw[L.P_FLYWHEEL_INERTIA] = p[L.P_FLYWHEEL_INERTIA] * factor
    pw[L.P_ROLLING_FORCE] = p[L.P_ROLLING_FORCE] * factor
    pw[L.P_GRADE_FORCE] = p[L.P_GRADE_FORCE] * factor
