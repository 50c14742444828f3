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
substeps short enough for that rate (``SUBSTEP_RATE_PRODUCT / lambda``). At standstill the
drum sticks and slips by the full model's rule (:mod:`brake_sim_ros.model.standstill`); while
it sticks the shoes' static friction share and their balances are solved together and the
flywheel moves on.

Arrays: parameters packed as in :mod:`layout`; rotor state ``y`` = [flywheel angle rad,
drum angle rad, flywheel speed rad/s, drum speed rad/s, friction work J, coupling-damper
loss J]; samples are rows of ``layout.COLUMNS`` followed by ``braking_torque_n_m``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from brake_sim_ros.model import contact, kernel, standstill
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.compiled import JIT, JIT_ALLOCATING

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


@njit(**JIT)
def shoe_equilibrium(p, base, fe, drum_speed, stuck, share, touch, guess, slope):
    """Shoe angle where the moments about the pivot balance.

    Args:
        p: packed parameters; base: the shoe's block.
        fe: actuation force after the share gain, N. drum_speed: rad/s.
        stuck, share: != 0 while static friction holds the drum; the friction force is then
            ``share`` (in [-1, 1]) of the shoe's capacity ``mu Fn`` (model/standstill.py).
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
            contact.shoe_eval(p, base, th, 0.0, drum_speed, 0.0, L.CONTACT_AUTO, stuck, share),
        )
    th = max(guess, touch)
    status = STATUS_NO_CONVERGENCE
    out = contact.shoe_eval(p, base, th, 0.0, drum_speed, fe, L.CONTACT_AUTO, stuck, share)
    for it in range(MAX_ITERATIONS):
        f = out[0]
        if slope >= 0.0 or it >= 2:
            fp = contact.shoe_eval(
                p, base, th + FD_STEP_RAD, 0.0, drum_speed, fe, L.CONTACT_AUTO, stuck, share
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
        out = contact.shoe_eval(p, base, th, 0.0, drum_speed, fe, L.CONTACT_AUTO, stuck, share)
    return th, slope, status, out


# Friction factor tanh(x) is exactly 1.0 in float64 for x above about 19.1: there the shoe
# balance no longer depends on the drum speed, and a solved balance is reused as long as the
# actuation force is bitwise unchanged (the hold phase of an event).
SATURATED_SLIP = 20.0
# per-shoe cache row: [valid, actuation N, theta rad, contact point's distance from the drum
# centre m, the 14 shoe_eval outputs]. Indexed in 2-D, without row views: a view costs a
# reference count per call, more than the arithmetic it serves.
C_VALID, C_FE, C_THETA, C_DIST, C_OUT = 0, 1, 2, 3, 4
C_SHARE = C_OUT + contact.N_EVAL  # row 0 only: last static-friction share, warm start
N_CACHE = C_SHARE + 1
# Static-friction share while the drum sticks: fixed-point iteration between the shoes'
# balances and the share, to this tolerance (the map contracts by about mu h / d < 0.5).
SHARE_TOL = 1e-13
MAX_SHARE_ITERATIONS = 60


# The stick state is passed as an np.int64 (``kstate``'s type), never as a literal 0 or 1:
# numba compiles a callee once more for each literal value of an argument.


@njit(**JIT)
def _solve_shoe(p, i, fe, wd, stuck, share, touch, shoes, cache):
    """Balance shoe ``i`` for actuation ``fe`` (N), drum speed ``wd`` (rad/s) and stick state
    into ``cache[i]``; returns the status. A sliding balance with saturated friction is
    marked reusable."""
    vs = p[L.P_FRICTION_SMOOTHING_SPEED]
    base = L.P_SHOE_BASE + i * L.SHOE_STRIDE
    th, slope, st, out = shoe_equilibrium(
        p, base, fe, wd, stuck, share, touch[i], shoes[i], shoes[2 + i]
    )
    shoes[i] = th
    shoes[2 + i] = slope
    valid = st == STATUS_OK and not stuck and abs(out[contact.E_V_SLIDE]) > SATURATED_SLIP * vs
    cache[i, C_VALID] = 1.0 if valid else 0.0
    cache[i, C_FE] = fe
    cache[i, C_THETA] = th
    cache[i, C_DIST] = math.hypot(out[contact.E_CONTACT_X], out[contact.E_CONTACT_Y])
    for j in range(contact.N_EVAL):
        cache[i, C_OUT + j] = out[j]
    return st


@njit(**JIT)
def _balance(p, y, fel, fer, stuck, touch, shoes, cache):
    """Balance both shoes for the rotor state ``y`` into ``cache``; returns the status.

    Sliding: each shoe alone (a saturated balance from the cache is reused while the
    actuation is unchanged). Sticking: the static share of the coupling torque and the
    shoes' normal forces are solved together by fixed-point iteration.
    """
    wd = 0.0 if stuck else y[R_DRUM_SPEED]
    vs = p[L.P_FRICTION_SMOOTHING_SPEED]
    if not stuck:
        for i in range(2):
            fe = fel if i == 0 else fer
            if cache[i, C_VALID] > 0.0 and cache[i, C_FE] == fe:
                v_new = wd * cache[i, C_DIST]
                if (
                    abs(v_new) > SATURATED_SLIP * vs
                    and v_new * cache[i, C_OUT + contact.E_V_SLIDE] > 0
                ):
                    cache[i, C_OUT + contact.E_V_SLIDE] = v_new
                    cache[i, C_OUT + contact.E_FRICTION_POWER] = (
                        cache[i, C_OUT + contact.E_FF] * v_new
                    )
                    continue
            st = _solve_shoe(p, i, fe, wd, np.int64(0), 0.0, touch, shoes, cache)
            if st != STATUS_OK:
                return st
        return STATUS_OK
    coupling = _coupling(p, y, 0.0)
    # Steffensen (Aitken-accelerated) iteration of share -> share(capacity(share)), warm
    # started from the last solution: the coupling torque changes little between stages.
    share = cache[0, C_SHARE]
    for _ in range(MAX_SHARE_ITERATIONS):
        s1, st = _share_map(p, coupling, share, fel, fer, touch, shoes, cache)
        if st != STATUS_OK:
            return st
        if abs(s1 - share) <= SHARE_TOL:
            cache[0, C_SHARE] = s1
            return STATUS_OK
        s2, st = _share_map(p, coupling, s1, fel, fer, touch, shoes, cache)
        if st != STATUS_OK:
            return st
        if abs(s2 - s1) <= SHARE_TOL:
            cache[0, C_SHARE] = s2
            return STATUS_OK
        denom = s2 - 2.0 * s1 + share
        share = s2 if denom == 0.0 else share - (s1 - share) ** 2 / denom
        share = min(max(share, -1.0), 1.0)
    return STATUS_NO_CONVERGENCE


@njit(**JIT)
def _share_map(p, coupling, share, fel, fer, touch, shoes, cache):
    """Balance both shoes with the static share ``share``; returns (the share their normal
    forces imply, status)."""
    for i in range(2):
        st = _solve_shoe(p, i, fel if i == 0 else fer, 0.0, np.int64(1), share, touch, shoes, cache)
        if st != STATUS_OK:
            return share, st
    capacity = standstill.static_capacity(
        p,
        cache[0, C_OUT + contact.E_FN],
        cache[0, C_DIST],
        cache[1, C_OUT + contact.E_FN],
        cache[1, C_DIST],
    )
    return standstill.stuck_share(coupling, capacity), STATUS_OK


@njit(inline="always", **JIT)
def _coupling(p, y, drum_speed):
    """Coupling torque on the drum (model/standstill.py) of the rotor state ``y``, N m."""
    return standstill.coupling_torque(
        p, y[R_FLY_ANGLE], y[R_DRUM_ANGLE], y[R_FLY_SPEED], drum_speed
    )


@njit(**JIT)
def _full_state(y, shoes, out):
    """The full model's state (layout.Y_*) of the rotor state ``y`` and the shoe angles
    (shoes at rest), so that the stick/slip rule of model/standstill.py applies as is."""
    out[:] = 0.0
    out[L.Y_FLYWHEEL_ANGLE] = y[R_FLY_ANGLE]
    out[L.Y_DRUM_ANGLE] = y[R_DRUM_ANGLE]
    out[L.Y_FLYWHEEL_SPEED] = y[R_FLY_SPEED]
    out[L.Y_DRUM_SPEED] = y[R_DRUM_SPEED]
    out[L.Y_LEFT_ANGLE] = shoes[0]
    out[L.Y_RIGHT_ANGLE] = shoes[1]


@njit(**JIT)
def _record(o, t, y, p, fel, fer, stuck, cache, fstate):
    """One sample row (layout.COLUMNS + braking torque) of the balanced state in ``cache``."""
    o[:] = 0.0
    o[L.C_TIME] = t
    o[L.C_STATE + L.Y_FLYWHEEL_ANGLE] = y[R_FLY_ANGLE]
    o[L.C_STATE + L.Y_DRUM_ANGLE] = y[R_DRUM_ANGLE]
    o[L.C_STATE + L.Y_FLYWHEEL_SPEED] = y[R_FLY_SPEED]
    o[L.C_STATE + L.Y_DRUM_SPEED] = y[R_DRUM_SPEED]
    torque = 0.0
    any_contact = False
    for i in range(2):
        o[L.C_STATE + L.Y_LEFT_ANGLE + i] = cache[i, C_THETA]
        o[L.C_INDENTATION + L.RIGHT_OF_SCALAR * i] = cache[i, C_OUT + contact.E_EPS]
        o[L.C_NORMAL_FORCE + L.RIGHT_OF_SCALAR * i] = cache[i, C_OUT + contact.E_FN]
        o[L.C_FRICTION_FORCE + L.RIGHT_OF_SCALAR * i] = cache[i, C_OUT + contact.E_FF]
        o[L.C_ACTUATION_FORCE + L.RIGHT_OF_SCALAR * i] = fel if i == 0 else fer
        # a shoe at rest: the pin holds it against contact, friction and actuation
        o[L.C_PIVOT_FX + L.RIGHT_OF_VECTOR * i] = -cache[i, C_OUT + contact.E_APPLIED_X]
        o[L.C_PIVOT_FY + L.RIGHT_OF_VECTOR * i] = -cache[i, C_OUT + contact.E_APPLIED_Y]
        o[L.C_CONTACT_X + L.RIGHT_OF_VECTOR * i] = cache[i, C_OUT + contact.E_CONTACT_X]
        o[L.C_CONTACT_Y + L.RIGHT_OF_VECTOR * i] = cache[i, C_OUT + contact.E_CONTACT_Y]
        o[L.C_SLIDING_SPEED + L.RIGHT_OF_SCALAR * i] = cache[i, C_OUT + contact.E_V_SLIDE]
        torque += cache[i, C_OUT + contact.E_DRUM_TORQUE]
        regime = L.REGIME_FREE
        if cache[i, C_OUT + contact.E_FN] > 0.0:
            regime = L.REGIME_CONTACT
            any_contact = True
        o[L.C_SHOE_REGIME + L.RIGHT_OF_SCALAR * i] = regime
        o[L.C_LINING_WEAR + L.RIGHT_OF_SCALAR * i] = p[
            L.P_LINING_BASE + i * L.LINING_STRIDE + L.LN_WEAR
        ]
    o[L.C_ENERGY + L.Y_FRICTION_WORK - L.Y_FRICTION_WORK] = y[R_FRICTION]
    o[L.C_ENERGY + L.Y_COUPLING_DAMPER_LOSS - L.Y_FRICTION_WORK] = y[R_DAMPER]
    o[L.C_LOCK_LOSS] = fstate[L.F_LOCK_LOSS]
    if stuck:
        o[L.C_REGIME] = L.REGIME_STOPPED
    elif any_contact:
        o[L.C_REGIME] = L.REGIME_CONTACT
    else:
        o[L.C_REGIME] = L.REGIME_FREE
    o[L.C_DRUM_STICKING] = 1.0 if stuck else 0.0
    o[L.C_PHASE] = -1.0  # no drive cycle at these levels (model/fidelity.py)
    o[L.C_BRAKE_TEMPERATURE] = p[L.P_HELD_TEMPERATURE]  # no thermal state either
    o[L.C_FLYWHEEL_INERTIA] = p[L.P_FLYWHEEL_INERTIA]
    o[L.C_LOAD_CHANGE_WORK] = 0.0
    o[COL_BRAKING_TORQUE] = -torque


@njit(**JIT_ALLOCATING)
def advance(y, step0, h, n_steps, p, tl, fl, tr, fr, touch, shoes, cache, kstate, fstate, out):
    """Advance the rotor ``n_steps`` macro steps of ``h`` seconds, one sample per step.

    Time of macro step ``k`` is ``(step0 + k) h`` exactly. Samples are taken at the start of
    each step (as the full model's stepper does). ``kstate`` (int64): [stuck, status,
    substeps taken, breakaways]; ``fstate`` (float64, layout.F_*; F_STOP_TIME < 0 until the
    drum first sticks); ``cache`` (float64, (2, N_CACHE)): the shoes' last balances, zeros
    to start. Returns the rows written; stops early with a status (module constants) on
    failure. The drum sticks and slips by the full model's rule (model/standstill.py),
    applied after every substep; while it sticks the flywheel moves on.

    The RK4 stages and the rotor's right-hand side are written out in this one loop: a
    call per stage passing a dozen arrays costs more than the arithmetic of a stage.
    """
    n = y.shape[0]
    ks = np.empty((4, n))
    tmp = np.empty(n)
    full = np.zeros(L.N_STATE)
    radius = p[L.P_DRUM_RADIUS]
    v_lock = p[L.P_FRICTION_SMOOTHING_SPEED]
    i_f = p[L.P_FLYWHEEL_INERTIA]
    i_d = p[L.P_DRUM_INERTIA]
    c_s = p[L.P_COUPLING_DAMPING]
    rigid = p[L.P_RIGID_COUPLING] > 0.0
    gl = p[L.P_SHOE_BASE + L.S_ACTUATION_GAIN]
    gr = p[L.P_SHOE_BASE + L.SHOE_STRIDE + L.S_ACTUATION_GAIN]
    stage_c = (0.0, 0.5, 0.5, 1.0)
    # the held drum's shoes were balanced at the end of the last step, which is this step's
    # start: the sample reuses that balance
    held_balanced = False
    for k in range(n_steps):
        t0 = (step0 + k) * h
        t_end = (step0 + k + 1) * h
        fel = gl * kernel._pwl(t0, tl, fl)
        fer = gr * kernel._pwl(t0, tr, fr)
        if not (kstate[0] and held_balanced):
            st = _balance(p, y, fel, fer, kstate[0], touch, shoes, cache)
            if st != STATUS_OK:
                kstate[1] = st
                return k
        _record(out[k], t0, y, p, fel, fer, kstate[0], cache, fstate)
        held_balanced = False
        t = t0
        for _ in range(MAX_SUBSTEPS):
            if t >= t_end:
                break
            stuck = kstate[0]
            hs = t_end - t
            last = True
            for stage in range(4):
                ts = t + stage_c[stage] * hs
                for j in range(n):
                    tmp[j] = y[j] if stage == 0 else y[j] + stage_c[stage] * hs * ks[stage - 1, j]
                # --- rotor right-hand side at (ts, tmp) ---
                wd = 0.0 if stuck else tmp[R_DRUM_SPEED]
                torque = 0.0
                power = 0.0
                damper_rate = 0.0  # d(friction torque)/d(drum speed), N m s
                if not stuck:
                    # (a held drum's rotor does not depend on the shoes: the flywheel
                    # turns on the coupling alone; the shoes are balanced for the samples
                    # and the breakaway check only)
                    fe_l = gl * kernel._pwl(ts, tl, fl)
                    fe_r = gr * kernel._pwl(ts, tr, fr)
                    st = _balance(p, tmp, fe_l, fe_r, np.int64(0), touch, shoes, cache)
                    if st != STATUS_OK:
                        kstate[1] = st
                        return k + 1
                for i in range(2):
                    if stuck:
                        break
                    torque += cache[i, C_OUT + contact.E_DRUM_TORQUE]
                    power += cache[i, C_OUT + contact.E_FRICTION_POWER]
                    fn = cache[i, C_OUT + contact.E_FN]
                    if stage == 0 and fn > 0.0 and not stuck:
                        dist = cache[i, C_DIST]
                        sf = math.tanh(cache[i, C_OUT + contact.E_V_SLIDE] / v_lock)
                        mu = p[L.P_SHOE_BASE + i * L.SHOE_STRIDE + L.S_FRICTION_COEFFICIENT]
                        damper_rate += mu * fn * dist * dist * (1.0 - sf * sf) / v_lock
                ks[stage, R_FRICTION] = power
                if rigid:
                    acc = 0.0 if stuck else torque / (i_f + i_d)
                    ks[stage, R_FLY_ANGLE] = wd
                    ks[stage, R_DRUM_ANGLE] = wd
                    ks[stage, R_FLY_SPEED] = acc
                    ks[stage, R_DRUM_SPEED] = acc
                    ks[stage, R_DAMPER] = 0.0
                    rate = damper_rate / (i_f + i_d)
                else:
                    coupling = _coupling(p, tmp, wd)
                    slip = tmp[R_FLY_SPEED] - wd
                    ks[stage, R_FLY_ANGLE] = tmp[R_FLY_SPEED]
                    ks[stage, R_DRUM_ANGLE] = wd
                    ks[stage, R_FLY_SPEED] = -coupling / i_f
                    ks[stage, R_DRUM_SPEED] = 0.0 if stuck else (coupling + torque) / i_d
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
            # the stick/slip rule of the full model, on the balanced shoes
            if stuck:
                t_new = t_end if last else t + hs
                st = _balance(
                    p,
                    y,
                    gl * kernel._pwl(t_new, tl, fl),
                    gr * kernel._pwl(t_new, tr, fr),
                    np.int64(1),
                    touch,
                    shoes,
                    cache,
                )
                if st != STATUS_OK:
                    kstate[1] = st
                    return k + 1
                held_balanced = last
            _full_state(y, shoes, full)
            if stuck:
                if standstill.slips(p, full):
                    kstate[0] = 0
                    kstate[3] += 1
            elif standstill.sticks(p, full, before):
                t_stick = standstill.interpolated_stick_time(
                    t, hs, before, abs(y[R_DRUM_SPEED]) * radius, v_lock
                )
                if fstate[L.F_WHEEL_LOCK_TIME] < 0.0:
                    fstate[L.F_WHEEL_LOCK_TIME] = t_stick
                fstate[L.F_LOCK_LOSS] += standstill.stick(p, full)
                y[R_FLY_SPEED] = full[L.Y_FLYWHEEL_SPEED]
                y[R_DRUM_SPEED] = full[L.Y_DRUM_SPEED]
                kstate[0] = 1
                if fstate[L.F_STOP_TIME] < 0.0 and standstill.at_rest(p, full):
                    fstate[L.F_STOP_TIME] = t_stick
            if kstate[0] and fstate[L.F_STOP_TIME] < 0.0:
                _full_state(y, shoes, full)
                if standstill.at_rest(p, full):
                    fstate[L.F_STOP_TIME] = t + hs
            t = t_end if last else t + hs
            for j in range(4):
                if not math.isfinite(y[j]):
                    kstate[1] = STATUS_NON_FINITE
                    return k + 1
    return n_steps
