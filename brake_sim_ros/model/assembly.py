"""Unpack parameters and defects into the kernels' flat arrays, checking validity once."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model import adjuster, kernel, lining, service, thermal
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.actuation import RESIDUAL_FORCE_N, RETURN_SPRING_PRELOAD_N
from brake_sim_ros.model.catalogue import (
    KIND_BY_NAME,
    LOCATIONS,
    WEAR_KIND,
    kinds_at,
    refuse_without_circuit,
)
from brake_sim_ros.model.defects import SERVICE_RUNOUT_UM, Defects, DrumDefect, ShoeDefect
from brake_sim_ros.model.line_kinds import LINE
from brake_sim_ros.model.packing import PackSite
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.placement import POSE_IDS, lining_mid_rad
from brake_sim_ros.model.service_parameters import ServiceBrakeParameters
from brake_sim_ros.model.vehicle import DEFAULT_WHEEL_RADIUS_M

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


def pack(
    params: BrakeParameters, defects: Defects, options: ModelOptions | None = None
) -> np.ndarray:
    """Packed parameter vector for the kernels (layout.P_* / S_*), after validity checks:
    the healthy brake's own slots, then every defect kind's packing (its catalogue entry's,
    :mod:`.packing`) at each of its locations, the shoes before the drum, the hydraulic
    line's last (refused on a brake without a circuit)."""
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
    for side in SIDES:
        defect: ShoeDefect = getattr(defects, side)
        site = PackSite(params, side, defect, p)
        _pack_shoe(params, site, enabled=side in options.shoes)
        for kind in kinds_at(side):
            kind.packing(site)
        adjuster.pack_adjuster(params, defect, side, defects.growth_of(WEAR_KIND, side), p)
        _check_shoe(params, side, defect, p, site.shoe_base)
    # the shoes at rest against the round drum: the gap a drum's runout must stay below
    round_drum = p.copy()
    site = PackSite(params, "drum", defects.drum, p)
    for kind in kinds_at("drum"):
        kind.packing(site)
    _check_runout(defects, round_drum)
    _pack_growth(params, defects, p)
    thermal.pack_fade(p)
    _pack_service(params, defects, p)
    _pack_tyre(params, options, p)
    _pack_line(params, defects, p)
    return p


def _pack_shoe(params: BrakeParameters, site: PackSite, *, enabled: bool) -> None:
    """The slots of a shoe that no defect kind changes: its side, tip, actuation
    direction, lining span, mass, spring margin; whether it is in the model and whether
    its force takes the shaped path (any kind with an actuation effect)."""
    g = params.shoe
    p, b, defect = site.p, site.shoe_base, site.defect
    m = -1.0 if site.location == "right" else 1.0
    half = math.radians(0.5 * (g.lining_end_deg - g.lining_start_deg))
    p[b + L.S_SIGN] = m
    p[b + L.S_LINING_HALF_ANGLE] = half
    p[b + L.S_LINING_HALF_COS] = math.cos(half)
    p[b + L.S_LINING_HALF_SIN] = math.sin(half)
    p[b + L.S_TIP_X], p[b + L.S_TIP_Y] = m * g.tip_x_m, g.tip_y_m
    p[b + L.S_ACTUATION_DIR_X], p[b + L.S_ACTUATION_DIR_Y] = -m, 0.0
    p[b + L.S_MASS] = g.mass_kg
    if site.params.service is None:  # the study brake's net-force spring shortcut
        p[b + L.S_ACTUATION_SHAPED] = 1.0 if defect.force_shaped else 0.0
        p[b + L.S_SPRING_MARGIN] = RETURN_SPRING_PRELOAD_N - RESIDUAL_FORCE_N
    else:  # its springs act as springs (_pack_service): only a reshaped history shapes
        p[b + L.S_ACTUATION_SHAPED] = 1.0 if defect.actuation_shaped else 0.0
    p[b + L.S_ENABLED] = 1.0 if enabled else 0.0
    p[site.lining_base + L.LN_RADIUS] = g.drum_radius_m - g.running_clearance_m


def _pack_line(params: BrakeParameters, defects: Defects, p: np.ndarray) -> None:
    """The hydraulic line's defects (catalogue location ``line``), each kind's packing; a
    brake without a circuit (the study brake) refuses any in one line."""
    if params.service is None:
        refuse_without_circuit(defects.line)
        return
    site = PackSite(params, LINE, defects.line, p)
    for kind in kinds_at(LINE):
        kind.packing(site)


def _pack_service(params: BrakeParameters, defects: Defects, p: np.ndarray) -> None:
    """Pack the service brake's springs, stops and hydraulic circuit (layout.P_SERVICE,
    P_SPRING_*, P_PISTON_AREA, P_LINE_*; :mod:`.service`); the study brake packs none. On
    the service brake a weakened return spring acts through its spring (preload and rate
    times ``1 - weakening``), not through the study brake's net-force shortcut
    (actuation.spring_release: its slots stay 0, see _pack_shoe and
    packing.pack_spring_release), so the shoe's force is shaped only by a reshaped history
    (delay, lag, pulsation)."""
    spec = params.service
    if spec is None:
        return
    p[L.P_SERVICE] = 1.0
    p[L.P_RESIDUAL_FORCE] = spec.residual_force_n
    p[L.P_STOP_STIFFNESS] = spec.stop_stiffness_n_per_m
    p[L.P_STOP_DAMPING] = spec.stop_damping_n_s_per_m
    p[L.P_PISTON_AREA] = spec.piston_area_m2
    p[L.P_LINE_COMPLIANCE] = spec.line_compliance_m3_per_pa
    p[L.P_LINE_RESISTANCE] = spec.line_resistance_pa_s_per_m3
    if spec.distributed_lining:  # each node's share of the lining (model/lining.py)
        g = params.shoe
        arc = math.radians(g.lining_end_deg - g.lining_start_deg)
        area = g.lining_width_m * (g.drum_radius_m - g.running_clearance_m) * arc / lining.NODES
        p[L.P_LINING_NODE_STIFFNESS] = spec.lining_foundation_pa_per_m * area
        p[L.P_LINING_NODE_DAMPING] = spec.lining_damping_time_s * p[L.P_LINING_NODE_STIFFNESS]
    for i, side in enumerate(SIDES):
        defect: ShoeDefect = getattr(defects, side)
        b = L.P_SHOE_BASE + i * L.SHOE_STRIDE
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


def _pack_tyre(params: BrakeParameters, options: ModelOptions, p: np.ndarray) -> None:
    """Pack the service brake's tyre (layout.P_TYRE_*, :mod:`.tyre`) and the default
    rolling radius it rolls on (a vehicle's replaces it: vehicle.pack_vehicle); the study
    brake packs none. A rigid coupling leaves no place for a tyre: refused."""
    if params.service is None:
        return
    if options.rigid_coupling:
        raise ParameterError(
            "model rigid_coupling with the service brake: not allowed (its tyre, with the"
            " road's friction limit, couples wheel and vehicle: allowed on the study brake)"
        )
    tyre = params.service.tyre
    p[L.P_WHEEL_RADIUS] = DEFAULT_WHEEL_RADIUS_M
    p[L.P_TYRE_STIFFNESS] = tyre.presliding_stiffness_per_m
    p[L.P_TYRE_DAMPING] = tyre.presliding_damping_s_per_m
    p[L.P_TYRE_VISCOUS] = tyre.viscous_s_per_m
    p[L.P_TYRE_SLIDING] = tyre.road_friction
    p[L.P_TYRE_PEAK] = tyre.peak_friction
    p[L.P_TYRE_STRIBECK_SPEED] = tyre.stribeck_speed_m_s
    p[L.P_TYRE_STRIBECK_EXPONENT] = tyre.stribeck_exponent


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
    p[nb + L.N_LINING_MID] = lining_mid_rad(params)
    p[nb + L.N_POSE] = POSE_IDS[g.pose]
    entries = defects.growth
    if len(entries) > L.MAX_GROWTH_ENTRIES:
        raise ParameterError(
            f"defects: {len(entries)} change during the run: allowed at most {L.MAX_GROWTH_ENTRIES}"
        )
    at = {loc: getattr(defects, loc).severities() for loc in LOCATIONS}
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


def _check_runout(defects: Defects, round_drum: np.ndarray) -> None:
    """Refuse a drum whose peak runout reaches the gap between the resting shoes and the
    round drum (``round_drum``: the vector packed before the drum's kinds): it would touch
    the retracted shoes every revolution, whatever the harmonics' phases."""
    drum: DrumDefect = defects.drum
    if not any(h.amplitude_um > 0.0 for h in drum.harmonics):
        return
    # the gap between each resting shoe and the round drum (the running clearance for a
    # healthy shoe; the shoe defects change it)
    gaps = [
        -indentation_at(
            round_drum,
            L.P_SHOE_BASE + i * L.SHOE_STRIDE,
            math.radians(getattr(defects, side).initial_angle_deg),
        )
        for i, side in enumerate(SIDES)
    ]
    gap = min(gaps)
    if drum.peak_runout_um * 1e-6 >= gap:
        raise ParameterError(
            f"drum peak runout sum_k a_k = {drum.peak_runout_um:g} um: allowed below the"
            f" gap between the resting shoes and the drum, {gap * 1e6:.0f} um (the running"
            " clearance), or the drum touches the retracted shoes every revolution"
            f" (permanent contact); service drums run out by up to {SERVICE_RUNOUT_UM:g} um"
        )


def _check_shoe(
    params: BrakeParameters,
    side: str,
    defect: ShoeDefect,
    p: np.ndarray,
    base: int,
) -> None:
    """Refuse a packed shoe whose pin sits at or beyond its lining, that starts inside the
    drum, or that self-locks when it leads."""
    lining_radius = p[base + L.S_LINING_RADIUS]
    pivot_r = math.hypot(p[base + L.S_PIVOT_X], p[base + L.S_PIVOT_Y])
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


def state_size(params: BrakeParameters, defects: Defects, thermal_state: bool) -> int:
    """Entries of a run's state vector (layout.Y_*): a service brake's always
    ``N_STATE_SERVICE``; else ``N_STATE_THERMAL`` with a thermal state, ``N_STATE_WEAR``
    when a lining wears with its friction work, ``N_STATE`` otherwise."""
    if params.service is not None:
        return L.N_STATE_SERVICE
    if thermal_state:
        return L.N_STATE_THERMAL
    return L.N_STATE_WEAR if defects.wearing_with_work else L.N_STATE


def residual_pressure_pa(spec: ServiceBrakeParameters) -> float:
    """The service brake's line pressure at rest, Pa: its residual force over its piston
    area (the check valve's pressure)."""
    return spec.residual_force_n / spec.piston_area_m2


def initial_state(
    params: BrakeParameters,
    defects: Defects,
    temperature_c: float | None = None,
    *,
    held_temperature_c: float = thermal.DEFAULT_TEMPERATURE_C,
) -> np.ndarray:
    """State at t = 0 (:func:`state_size` entries): flywheel and drum at the initial speed,
    shoes at rest; the linings' wear states (layout ``N_STATE_WEAR``) from 0; the brake's
    temperature ``temperature_c`` (deg C, layout ``N_STATE_THERMAL``) when the run has a
    thermal state (model/thermal.py), else, on a service brake, which carries the slot
    anyway, the temperature the run is held at, ``held_temperature_c`` (deg C); a service
    brake's line at its residual pressure (:func:`residual_pressure_pa`)."""
    y = np.zeros(state_size(params, defects, temperature_c is not None))
    if y.shape[0] > L.Y_BRAKE_TEMPERATURE:
        y[L.Y_BRAKE_TEMPERATURE] = held_temperature_c if temperature_c is None else temperature_c
    if params.service is not None:  # the line at rest: the residual pressure
        y[L.Y_LINE_PRESSURE] = residual_pressure_pa(params.service)
    y[L.Y_FLYWHEEL_SPEED] = params.driveline.initial_speed_rad_s
    y[L.Y_DRUM_SPEED] = params.driveline.initial_speed_rad_s
    y[L.Y_LEFT_ANGLE] = math.radians(defects.left.initial_angle_deg)
    y[L.Y_RIGHT_ANGLE] = math.radians(defects.right.initial_angle_deg)
    return y


def resized_state(
    y: np.ndarray,
    params: BrakeParameters,
    defects: Defects,
    *,
    was_thermal: bool,
    start_temperature_c: float | None,
    held_temperature_c: float,
) -> np.ndarray:
    """The state ``y`` of a run carried over to new parameters (``params``, ``defects``):
    a lining that starts wearing with its work gets its wear states (from 0); a thermal
    state that ends is dropped (a service brake's slot then holds ``held_temperature_c``),
    one that starts begins at ``start_temperature_c`` (deg C); a service brake keeps its
    ``N_STATE_SERVICE`` entries. ``was_thermal``: whether the run had a thermal state."""
    if params.service is None and y.shape[0] > L.N_STATE_THERMAL:  # was a service brake
        y = y[: L.N_STATE_THERMAL if was_thermal else L.N_STATE_WEAR]
    size = L.N_STATE_SERVICE if params.service is not None else y.shape[0]
    if defects.wearing_with_work and size < L.N_STATE_WEAR:
        size = L.N_STATE_WEAR  # a lining starts wearing with its friction work: from 0
    if start_temperature_c is None and params.service is None:  # no thermal state
        size = min(size, L.N_STATE_THERMAL - 1)
    elif start_temperature_c is not None:
        size = max(size, L.N_STATE_THERMAL)
    grown = np.zeros(size)
    kept = min(size, y.shape[0])
    grown[:kept] = y[:kept]
    if params.service is not None and kept <= L.Y_LINE_PRESSURE:  # the line starts at rest
        grown[L.Y_LINE_PRESSURE] = residual_pressure_pa(params.service)
    if size > L.Y_BRAKE_TEMPERATURE:
        if start_temperature_c is None:
            grown[L.Y_BRAKE_TEMPERATURE] = held_temperature_c
        elif not was_thermal or y.shape[0] <= L.Y_BRAKE_TEMPERATURE:
            grown[L.Y_BRAKE_TEMPERATURE] = start_temperature_c
    return grown
