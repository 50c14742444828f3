"""The service brake's tyre between the vehicle (flywheel) and the wheel (drum), compiled
(numba): a lumped LuGre law with the road's friction limit.

Each rule is written here once: the kernel (:mod:`brake_sim_ros.model.kernel`) takes the
tyre's torque, loss and deflection rate, the stick rule (:mod:`.standstill`) its torque
on a held drum, the energy books (:mod:`brake_sim_ros.analysis.energy`) its stored
energy, all from these functions.

The law (Canudas-de-Wit, Tsiotras, Velenis, Basset and Gissinger, "Dynamic friction
models for road/tire longitudinal interaction", Vehicle System Dynamics 39(3), 2003; the
lumped form of Canudas-de-Wit and Tsiotras, IEEE CDC 1999). With the slip speed
``v_r = R (w_d - w_f)`` (m/s: the wheel's surface speed over the vehicle's, negative
when braking; ``R`` the rolling radius, ``w_d`` the drum's and ``w_f`` the flywheel's
speed, rad/s) and the tread's deflection ``z`` (m, the state layout.Y_TYRE_DEFLECTION)::

    g(v_r)  = mu_c + (mu_s - mu_c) exp(-|v_r / v_s|^a)         (the road's Stribeck curve)
    dz/dt   = v_r - sigma0 |v_r| z / g(v_r)
    F       = F_z (sigma0 z + sigma1 dz/dt + sigma2 v_r)        (N, along v_r)

``F_z`` the wheel's vertical load: the mass the flywheel stands for (``I_f / R^2``,
model/vehicle.py) times g, so that a heavier vehicle (a cycle's load factor) presses its
tyre harder. The road pushes the tyre against its slip: the torque on the drum is
``-R F`` and on the flywheel ``+R F``; it replaces the torsional coupling of the study
brake (:func:`.standstill.coupling_torque`), whose twist ``th_f - th_d`` is the tyre's
deflection over ``R`` while nothing slides (``dz/dt = v_r`` for small ``z``).

* Rolling and presliding (``|z|`` below ``g / sigma0``): the tread is a spring of
  ``sigma0 F_z`` N/m with the damper ``sigma1 F_z`` N s/m; a held wheel holds the vehicle.
* Sliding (a locked wheel, ``v_r = -v``): ``z`` settles at ``g(v_r) / sigma0`` within
  ``g / (sigma0 |v_r|)`` s and ``F = -F_z (g(v_r) + sigma2 |v_r|)``: the vehicle
  decelerates at ``g(v) + sigma2 v`` times g.
* Energy: the rotors give the tyre ``F v_r`` (W), of which the tread stores ``sigma0
  F_z z dz/dt`` (it holds ``sigma0 F_z z^2 / 2``) and the rest is lost
  (:func:`loss_power`). The kernel books the whole ``F v_r`` as the tyre's work (the
  recorded ``coupling_damper_loss_j`` on the service brake): the tread's energy is not in
  the recorded sample (the deflection is a state, not a column), and it is at most
  ``mu_s^2 F_z / (2 sigma0)``, 42 J on a dry road, against the 91.6 kJ of a stop from
  100 km/h.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from brake_sim_ros.model import layout as L
from brake_sim_ros.model.compiled import JIT, JIT_ALLOCATING
from brake_sim_ros.model.vehicle import GRAVITY_M_S2


@njit(inline="always", **JIT)
def stribeck(slip_speed, sliding, peak, speed, exponent):
    """The road's friction coefficient at the slip speed ``slip_speed`` (m/s):
    ``sliding + (peak - sliding) exp(-|slip_speed / speed|^exponent)``."""
    ratio = abs(slip_speed / speed)
    # an exponential (exponent 1, the default) skips the power: pow(x, 1) is x, the same
    # bits (tests/model/test_tyre.py checks the compiled power so), at a fifth of the cost
    shape = ratio if exponent == 1.0 else ratio**exponent
    return sliding + (peak - sliding) * math.exp(-shape)


@njit(inline="always", **JIT)
def law(z, slip_speed, sigma0, sigma1, sigma2, sliding, peak, speed, exponent):
    """The LuGre law per newton of load: (force over the load, the deflection's rate
    m/s) at the deflection ``z`` (m) and slip speed ``slip_speed`` (m/s); ``sigma0`` 1/m,
    ``sigma1`` and ``sigma2`` s/m, the Stribeck curve's arguments as :func:`stribeck`."""
    g = stribeck(slip_speed, sliding, peak, speed, exponent)
    rate = slip_speed - sigma0 * abs(slip_speed) * z / g
    return sigma0 * z + sigma1 * rate + sigma2 * slip_speed, rate


@njit(inline="always", **JIT)
def wheel_load(p):
    """The wheel's vertical load, N: the mass the flywheel stands for times g."""
    r = p[L.P_WHEEL_RADIUS]
    return p[L.P_FLYWHEEL_INERTIA] / (r * r) * GRAVITY_M_S2


@njit(inline="always", **JIT)
def coupling(p, z, flywheel_speed, drum_speed):
    """(torque of the tyre on the drum N m, positive counter-clockwise; power the rotors
    give the tyre W, ``F v_r``: what its tread stores, ``sigma0 F_z z dz/dt``, and what
    it loses; the deflection's rate m/s) at the deflection ``z`` (m) and the speeds
    (rad/s). The flywheel takes the opposite torque."""
    r = p[L.P_WHEEL_RADIUS]
    load = wheel_load(p)
    slip = r * (drum_speed - flywheel_speed)
    ratio, rate = law(
        z,
        slip,
        p[L.P_TYRE_STIFFNESS],
        p[L.P_TYRE_DAMPING],
        p[L.P_TYRE_VISCOUS],
        p[L.P_TYRE_SLIDING],
        p[L.P_TYRE_PEAK],
        p[L.P_TYRE_STRIBECK_SPEED],
        p[L.P_TYRE_STRIBECK_EXPONENT],
    )
    force = load * ratio
    return -r * force, force * slip, rate


@njit(inline="always", **JIT)
def loss_power(p, z, rate, power):
    """The tyre's loss (W) of the power ``power`` (W) the rotors give it at the
    deflection ``z`` (m) moving at ``rate`` (m/s): what its tread does not store."""
    return power - p[L.P_TYRE_STIFFNESS] * wheel_load(p) * z * rate


@njit(inline="always", **JIT)
def torsional_stiffness(p):
    """The tread's presliding stiffness seen between flywheel and drum, N m/rad:
    ``sigma0 F_z R^2``."""
    r = p[L.P_WHEEL_RADIUS]
    return p[L.P_TYRE_STIFFNESS] * wheel_load(p) * r * r


@njit(inline="always", **JIT)
def grip_torque(p):
    """The largest torque the tyre holds without sliding, N m: ``mu_s F_z R``."""
    return p[L.P_TYRE_PEAK] * wheel_load(p) * p[L.P_WHEEL_RADIUS]


@njit(inline="always", **JIT)
def stored_energy(p, z):
    """Elastic energy of the tread at the deflection ``z`` (m), J: ``sigma0 F_z z^2 / 2``."""
    return 0.5 * p[L.P_TYRE_STIFFNESS] * wheel_load(p) * z * z


@njit(**JIT_ALLOCATING)
def stored_energy_rows(p, z, flywheel_inertia):
    """:func:`stored_energy` (J) at each deflection ``z`` (m) with the flywheel inertia
    in force there (kg m^2; a cycle's load changes it), arrays of one length."""
    pw = p.copy()
    out = np.zeros(z.shape[0])
    for i in range(z.shape[0]):
        pw[L.P_FLYWHEEL_INERTIA] = flywheel_inertia[i]
        out[i] = stored_energy(pw, z[i])
    return out
