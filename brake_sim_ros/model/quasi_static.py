"""Contact-regime model: quasi-static shoes on a flywheel-drum rotor (compiled, numba).

No impact dynamics. Each shoe is massless in its rotation: at every evaluation its angle
is the one where the moments about its pivot balance (actuation on the tip, Kelvin-Voigt
normal force ``k_c eps`` and smoothed Coulomb friction at the geometric contact point;
the same :func:`kernel.shoe_eval` as the full model, called with zero shoe speed). The
balance is solved by a chord-Newton iteration warm-started from the previous solution;
in the hold phase, where neither the actuation nor the (saturated) friction law changes,
one evaluation confirms the previous angle. The pivot reaction is the shoe's static
equilibrium: minus the sum of contact, friction and actuation forces.

The rotor (flywheel and drum on the torsional coupling, or one rigid body) is integrated
with classical RK4 at a macro step that resolves the torsional mode. Near standstill the
smoothed friction law acts on the drum as a viscous damper of slope
``mu Fn R^2 (1 - s^2) / v_s`` (``s = tanh(v / v_s)``): the macro step is then split into
substeps short enough for that rate (``SUBSTEP_RATE_PRODUCT / lambda``). The brake locks
at standstill by the full model's rule (drum surface speed down to ``v_s``).

Arrays: parameters packed as in :mod:`layout`; rotor state ``y`` = [flywheel angle rad,
drum angle rad, flywheel speed rad/s, drum speed rad/s, friction work J, coupling-damper
loss J]; samples are rows of ``layout.COLUMNS`` followed by ``braking_torque_n_m``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from brake_sim_ros.model import kernel
from brake_sim_ros.model import layout as L

N_ROTOR = 6
R_FLY_ANGLE, R_DRUM_ANGLE, R_FLY_SPEED, R_DRUM_SPEED, R_FRICTION, R_DAMPER = range(N_ROTOR)
N_SAMPLE_COLUMNS = L.N_COLUMNS + 1  # + braking torque, N m
COL_BRAKING_TORQUE = L.N_COLUMNS
# Newton tolerance on the shoe angle, rad: 1e-13 rad moves the lining by 2e-14 m, a normal
# force of about 1e-6 N.
ANGLE_TOL_RAD = 1e-13
FD_STEP_RAD = 1e-9
MAX_ITERATIONS = 60
# substep x (stiffest rate of the drum on the friction damper); RK4 is stable to 2.78
SUBSTEP_RATE_PRODUCT = 0.5
MAX_SUBSTEPS = 100_000
STATUS_OK = 0
STATUS_SELF_LOCKING = 1
STATUS_NO_CONVERGENCE = 2
STATUS_NON_FINITE = 3


@njit(cache=True)
def shoe_equilibrium(p, base, fe, drum_speed, locked, touch, guess, slope):
    """Shoe angle where the moments about the pivot balance.

    Args:
        p: packed parameters; base: the shoe's block.
        fe: actuation force after the share gain, N. drum_speed: rad/s.
        locked: != 0 when the brake holds the drum (no friction).
        touch: angle at which the lining just touches the drum, rad.
        guess: starting angle, rad; slope: last known d(theta_ddot)/d(theta), 1/s^2
            (>= 0 for none).

    Returns:
        (theta rad, slope 1/s^2, status, shoe_eval tuple at theta).
    """
    if p[base + L.S_ENABLED] <= 0.0 or fe <= 0.0:
        th = min(guess, touch)
        return (
            th,
            slope,
            STATUS_OK,
            kernel.shoe_eval(p, base, th, 0.0, drum_speed, 0.0, L.CONTACT_AUTO, locked),
        )
    th = max(guess, touch)
    status = STATUS_NO_CONVERGENCE
    out = kernel.shoe_eval(p, base, th, 0.0, drum_speed, fe, L.CONTACT_AUTO, locked)
    for it in range(MAX_ITERATIONS):
        f = out[0]
        if slope >= 0.0 or it >= 2:
            fp = kernel.shoe_eval(
                p, base, th + FD_STEP_RAD, 0.0, drum_speed, fe, L.CONTACT_AUTO, locked
            )[0]
            slope = (fp - f) / FD_STEP_RAD
            if slope >= 0.0:
                # no restoring moment in contact: friction moment beats the contact moment
                status = STATUS_SELF_LOCKING
                break
        step = -f / slope
        if abs(step) <= ANGLE_TOL_RAD:
            status = STATUS_OK
            break
        new = th + step
        if new < touch:
            new = 0.5 * (th + touch)  # stay on the contact branch
        th = new
        out = kernel.shoe_eval(p, base, th, 0.0, drum_speed, fe, L.CONTACT_AUTO, locked)
    return th, slope, status, out


# Friction factor tanh(x) is exactly 1.0 in float64 for x above about 19.1: there the shoe
# balance no longer depends on the drum speed, and a solved balance is reused as long as the
# actuation force is bitwise unchanged (the hold phase of an event).
SATURATED_SLIP = 20.0
# per-shoe cache row: [valid, actuation N, locked, theta rad, contact point's distance from
# the drum centre m, the 14 shoe_eval outputs]. Indexed in 2-D, without row views: a view
# costs a reference count per call, more than the arithmetic it serves.
C_VALID, C_FE, C_LOCKED, C_THETA, C_DIST, C_OUT = 0, 1, 2, 3, 4, 5
N_CACHE = C_OUT + 14


@njit(cache=True)
def _solve_shoe(p, i, fe, wd, locked, touch, shoes, cache):
    """Balance shoe ``i`` for actuation ``fe`` (N) and drum speed ``wd`` (rad/s) into
    ``cache[i]``; returns the status."""
    vs = p[L.P_FRICTION_SMOOTHING_SPEED]
    base = L.P_SHOE_BASE + i * L.SHOE_STRIDE
    th, slope, st, out = shoe_equilibrium(p, base, fe, wd, locked, touch[i], shoes[i], shoes[2 + i])
    shoes[i] = th
    shoes[2 + i] = slope
    valid = st == STATUS_OK and (locked or abs(out[6]) > SATURATED_SLIP * vs)
    cache[i, C_VALID] = 1.0 if valid else 0.0
    cache[i, C_FE] = fe
    cache[i, C_LOCKED] = locked
    cache[i, C_THETA] = th
    cache[i, C_DIST] = math.hypot(out[7], out[8])
    for j in range(14):
        cache[i, C_OUT + j] = out[j]
    return st


@njit(cache=True)
def _record(o, t, y, p, fel, fer, touch, shoes, cache, locked, fstate):
    """One sample row (layout.COLUMNS + braking torque) of the current state."""
    wd = y[R_DRUM_SPEED]
    vs = p[L.P_FRICTION_SMOOTHING_SPEED]
    o[:] = 0.0
    o[0] = t
    o[1] = y[R_FLY_ANGLE]
    o[2] = y[R_DRUM_ANGLE]
    o[5] = y[R_FLY_SPEED]
    o[6] = wd
    torque = 0.0
    any_contact = False
    for i in range(2):
        fe = fel if i == 0 else fer
        reused = False
        if cache[i, C_VALID] > 0.0 and cache[i, C_FE] == fe and cache[i, C_LOCKED] == locked:
            if locked:
                reused = True
            else:
                v_new = wd * cache[i, C_DIST]
                if abs(v_new) > SATURATED_SLIP * vs and v_new * cache[i, C_OUT + 6] > 0.0:
                    cache[i, C_OUT + 6] = v_new
                    cache[i, C_OUT + 11] = cache[i, C_OUT + 5] * v_new
                    reused = True
        if not reused:
            _solve_shoe(p, i, fe, wd, locked, touch, shoes, cache)
        o[3 + i] = cache[i, C_THETA]
        o[9 + i] = cache[i, C_OUT + 2]
        o[11 + i] = cache[i, C_OUT + 4]
        o[13 + i] = cache[i, C_OUT + 5]
        o[15 + i] = fe
        # a shoe at rest: the pin holds it against contact, friction and actuation
        o[17 + 2 * i] = -cache[i, C_OUT + 9]
        o[18 + 2 * i] = -cache[i, C_OUT + 10]
        o[21 + 2 * i] = cache[i, C_OUT + 7]
        o[22 + 2 * i] = cache[i, C_OUT + 8]
        o[35 + i] = cache[i, C_OUT + 6]
        torque += cache[i, C_OUT + 1]
        regime = L.REGIME_FREE
        if cache[i, C_OUT + 4] > 0.0:
            regime = L.REGIME_CONTACT
            any_contact = True
        o[31 + i] = regime
    o[25] = y[R_FRICTION]
    o[26] = y[R_DAMPER]
    o[29] = fstate[1]
    if locked:
        o[30] = L.REGIME_STOPPED
    elif any_contact:
        o[30] = L.REGIME_CONTACT
    else:
        o[30] = L.REGIME_FREE
    o[COL_BRAKING_TORQUE] = -torque


@njit(cache=True)
def advance(y, step0, h, n_steps, p, tl, fl, tr, fr, touch, shoes, cache, kstate, fstate, out):
    """Advance the rotor ``n_steps`` macro steps of ``h`` seconds, one sample per step.

    Time of macro step ``k`` is ``(step0 + k) h`` exactly. Samples are taken at the start of
    each step (as the full model's stepper does). ``kstate`` (int64): [locked, status,
    substeps taken]; ``fstate`` (float64): [lock time s, lock loss J]; ``cache`` (float64,
    (2, N_CACHE)): the shoes' last balances, zeros to start. Returns the rows
    written; stops early with a status (module constants) on failure.

    The RK4 stages and the rotor's right-hand side are written out in this one loop: a
    call per stage passing a dozen arrays costs more than the arithmetic of a stage.
    """
    n = y.shape[0]
    ks = np.empty((4, n))
    tmp = np.empty(n)
    radius = p[L.P_DRUM_RADIUS]
    v_lock = p[L.P_FRICTION_SMOOTHING_SPEED]
    mu = p[L.P_FRICTION_COEFFICIENT]
    i_f = p[L.P_FLYWHEEL_INERTIA]
    i_d = p[L.P_DRUM_INERTIA]
    k_s = p[L.P_COUPLING_STIFFNESS]
    c_s = p[L.P_COUPLING_DAMPING]
    rigid = p[L.P_RIGID_COUPLING] > 0.0
    gl = p[L.P_SHOE_BASE + L.S_ACTUATION_GAIN]
    gr = p[L.P_SHOE_BASE + L.SHOE_STRIDE + L.S_ACTUATION_GAIN]
    stage_c = (0.0, 0.5, 0.5, 1.0)
    for k in range(n_steps):
        t0 = (step0 + k) * h
        t_end = (step0 + k + 1) * h
        fel = gl * kernel._pwl(t0, tl, fl)
        fer = gr * kernel._pwl(t0, tr, fr)
        _record(out[k], t0, y, p, fel, fer, touch, shoes, cache, kstate[0], fstate)
        if kstate[0]:
            continue  # locked: flywheel and drum held, the shoes follow the actuation
        t = t0
        for _ in range(MAX_SUBSTEPS):
            if t >= t_end or kstate[0]:
                break
            hs = t_end - t
            last = True
            for stage in range(4):
                ts = t + stage_c[stage] * hs
                for j in range(n):
                    tmp[j] = y[j] if stage == 0 else y[j] + stage_c[stage] * hs * ks[stage - 1, j]
                # --- rotor right-hand side at (ts, tmp) ---
                wd = tmp[R_DRUM_SPEED]
                torque = 0.0
                power = 0.0
                damper_rate = 0.0  # d(friction torque)/d(drum speed), N m s
                fe_l = gl * kernel._pwl(ts, tl, fl)
                fe_r = gr * kernel._pwl(ts, tr, fr)
                for i in range(2):
                    fe = fe_l if i == 0 else fe_r
                    reused = False
                    if cache[i, C_VALID] > 0.0 and cache[i, C_FE] == fe and cache[i, C_LOCKED] == 0:
                        v_new = wd * cache[i, C_DIST]
                        if abs(v_new) > SATURATED_SLIP * v_lock and v_new * cache[i, C_OUT + 6] > 0:
                            cache[i, C_OUT + 6] = v_new
                            cache[i, C_OUT + 11] = cache[i, C_OUT + 5] * v_new
                            reused = True
                    if not reused:
                        st = _solve_shoe(p, i, fe, wd, 0, touch, shoes, cache)
                        if st != STATUS_OK:
                            kstate[1] = st
                            return k + 1
                    torque += cache[i, C_OUT + 1]
                    power += cache[i, C_OUT + 11]
                    fn = cache[i, C_OUT + 4]
                    if stage == 0 and fn > 0.0 and not reused:
                        dist = cache[i, C_DIST]
                        sf = math.tanh(cache[i, C_OUT + 6] / v_lock)
                        damper_rate += mu * fn * dist * dist * (1.0 - sf * sf) / v_lock
                ks[stage, R_FRICTION] = power
                if rigid:
                    acc = torque / (i_f + i_d)
                    ks[stage, R_FLY_ANGLE] = wd
                    ks[stage, R_DRUM_ANGLE] = wd
                    ks[stage, R_FLY_SPEED] = acc
                    ks[stage, R_DRUM_SPEED] = acc
                    ks[stage, R_DAMPER] = 0.0
                    rate = damper_rate / (i_f + i_d)
                else:
                    slip = tmp[R_FLY_SPEED] - wd
                    coupling = k_s * (tmp[R_FLY_ANGLE] - tmp[R_DRUM_ANGLE]) + c_s * slip
                    ks[stage, R_FLY_ANGLE] = tmp[R_FLY_SPEED]
                    ks[stage, R_DRUM_ANGLE] = wd
                    ks[stage, R_FLY_SPEED] = -coupling / i_f
                    ks[stage, R_DRUM_SPEED] = (coupling + torque) / i_d
                    ks[stage, R_DAMPER] = c_s * slip * slip
                    rate = (damper_rate + c_s) / i_d
                if stage == 0 and rate * hs > SUBSTEP_RATE_PRODUCT:
                    # the drum rides on the friction law's viscous zone: substep
                    hs = SUBSTEP_RATE_PRODUCT / rate
                    last = False
                    if t + hs > t_end - 1e-3 * hs:
                        hs = t_end - t
                        last = True
            before = abs(y[R_DRUM_SPEED]) * radius
            for j in range(n):
                y[j] += hs / 6.0 * (ks[0, j] + 2.0 * ks[1, j] + 2.0 * ks[2, j] + ks[3, j])
            kstate[2] += 1
            surface = abs(y[R_DRUM_SPEED]) * radius
            engaged = cache[0, C_OUT + 4] > 0.0 or cache[1, C_OUT + 4] > 0.0
            if surface <= v_lock and engaged:
                # standstill: the brake locks; interpolate the instant |v| reached v_lock
                frac = 1.0
                if before > surface:
                    frac = min(max((before - v_lock) / (before - surface), 0.0), 1.0)
                fstate[0] = t + frac * hs
                fstate[1] += 0.5 * i_f * y[R_FLY_SPEED] ** 2 + 0.5 * i_d * y[R_DRUM_SPEED] ** 2
                y[R_FLY_SPEED] = 0.0
                y[R_DRUM_SPEED] = 0.0
                kstate[0] = 1
            t = t_end if last else t + hs
            for j in range(4):
                if not math.isfinite(y[j]):
                    kstate[1] = STATUS_NON_FINITE
                    return k + 1
    return n_steps
