"""Unpack parameters and defects into the kernels' flat arrays, checking validity once."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model import kernel
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.parameters import BrakeParameters

SIDES = ("left", "right")


@dataclass(frozen=True)
class ModelOptions:
    """What the assembled model carries (fidelity choices that change the equations).

    Attributes:
        rigid_coupling: flywheel and drum as one rigid body (no torsional mode).
        shoes: which shoes are in the model; a removed shoe stays retracted.
    """

    rigid_coupling: bool = False
    shoes: tuple[str, ...] = SIDES


@dataclass(frozen=True)
class ShoePlacement:
    """One shoe's resolved world geometry at its symmetric rest angle (defects applied)."""

    sign: float
    pivot_xy_m: tuple[float, float]
    lining_centre_xy_m: tuple[float, float]
    lining_radius_m: float
    lining_mid_rad: float
    lining_half_rad: float
    tip_xy_m: tuple[float, float]
    actuation_dir: tuple[float, float]
    mass_centre_xy_m: tuple[float, float]


def place_shoe(params: BrakeParameters, side: str, defect: ShoeDefect) -> ShoePlacement:
    """Resolve a shoe's geometry. A pivot-radius defect moves the pivot radially and the
    whole shoe with it (the shoe is carried by its pin)."""
    g = params.shoe
    mirror = -1.0 if side == "right" else 1.0
    px, py = g.pivot_xy_m
    px *= mirror
    shift = defect.pivot_radius_change_pct / 100.0
    sx, sy = shift * px, shift * py
    start, end = g.lining_start_deg, g.lining_end_deg
    if side == "right":
        start, end = 180.0 - end, 180.0 - start
    return ShoePlacement(
        sign=mirror,
        pivot_xy_m=(px + sx, py + sy),
        lining_centre_xy_m=(sx, sy),
        lining_radius_m=g.drum_radius_m - g.running_clearance_m,
        lining_mid_rad=math.radians(0.5 * (start + end)),
        lining_half_rad=math.radians(0.5 * (end - start)),
        tip_xy_m=(mirror * g.tip_x_m + sx, g.tip_y_m + sy),
        actuation_dir=(-mirror, 0.0),
        mass_centre_xy_m=(mirror * g.mass_centre_x_m + sx, g.mass_centre_y_m + sy),
    )


def pack(
    params: BrakeParameters, defects: Defects, options: ModelOptions | None = None
) -> np.ndarray:
    """Packed parameter vector for the kernels (layout.P_* / S_*), after validity checks."""
    options = options or ModelOptions()
    unknown = set(options.shoes) - set(SIDES)
    if unknown or not options.shoes:
        raise ParameterError(
            f"model shoes {options.shoes!r}: allowed a non-empty subset of {SIDES}"
        )
    d = params.driveline
    p = np.zeros(L.N_PARAMS)
    p[L.P_FLYWHEEL_INERTIA] = d.flywheel_inertia_kg_m2
    p[L.P_DRUM_INERTIA] = d.drum_inertia_kg_m2
    p[L.P_COUPLING_STIFFNESS] = d.coupling_stiffness_n_m_per_rad
    p[L.P_COUPLING_DAMPING] = d.coupling_damping_n_m_s_per_rad
    p[L.P_DRUM_RADIUS] = params.shoe.drum_radius_m
    p[L.P_CONTACT_STIFFNESS] = params.contact_stiffness_n_per_m
    p[L.P_CONTACT_DAMPING] = params.contact.damping_n_s_per_m
    p[L.P_FRICTION_COEFFICIENT] = params.friction.coefficient
    p[L.P_FRICTION_SMOOTHING_SPEED] = params.friction.smoothing_speed_m_s
    p[L.P_RIGID_COUPLING] = 1.0 if options.rigid_coupling else 0.0
    for i, side in enumerate(SIDES):
        defect: ShoeDefect = getattr(defects, side)
        s = place_shoe(params, side, defect)
        b = L.P_SHOE_BASE + i * L.SHOE_STRIDE
        p[b + L.S_SIGN] = s.sign
        p[b + L.S_PIVOT_X], p[b + L.S_PIVOT_Y] = s.pivot_xy_m
        p[b + L.S_LINING_CENTRE_X], p[b + L.S_LINING_CENTRE_Y] = s.lining_centre_xy_m
        p[b + L.S_LINING_RADIUS] = s.lining_radius_m
        p[b + L.S_LINING_MID_ANGLE] = s.lining_mid_rad
        p[b + L.S_LINING_HALF_ANGLE] = s.lining_half_rad
        p[b + L.S_LINING_MID_COS] = math.cos(s.lining_mid_rad)
        p[b + L.S_LINING_MID_SIN] = math.sin(s.lining_mid_rad)
        p[b + L.S_LINING_HALF_COS] = math.cos(s.lining_half_rad)
        p[b + L.S_LINING_HALF_SIN] = math.sin(s.lining_half_rad)
        p[b + L.S_TIP_X], p[b + L.S_TIP_Y] = s.tip_xy_m
        p[b + L.S_ACTUATION_DIR_X], p[b + L.S_ACTUATION_DIR_Y] = s.actuation_dir
        p[b + L.S_MASS] = params.shoe.mass_kg
        p[b + L.S_MASS_CENTRE_X], p[b + L.S_MASS_CENTRE_Y] = s.mass_centre_xy_m
        p[b + L.S_INERTIA] = params.shoe.inertia_about_pivot_kg_m2
        p[b + L.S_ACTUATION_GAIN] = defect.actuation_gain
        p[b + L.S_ENABLED] = 1.0 if side in options.shoes else 0.0
        _check_shoe(params, side, defect, s, p, b)
    return p


def _check_shoe(
    params: BrakeParameters,
    side: str,
    defect: ShoeDefect,
    s: ShoePlacement,
    p: np.ndarray,
    base: int,
) -> None:
    lining_radius = s.lining_radius_m
    pivot_r = math.hypot(*s.pivot_xy_m)
    if pivot_r >= lining_radius:
        raise ParameterError(
            f"{side} pivot radius change {defect.pivot_radius_change_pct:+g} % puts the pivot"
            f" {pivot_r * 1e3:.1f} mm from the drum centre, at or beyond the lining surface"
            f" ({lining_radius * 1e3:.1f} mm): allowed a pivot inside the shoe"
        )
    eps0 = indentation_at(p, base, math.radians(defect.initial_angle_deg))
    if eps0 >= 0.0:
        raise ParameterError(
            f"{side} shoe defects (pivot radius {defect.pivot_radius_change_pct:+g} %, initial"
            f" angle {defect.initial_angle_deg:+g} deg) start the lining {eps0 * 1e3:.3f} mm"
            " inside the drum: allowed only defects that leave the shoe clear of the drum at"
            f" the start (running clearance {params.shoe.running_clearance_m * 1e3:.2f} mm)"
        )


def indentation_at(p: np.ndarray, base: int, theta_rad: float) -> float:
    """Indentation (m, positive = penetration) of a shoe held at ``theta_rad``."""
    out = kernel.shoe_eval(p, base, theta_rad, 0.0, 0.0, 0.0, L.CONTACT_AUTO)
    return float(out[2])


def initial_state(params: BrakeParameters, defects: Defects) -> np.ndarray:
    """State at t = 0: flywheel and drum at the initial speed, shoes at rest."""
    y = np.zeros(L.N_STATE)
    y[L.Y_FLYWHEEL_SPEED] = params.driveline.initial_speed_rad_s
    y[L.Y_DRUM_SPEED] = params.driveline.initial_speed_rad_s
    y[L.Y_LEFT_ANGLE] = math.radians(defects.left.initial_angle_deg)
    y[L.Y_RIGHT_ANGLE] = math.radians(defects.right.initial_angle_deg)
    return y
