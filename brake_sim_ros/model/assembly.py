"""Unpack parameters and defects into the kernels' flat arrays, checking validity once."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model import growth, kernel, service, thermal
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.actuation import RESIDUAL_FORCE_N, RETURN_SPRING_PRELOAD_N
from brake_sim_ros.model.catalogue import KIND_BY_NAME
from brake_sim_ros.model.defects import (
    MAX_DRUM_SLOPE,
    SERVICE_RUNOUT_UM,
    Defects,
    DrumDefect,
    ShoeDefect,
)
from brake_sim_ros.model.parameters import BrakeParameters

SIDES = L.SIDES


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
    """One shoe's assembled geometry at its symmetric rest angle (defects applied), in the
    backing-plate frame (m, rad).

    Attributes:
        sign: +1 left shoe (outward = counter-clockwise), -1 right shoe (mirror image).
        pivot_xy_m: the pin, the axis the shoe turns about in service.
        lining_centre_xy_m, lining_radius_m, lining_mid_rad, lining_half_rad: the lining
            arc (centre, radius, polar angle of its middle seen from the centre, half span).
        tip_xy_m: where the piston pushes; it stays on the piston whatever the pin does.
        actuation_dir: unit direction of the piston's push (fixed in the backing plate).
        mass_centre_xy_m: the shoe's mass centre.
        inertia_about_pivot_kg_m2: moment of inertia about the pin (parallel-axis theorem
            from the nominal value, for the pin's place in the shoe's heel seat).
        abutment_turn_rad: angle the shoe body turned about its tip abutment to follow
            the pin, rad, in the shoe's own sense (counter-clockwise for the left shoe,
            clockwise for the right one, as its angle).
        heel_seat_offset_m: part of the pin's displacement along the tip-pin line, taken
            up in the heel seat (positive: the pin moved away from the tip), m.
    """

    sign: float
    pivot_xy_m: tuple[float, float]
    lining_centre_xy_m: tuple[float, float]
    lining_radius_m: float
    lining_mid_rad: float
    lining_half_rad: float
    tip_xy_m: tuple[float, float]
    actuation_dir: tuple[float, float]
    mass_centre_xy_m: tuple[float, float]
    inertia_about_pivot_kg_m2: float
    abutment_turn_rad: float
    heel_seat_offset_m: float


def place_shoe(params: BrakeParameters, side: str, defect: ShoeDefect) -> ShoePlacement:
    """Assemble a shoe between its two abutments: the pin at the heel, the piston at the tip.

    The nominal geometry (:class:`ShoeGeometry`, left shoe) has the lining concentric with
    the drum at rest. A pivot-radius defect moves the pin radially, ``delta = pct/100 * P``.
    A rigid shoe at rest is held by two abutments and its return spring:

    * the tip rests on the wheel-cylinder piston, retracted against its stop: the piston
      holds it along its axis, the slot in its end across it. The tip stays where it is,
      whatever the pin does;
    * the heel rests in its seat on the pin. The seat is open along the shoe's tip-pin
      line, as a heel on an anchor: it holds the heel across that line and lets it slide
      along it. (A seat closed both ways would over-constrain a rigid shoe held at its tip:
      a pin displaced along the line would have to stretch the shoe.)

    So the part of ``delta`` across the tip-pin line carries the heel with the pin: the
    shoe body turns about the tip ``T`` by the exact angle between ``P - T`` and ``P' - T``;
    lining, mass centre and heel follow, the tip stays on the piston. The part along the
    line is taken up in the seat: it does not move the body, but the shoe then turns on the
    pin at its new place ``P'`` (its moment arms and its inertia about the pin follow).

    To first order a radial pin shift thus closes the running clearance at the first
    contact by ``pct/100 * D * a / L`` (``D`` the distance of the tip-pin line from the drum
    centre, ``a`` the tip's distance from the contact normal, ``L`` the tip-pin distance):
    opposite shifts move the lining by equal amounts in opposite directions. A pin at the
    bottom of the drum moves mostly along the line (``D`` small), so it turns the shoe
    little.

    A worn lining's arc has the radius of the new one less the wear (its surface moves in).

    The right shoe is the mirror image of the left one about the y axis, defect included.
    """
    g = params.shoe
    # the compiled model re-places a shoe whose pin moves during a run with the same
    # function (model/growth.py); here its Python source runs, so the assembled geometry
    # keeps CPython's math to the last bit
    px, py = g.pivot_xy_m
    qx, qy, cx, cy, mid, mx, my, inertia, turn, seat = growth.shoe_placement.py_func(
        defect.pivot_radius_change_pct / 100.0,
        -1.0 if side == "right" else 1.0,
        px,
        py,
        g.tip_x_m,
        g.tip_y_m,
        g.mass_centre_x_m,
        g.mass_centre_y_m,
        g.inertia_about_pivot_kg_m2,
        g.mass_kg,
        _lining_mid_rad(params),
    )
    m = -1.0 if side == "right" else 1.0
    return ShoePlacement(
        sign=m,
        pivot_xy_m=(qx, qy),
        lining_centre_xy_m=(cx, cy),
        lining_radius_m=g.drum_radius_m - g.running_clearance_m - defect.lining_wear_mm * 1e-3,
        lining_mid_rad=mid,
        lining_half_rad=math.radians(0.5 * (g.lining_end_deg - g.lining_start_deg)),
        tip_xy_m=(m * g.tip_x_m, g.tip_y_m),
        actuation_dir=(-m, 0.0),
        mass_centre_xy_m=(mx, my),
        inertia_about_pivot_kg_m2=inertia,
        abutment_turn_rad=turn,
        heel_seat_offset_m=seat,
    )


def _lining_mid_rad(params: BrakeParameters) -> float:
    """Polar angle of the nominal left shoe's lining middle, rad."""
    g = params.shoe
    return math.radians(0.5 * (g.lining_start_deg + g.lining_end_deg))


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
        growth.write_placement.py_func(
            p,
            b,
            *s.pivot_xy_m,
            *s.lining_centre_xy_m,
            s.lining_mid_rad,
            *s.mass_centre_xy_m,
            s.inertia_about_pivot_kg_m2,
        )
        p[b + L.S_LINING_RADIUS] = s.lining_radius_m
        p[b + L.S_LINING_HALF_ANGLE] = s.lining_half_rad
        p[b + L.S_LINING_HALF_COS] = math.cos(s.lining_half_rad)
        p[b + L.S_LINING_HALF_SIN] = math.sin(s.lining_half_rad)
        p[b + L.S_TIP_X], p[b + L.S_TIP_Y] = s.tip_xy_m
        p[b + L.S_ACTUATION_DIR_X], p[b + L.S_ACTUATION_DIR_Y] = s.actuation_dir
        p[b + L.S_MASS] = params.shoe.mass_kg
        p[b + L.S_ACTUATION_GAIN] = defect.actuation_gain
        p[b + L.S_SHARE] = defect.actuation_share
        p[b + L.S_PRESSURE_FACTOR] = 1.0 + defect.actuation_gain_change_pct / 100.0
        p[b + L.S_ACTUATION_DELAY] = defect.actuation_delay_ms * 1e-3
        p[b + L.S_ACTUATION_LAG] = defect.actuation_lag_ms * 1e-3
        p[b + L.S_PULSATION_AMPLITUDE] = defect.actuation_pulsation_pct / 100.0
        p[b + L.S_PULSATION_FREQUENCY] = defect.actuation_pulsation_hz
        p[b + L.S_ACTUATION_SHAPED] = 1.0 if defect.force_shaped else 0.0
        p[b + L.S_SPRING_RELEASE] = (
            defect.return_spring_weakening_pct / 100.0 * RETURN_SPRING_PRELOAD_N
        )
        p[b + L.S_SPRING_MARGIN] = RETURN_SPRING_PRELOAD_N - RESIDUAL_FORCE_N
        p[b + L.S_FRICTION_COEFFICIENT] = growth.lining_friction.py_func(
            params.friction.coefficient, defect.friction_change_pct
        )
        p[b + L.S_ENABLED] = 1.0 if side in options.shoes else 0.0
        lb = L.P_LINING_BASE + i * L.LINING_STRIDE
        p[lb + L.LN_RADIUS] = params.shoe.drum_radius_m - params.shoe.running_clearance_m
        p[lb + L.LN_WEAR] = defect.lining_wear_mm * 1e-3
        _check_shoe(params, side, defect, s, p, b)
    _pack_drum(params, defects, p)
    _pack_growth(params, defects, p)
    thermal.pack_fade(p)
    _pack_service(params, defects, p)
    return p


def _pack_service(params: BrakeParameters, defects: Defects, p: np.ndarray) -> None:
    """Pack the service brake's springs and stops (layout.P_SERVICE, P_SPRING_*;
    :mod:`.service`); the study brake packs none. On the service brake a weakened return
    spring acts through its spring (preload and rate times ``1 - weakening``), not through
    the study brake's net-force shortcut (actuation.spring_release), so the shoe's force
    is shaped only by a reshaped history (delay, lag, pulsation)."""
    spec = params.service
    if spec is None:
        return
    p[L.P_SERVICE] = 1.0
    p[L.P_RESIDUAL_FORCE] = spec.residual_force_n
    p[L.P_STOP_STIFFNESS] = spec.stop_stiffness_n_per_m
    p[L.P_STOP_DAMPING] = spec.stop_damping_n_s_per_m
    for i, side in enumerate(SIDES):
        defect: ShoeDefect = getattr(defects, side)
        b = L.P_SHOE_BASE + i * L.SHOE_STRIDE
        p[b + L.S_SPRING_RELEASE] = 0.0
        p[b + L.S_SPRING_MARGIN] = 0.0
        p[b + L.S_ACTUATION_SHAPED] = 1.0 if defect.actuation_shaped else 0.0
        phi = p[b + L.S_SIGN] * math.radians(defect.initial_angle_deg)
        rest = service.tip_travel.py_func(p, b, math.cos(phi), math.sin(phi), 0.0)[0]
        kept = 1.0 - defect.return_spring_weakening_pct / 100.0
        r = L.P_SPRING_BASE + i * L.SPRING_STRIDE
        p[r + L.R_PRELOAD] = kept * spec.return_spring_preload_n
        p[r + L.R_RATE] = kept * spec.return_spring_rate_n_per_m
        p[r + L.R_REST_TRAVEL] = rest
        # the healthy shoe rests on its stop at its rest angle: the stop carries the
        # preload less the residual force there
        healthy_press = spec.return_spring_preload_n - spec.residual_force_n
        p[r + L.R_STOP_TRAVEL] = rest + healthy_press / spec.stop_stiffness_n_per_m


def _pack_growth(params: BrakeParameters, defects: Defects, p: np.ndarray) -> None:
    """Pack the nominal shoe (from which a moving pin re-places it) and one growth entry
    per defect that changes during the run (layout.P_GROWTH_*). The slots above hold the
    final severities, checked there: the severities on the way (between healthy and the
    final one, of the same sign) assemble as well."""
    g = params.shoe
    nb = L.P_NOMINAL_BASE
    p[nb + L.N_PIVOT_X], p[nb + L.N_PIVOT_Y] = g.pivot_xy_m
    p[nb + L.N_TIP_X], p[nb + L.N_TIP_Y] = g.tip_x_m, g.tip_y_m
    p[nb + L.N_MASS_CENTRE_X], p[nb + L.N_MASS_CENTRE_Y] = g.mass_centre_x_m, g.mass_centre_y_m
    p[nb + L.N_INERTIA] = g.inertia_about_pivot_kg_m2
    p[nb + L.N_MASS] = g.mass_kg
    p[nb + L.N_LINING_MID] = _lining_mid_rad(params)
    entries = defects.growth
    if len(entries) > L.MAX_GROWTH_ENTRIES:
        raise ParameterError(
            f"defects: {len(entries)} change during the run: allowed at most {L.MAX_GROWTH_ENTRIES}"
        )
    at = {loc: getattr(defects, loc).severities() for loc in ("left", "right", "drum")}
    for j, (kind, location, law) in enumerate(entries):
        growth_id = KIND_BY_NAME[kind].growth_id  # its id in growth.apply (the catalogue's)
        if growth_id is None:
            raise ParameterError(
                f"defect {kind} at {location} cannot change during a run in this model:"
                " allowed only a step at 0 s"
            )
        b = L.P_GROWTH_BASE + j * L.GROWTH_STRIDE
        p[b + L.G_KIND] = growth_id
        p[b + L.G_SHOE] = SIDES.index(location) if location in SIDES else -1
        p[b + L.G_LAW] = law.law_id
        p[b + L.G_ONSET] = law.onset_s
        p[b + L.G_RATE] = law.rate
        p[b + L.G_START] = law.start
        p[b + L.G_FINAL] = at[location][kind]
    p[L.P_GROWTH_COUNT] = float(len(entries))


def _pack_drum(params: BrakeParameters, defects: Defects, p: np.ndarray) -> None:
    """Pack the drum's radius harmonics (layout.P_DRUM_WAVE_*) after checking the limits
    that need the assembled brake: the slope, and the peak runout against the rest gap.

    A round drum (no harmonic of non-zero amplitude) packs no harmonic at all, so the
    kernels take exactly the round drum's arithmetic.
    """
    drum: DrumDefect = defects.drum
    _pack_flat(params, drum, p)
    waves = [h for h in drum.harmonics if h.amplitude_um > 0.0]
    if not waves:
        return
    radius = params.shoe.drum_radius_m
    slope = drum.slope(radius)
    if slope > MAX_DRUM_SLOPE:
        raise ParameterError(
            f"drum harmonics slope sum_k k a_k / R0 = {slope:.4f}: allowed at most"
            f" {MAX_DRUM_SLOPE} (the contact geometry tilts the normal by a small slope)"
        )
    # the gap between each resting shoe and the round drum (the running clearance for a
    # healthy shoe; the shoe defects change it)
    gaps = [
        -indentation_at(
            p,
            L.P_SHOE_BASE + i * L.SHOE_STRIDE,
            math.radians(getattr(defects, side).initial_angle_deg),
        )
        for i, side in enumerate(SIDES)
    ]
    runout_m = drum.peak_runout_um * 1e-6
    gap = min(gaps)
    if runout_m >= gap:
        raise ParameterError(
            f"drum peak runout sum_k a_k = {drum.peak_runout_um:g} um: allowed below the"
            f" gap between the resting shoes and the drum, {gap * 1e6:.0f} um (the running"
            " clearance), or the drum touches the retracted shoes every revolution"
            f" (permanent contact); service drums run out by up to {SERVICE_RUNOUT_UM:g} um"
        )
    p[L.P_DRUM_WAVE_COUNT] = float(len(waves))
    for j, h in enumerate(waves):
        b = L.P_DRUM_WAVE_BASE + j * L.DRUM_WAVE_STRIDE
        p[b + L.W_ORDER] = float(h.order)
        p[b + L.W_AMPLITUDE] = h.amplitude_um * 1e-6
        p[b + L.W_PHASE] = math.radians(h.phase_deg)


def _pack_flat(params: BrakeParameters, drum: DrumDefect, p: np.ndarray) -> None:
    """Pack the drum's flat (layout.P_FLAT_*) after checking its slope against the drum's
    radius; none (depth 0) leaves the round drum's arithmetic."""
    if drum.flat_depth_um <= 0.0:
        return
    slope = drum.flat_slope(params.shoe.drum_radius_m)
    if slope > MAX_DRUM_SLOPE:
        raise ParameterError(
            f"drum flat of {drum.flat_depth_um:g} um over {drum.flat_width_deg:g} deg: slope"
            f" pi d / (2 w R0) = {slope:.4f}, allowed at most {MAX_DRUM_SLOPE} (the contact"
            " geometry tilts the normal by a small slope): make it wider or shallower"
        )
    p[L.P_FLAT_DEPTH] = drum.flat_depth_um * 1e-6
    p[L.P_FLAT_CENTRE] = math.radians(drum.flat_centre_deg)
    p[L.P_FLAT_HALF_WIDTH] = math.radians(0.5 * drum.flat_width_deg)


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
    if p[base + L.S_ENABLED] <= 0.0:
        return
    arms = contact_arms(p, base, math.radians(defect.initial_angle_deg))
    mu = p[base + L.S_FRICTION_COEFFICIENT]
    if arms is not None and mu >= arms.self_locking_coefficient:
        change = (
            f" (friction change {defect.friction_change_pct:+g} %)"
            if defect.friction_change_pct
            else ""
        )
        raise ParameterError(
            f"friction coefficient {mu:g}{change} self-locks the {side} shoe when it leads:"
            " at first contact the friction arm about its pivot is h ="
            f" {arms.friction_arm_m * 1e3:.1f} mm and the normal-force arm d ="
            f" {arms.normal_arm_m * 1e3:.1f} mm, so friction"
            " alone holds the shoe on the drum and the normal force grows without bound:"
            f" allowed a coefficient below the self-locking limit d/h ="
            f" {arms.self_locking_coefficient:.4f}"
        )


# Largest shoe rotation searched for the first contact, rad (about 30 deg): far beyond any
# running clearance the parameters allow (10 % of the drum radius at the pivot radius).
_ONSET_SEARCH_RAD = 0.5


@dataclass(frozen=True)
class ContactArms:
    """Moment arms about a shoe's pivot where its lining first touches the drum.

    Attributes:
        onset_angle_rad: shoe angle at first contact (indentation 0), rad.
        normal_arm_m: ``d``, distance from the pivot to the line of the normal force, m.
        friction_arm_m: ``h``, distance from the pivot to the line of the friction force
            (the drum tangent at the contact point), m.
        actuation_arm_m: ``q``, distance from the pivot to the line of the actuation force, m.
    """

    onset_angle_rad: float
    normal_arm_m: float
    friction_arm_m: float
    actuation_arm_m: float

    @property
    def self_locking_coefficient(self) -> float:
        """``d / h``: from this friction coefficient up, a leading shoe self-locks.

        The leading shoe's moment balance ``Fn d - mu Fn h = Fe q`` gives
        ``Fn = Fe q / (d - mu h)``, finite only for ``mu < d / h``.
        """
        return self.normal_arm_m / self.friction_arm_m if self.friction_arm_m > 0 else math.inf


def contact_arms(p: np.ndarray, base: int, start_angle_rad: float) -> ContactArms | None:
    """Moment arms of the shoe at ``base`` at its first contact when it turns outward from
    ``start_angle_rad``; None if it cannot reach the drum within 0.5 rad."""

    def eps(theta: float) -> float:
        return indentation_at(p, base, theta)

    hi = start_angle_rad + _ONSET_SEARCH_RAD
    if eps(hi) <= 0.0 or eps(start_angle_rad) >= 0.0:
        return None
    onset = brentq(eps, start_angle_rad, hi, xtol=1e-14)
    out = kernel.shoe_eval(p, base, onset, 0.0, 0.0, 0.0, L.CONTACT_ON)
    x, y = float(out[7]), float(out[8])
    px, py = p[base + L.S_PIVOT_X], p[base + L.S_PIVOT_Y]
    dist = math.hypot(x, y)
    nx, ny = x / dist, y / dist  # the drum's outward normal at the contact point
    ax, ay = x - px, y - py
    phi = p[base + L.S_SIGN] * onset
    c, sn = math.cos(phi), math.sin(phi)
    tdx, tdy = p[base + L.S_TIP_X] - px, p[base + L.S_TIP_Y] - py
    tx, ty = c * tdx - sn * tdy, sn * tdx + c * tdy
    ex, ey = p[base + L.S_ACTUATION_DIR_X], p[base + L.S_ACTUATION_DIR_Y]
    return ContactArms(
        onset_angle_rad=float(onset),
        normal_arm_m=abs(ax * ny - ay * nx),
        friction_arm_m=abs(ax * nx + ay * ny),
        actuation_arm_m=abs(tx * ey - ty * ex),
    )


def indentation_at(
    p: np.ndarray, base: int, theta_rad: float, drum_angle_rad: float = 0.0
) -> float:
    """Indentation (m, positive = penetration) of a shoe held at ``theta_rad`` against the
    drum at ``drum_angle_rad`` (which matters only for an out-of-round drum)."""
    out = kernel.shoe_eval(
        p, base, theta_rad, 0.0, 0.0, 0.0, L.CONTACT_AUTO, 0, 0.0, drum_angle_rad
    )
    return float(out[2])


def initial_state(
    params: BrakeParameters, defects: Defects, temperature_c: float | None = None
) -> np.ndarray:
    """State at t = 0: flywheel and drum at the initial speed, shoes at rest; with the
    linings' wear states (layout ``N_STATE_WEAR``, from 0) when a lining wears with its
    friction work; with the brake's temperature ``temperature_c`` (deg C, layout
    ``N_STATE_THERMAL``) when the run has a thermal state (model/thermal.py)."""
    size = L.N_STATE_WEAR if defects.wearing_with_work else L.N_STATE
    y = np.zeros(L.N_STATE_THERMAL if temperature_c is not None else size)
    if temperature_c is not None:
        y[L.Y_BRAKE_TEMPERATURE] = temperature_c
    y[L.Y_FLYWHEEL_SPEED] = params.driveline.initial_speed_rad_s
    y[L.Y_DRUM_SPEED] = params.driveline.initial_speed_rad_s
    y[L.Y_LEFT_ANGLE] = math.radians(defects.left.initial_angle_deg)
    y[L.Y_RIGHT_ANGLE] = math.radians(defects.right.initial_angle_deg)
    return y
