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

* Wheel cylinder: never less than the residual line force ``F_r``,
  ``F_cyl = max(F_commanded, F_r)`` (a check valve keeps the residual pressure).
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
from brake_sim_ros.model.compiled import JIT


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
def cylinder_force(p, commanded):
    """The wheel cylinder's force on the tip, N: the commanded (after the shoe's gain), never
    below the residual line force."""
    residual = p[L.P_RESIDUAL_FORCE]
    return commanded if commanded > residual else residual


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
def tip_forces(p, shoe, commanded, travel, rate):
    """(cylinder force N, net outward force at the tip N, stop damper loss W) of shoe
    ``shoe`` for the commanded force ``commanded`` (N, after its gain)."""
    cylinder = cylinder_force(p, commanded)
    stop, loss = stop_force(p, shoe, travel, rate)
    return cylinder, cylinder - spring_force(p, shoe, travel) + stop, loss


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


@njit(**JIT)
def stored_energy_rows(p, left_angle, right_angle):
    """Elastic energy of both shoes' springs and stops (J) at each pair of shoe angles
    (rad, arrays of one length)."""
    out = np.zeros(left_angle.shape[0])
    for i in range(left_angle.shape[0]):
        for shoe in range(2):
            base = L.P_SHOE_BASE + shoe * L.SHOE_STRIDE
            theta = left_angle[i] if shoe == 0 else right_angle[i]
            phi = p[base + L.S_SIGN] * theta
            travel = tip_travel(p, base, np.cos(phi), np.sin(phi), 0.0)[0]
            out[i] += stored_energy(p, shoe, travel)
    return out
