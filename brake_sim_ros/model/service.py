"""The service brake's return springs and rest stops, compiled (numba).

Each rule is written here once: the kernel (:mod:`brake_sim_ros.model.kernel`) takes the
forces at the tip, the energy books (:mod:`brake_sim_ros.analysis.energy`) the stored
energies, both from these functions.

Everything acts at the shoe's tip along the wheel-cylinder axis ``e`` (the actuation's
fixed direction, outward), where the piston pushes. The coordinate is the tip's outward
travel ``u = (T(theta) - T(0)) . e`` (m): ``T`` the tip turned with the shoe about its
pivot, ``T(0)`` its assembled place. A force ``F`` along ``e`` at the tip does the work
``F du`` as the shoe turns (``du/dtheta`` is its moment arm), so the tip forces add to the
actuation's in the shoe's moment balance (:func:`brake_sim_ros.model.contact.shoe_forces`).

* Wheel cylinder and line (the hydraulic circuit): one cylinder, two pistons of area
  ``A``, one line pressure ``p`` (Pa, the state layout.Y_LINE_PRESSURE). The line is fed
  from the source pressure ``p_s = max((F_L + F_R) / 2, F_r) / A``: the pistons' mean
  commanded force (each shoe's after its gain and shaping, model/actuation.py) over the
  area, never below the residual pressure a check valve keeps. The volume balance
  ``C p' = (p_s - p) / R - A (u_l' + u_r')`` (``C`` the circuit's compliance seen from
  the wheel, ``R`` the line's resistance, ``u'`` each tip's outward speed): the pressure
  rises with ``R C`` and a tip pushed back by the drum pushes fluid back. Each piston
  pushes its tip with the line pressure plus its own commanded force's departure from the
  pistons' mean, ``F_cyl = max(A p + F_i - (F_L + F_R) / 2, F_r)``: a held force gives
  ``p = p_s`` and each shoe exactly the ideal source's ``max(F_i, F_r)`` (but for two
  unequal commands whose mean is below the residual force); the pressure's rise and its
  pulses act on both pistons alike; a per-shoe defect (gain, share, delay, lag, pulsation)
  is that piston's own departure (a weak, sticking or pulsing piston). The pistons' mean
  force over ``A`` is ``p`` (the line-pressure sensor's reading) while neither sits at
  ``F_r``. Stored ``C p^2 / 2``;
  the line loses ``(p_s - p)^2 / R``; the source works ``p_s (p_s - p) / R``, and a
  piston's force beyond ``A p`` (its own departure, the residual floor) works at its tip.
* The line's defects (catalogue location ``line``, :mod:`.line_kinds`). Air: a volume
  ``V_a`` (m^3 at the atmospheric pressure ``p_a``, absolute) compressed isothermally,
  ``V = V_a p_a / (p_a + p)`` at the gauge pressure ``p``, adds the compliance
  ``C_a(p) = V_a p_a / (p_a + p)^2`` to ``C`` (large at the residual pressure, small once
  the pressure is high: the spongy pedal) and stores ``V_a p_a (ln(1 + x) - x / (1 + x))``,
  ``x = p / p_a``. A leak: a flow ``G p`` out of the circuit to the reservoir (a laminar
  leak past a seal), which the source makes up through the line, so that a held source
  gives ``p = p_s / (1 + G R)`` and the pressure settles with ``R C / (1 + G R)``; the
  leak loses ``G p^2``.
* Return spring (pulls inward): ``F_s = P + k (u - u_rest)``, ``P`` and ``k`` its preload and
  rate as weakened; stored energy ``P (u - u_rest) + k (u - u_rest)^2 / 2``.
* Rest stop (pushes outward, one-sided): with ``delta = u_stop - u`` the shoe's press on
  it, ``F_st = k_st delta + c_st delta'`` while ``delta > 0``, never negative (Kelvin-Voigt,
  as the lining contact); stored ``k_st delta^2 / 2``, its damper's loss ``(F_st - k_st
  delta) delta'``. ``u_stop`` is placed so that the healthy shoe rests on its stop at its
  rest angle: ``u_stop = u_rest + (P - F_r) / k_st``.

Net outward force at the tip: ``F_cyl - F_s + F_st``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from brake_sim_ros.model import layout as L
from brake_sim_ros.model.compiled import JIT, JIT_ALLOCATING


@njit(inline="always", **JIT)
def tip_travel(p, base, c, sn, omega):
    """The tip's outward travel along the cylinder axis (m), its rate (m/s) and its arm
    ``du/dtheta`` (m/rad) for the shoe at ``base`` turned by ``phi`` (cos ``c``, sin
    ``sn``: :func:`.contact.kinematics`' slots 8 and 9) at ``omega`` rad/s."""
    s = p[base + L.S_SIGN]
    tdx = p[base + L.S_TIP_X] - p[base + L.S_PIVOT_X]
    tdy = p[base + L.S_TIP_Y] - p[base + L.S_PIVOT_Y]
    tx = c * tdx - sn * tdy
    ty = sn * tdx + c * tdy
    ex = p[base + L.S_ACTUATION_DIR_X]
    ey = p[base + L.S_ACTUATION_DIR_Y]
    travel = (tx - tdx) * ex + (ty - tdy) * ey
    arm = s * (tx * ey - ty * ex)
    return travel, arm * omega, arm


@njit(inline="always", **JIT)
def line_source(p, commanded_left, commanded_right):
    """The source pressure ``p_s`` the line is fed from, Pa: the pistons' mean commanded
    force (N, after each shoe's gain and shaping) over the piston area, never below the
    residual pressure."""
    mean = 0.5 * (commanded_left + commanded_right)
    residual = p[L.P_RESIDUAL_FORCE]
    return (mean if mean > residual else residual) / p[L.P_PISTON_AREA]


@njit(inline="always", **JIT)
def piston_force(p, commanded, mean, pressure):
    """A piston's force on its tip, N: the line pressure ``pressure`` (Pa) on its area plus
    its own commanded force's departure from the pistons' mean, ``commanded - mean`` (N,
    after the gains), never below the residual force."""
    force = p[L.P_PISTON_AREA] * pressure + (commanded - mean)
    residual = p[L.P_RESIDUAL_FORCE]
    return force if force > residual else residual


@njit(inline="always", **JIT)
def line_inflow(p, source, pressure):
    """The flow from the source into the line, m^3/s: ``(p_s - p) / R``."""
    return (source - pressure) / p[L.P_LINE_RESISTANCE]


@njit(inline="always", **JIT)
def spring_force(p, shoe, travel):
    """The return spring's inward pull at the tip of shoe ``shoe`` (0 left, 1 right), N,
    at the tip travel ``travel`` (m)."""
    b = L.P_SPRING_BASE + shoe * L.SPRING_STRIDE
    return p[b + L.R_PRELOAD] + p[b + L.R_RATE] * (travel - p[b + L.R_REST_TRAVEL])


@njit(inline="always", **JIT)
def stop_force(p, shoe, travel, rate):
    """The rest stop's outward push on the tip (N, >= 0) and its damper's loss (W) at the
    tip travel ``travel`` (m) and rate ``rate`` (m/s)."""
    b = L.P_SPRING_BASE + shoe * L.SPRING_STRIDE
    press = p[b + L.R_STOP_TRAVEL] - travel
    if press <= 0.0:
        return 0.0, 0.0
    k = p[L.P_STOP_STIFFNESS]
    force = k * press - p[L.P_STOP_DAMPING] * rate
    if force < 0.0:
        force = 0.0
    # power into the stop minus the rate of its elastic energy (as the lining contact's)
    return force, (force - k * press) * (-rate)


@njit(inline="always", **JIT)
def tip_forces(p, shoe, cylinder, travel, rate):
    """(net outward force at the tip N, stop damper loss W) of shoe ``shoe`` pushed by its
    piston with ``cylinder`` N (:func:`piston_force`)."""
    stop, loss = stop_force(p, shoe, travel, rate)
    return cylinder - spring_force(p, shoe, travel) + stop, loss


# Atmospheric pressure, Pa (absolute): the air in a line is at it when the circuit is open
# to the reservoir (bled, at rest); the line pressure ``p`` is a gauge pressure.
ATMOSPHERIC_PA = 101_325.0
# Lowest gauge pressure the air's law is evaluated at, as a fraction of -p_a: a line
# pressure never falls this far below atmospheric (the fluid would boil off first).
_AIR_FLOOR = -0.5


@njit(inline="always", **JIT)
def air_compliance(p, pressure):
    """The compliance the line's air adds at the gauge pressure ``pressure`` (Pa),
    m^3/Pa: ``V_a p_a / (p_a + p)^2`` (0 without air)."""
    volume = p[L.P_LINE_AIR_VOLUME]
    if volume <= 0.0:
        return 0.0
    x = pressure / ATMOSPHERIC_PA
    if x < _AIR_FLOOR:
        x = _AIR_FLOOR
    return volume / (ATMOSPHERIC_PA * (1.0 + x) * (1.0 + x))


@njit(inline="always", **JIT)
def line_faults(p, pressure):
    """The circuit's compliance beyond ``C`` at the line pressure ``pressure`` (Pa,
    m^3/Pa: the air's) and the flow it loses to a leak (m^3/s, ``G p``)."""
    return air_compliance(p, pressure), p[L.P_LINE_LEAK_CONDUCTANCE] * pressure


@njit(inline="always", **JIT)
def hydraulics(p, pressure, commanded_left, commanded_right, rate_left, rate_right):
    """The circuit at the line pressure ``pressure`` (Pa) for the pistons' commanded forces
    (N, after their gains) and the tips' outward speeds (m/s): (left piston force N, right
    piston force N, ``dp/dt`` Pa/s, the line's loss W, the actuation's power W: the
    source's ``p_s`` times the inflow plus each piston's force beyond ``A p`` times its
    tip's speed)."""
    area = p[L.P_PISTON_AREA]
    source = line_source(p, commanded_left, commanded_right)
    mean = 0.5 * (commanded_left + commanded_right)
    left = piston_force(p, commanded_left, mean, pressure)
    right = piston_force(p, commanded_right, mean, pressure)
    inflow = line_inflow(p, source, pressure)
    compliance = p[L.P_LINE_COMPLIANCE]
    stored = inflow  # into the compliance: the source's flow less a leak's
    loss = (source - pressure) * inflow
    # air or a leak (the healthy line's arithmetic stays as it was)
    if p[L.P_LINE_AIR_VOLUME] > 0.0 or p[L.P_LINE_LEAK_CONDUCTANCE] > 0.0:
        air, leak = line_faults(p, pressure)
        compliance += air
        stored -= leak
        loss += pressure * leak
    rate = (stored - area * (rate_left + rate_right)) / compliance
    power = source * inflow + (left - area * pressure) * rate_left
    power += (right - area * pressure) * rate_right
    return left, right, rate, loss, power


@njit(inline="always", **JIT)
def line_energy(p, pressure):
    """Energy the circuit's compliance (and its air) stores at the line pressure
    ``pressure`` (Pa), J."""
    energy = 0.5 * p[L.P_LINE_COMPLIANCE] * pressure * pressure
    volume = p[L.P_LINE_AIR_VOLUME]
    if volume > 0.0:
        x = pressure / ATMOSPHERIC_PA
        if x < _AIR_FLOOR:
            x = _AIR_FLOOR
        energy += volume * ATMOSPHERIC_PA * (np.log1p(x) - x / (1.0 + x))
    return energy


@njit(inline="always", **JIT)
def stored_energy(p, shoe, travel):
    """Elastic energy of shoe ``shoe``'s return spring (from its rest) and rest stop at the
    tip travel ``travel`` (m), J."""
    b = L.P_SPRING_BASE + shoe * L.SPRING_STRIDE
    stretch = travel - p[b + L.R_REST_TRAVEL]
    energy = stretch * (p[b + L.R_PRELOAD] + 0.5 * p[b + L.R_RATE] * stretch)
    press = p[b + L.R_STOP_TRAVEL] - travel
    if press > 0.0:
        energy += 0.5 * p[L.P_STOP_STIFFNESS] * press * press
    return energy


@njit(inline="always", **JIT)
def shoe_energy(p, shoe, theta):
    """Elastic energy of shoe ``shoe``'s (0 left, 1 right) return spring and rest stop at
    the shoe angle ``theta`` (rad), J (:func:`stored_energy` at its tip's travel)."""
    base = L.P_SHOE_BASE + shoe * L.SHOE_STRIDE
    phi = p[base + L.S_SIGN] * theta
    travel = tip_travel(p, base, np.cos(phi), np.sin(phi), 0.0)[0]
    return stored_energy(p, shoe, travel)


@njit(**JIT_ALLOCATING)
def stored_energy_rows(p, left_angle, right_angle):
    """Elastic energy of both shoes' springs and stops (J, :func:`shoe_energy`) at each
    pair of shoe angles (rad, arrays of one length)."""
    out = np.zeros(left_angle.shape[0])
    for i in range(left_angle.shape[0]):
        out[i] += shoe_energy(p, 0, left_angle[i])
        out[i] += shoe_energy(p, 1, right_angle[i])
    return out
