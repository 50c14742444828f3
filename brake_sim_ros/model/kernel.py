"""Compiled (numba) right-hand side, sample evaluation and fixed-step RK4 stepping.

Everything here takes plain floats and float64/int64 arrays laid out as in
:mod:`brake_sim_ros.model.layout`; dataclasses are unpacked at the boundary
(:mod:`brake_sim_ros.model.assembly`).

Contact geometry. A shoe is rigid and turns by ``phi = sign * theta`` about its pivot
``P``. Its lining is an arc of radius ``r`` around the point ``C`` (the drum centre when
the shoe is at rest, so the running clearance is ``R_d - r``). The lining point farthest
from the drum centre is on the ray from the origin through ``C`` when that ray crosses
the arc, otherwise at the arc end angularly nearest to it; its distance from the centre
minus ``R_d`` is the indentation ``eps``. The normal is the drum's outward normal there.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from brake_sim_ros.model import layout as L


@njit(cache=True, inline="always")
def _pwl(t, ts, fs):
    """Piecewise-linear interpolation, held constant outside the knots."""
    n = ts.shape[0]
    if t <= ts[0]:
        return fs[0]
    if t >= ts[n - 1]:
        return fs[n - 1]
    lo = 0
    hi = n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if ts[mid] <= t:
            lo = mid
        else:
            hi = mid
    w = (t - ts[lo]) / (ts[hi] - ts[lo])
    return fs[lo] + w * (fs[hi] - fs[lo])


@njit(cache=True, inline="always")
def _contact_point(p, base, c, sn):
    """Lining point farthest from the drum centre for a shoe turned by phi (cos c, sin sn).

    Returns (x, y, distance from the drum centre, unit normal x, unit normal y), m.
    """
    px = p[base + L.S_PIVOT_X]
    py = p[base + L.S_PIVOT_Y]
    dx = p[base + L.S_LINING_CENTRE_X] - px
    dy = p[base + L.S_LINING_CENTRE_Y] - py
    cx = px + c * dx - sn * dy
    cy = py + sn * dx + c * dy
    m0x = p[base + L.S_LINING_MID_COS]
    m0y = p[base + L.S_LINING_MID_SIN]
    mx = c * m0x - sn * m0y
    my = sn * m0x + c * m0y
    r = p[base + L.S_LINING_RADIUS]
    ce = math.sqrt(cx * cx + cy * cy)
    if ce > 1e-300:
        ux = cx / ce
        uy = cy / ce
    else:
        ux = mx
        uy = my
    if ux * mx + uy * my >= p[base + L.S_LINING_HALF_COS]:
        # the ray from the drum centre through the arc centre crosses the lining
        return cx + r * ux, cy + r * uy, ce + r, ux, uy
    hc = p[base + L.S_LINING_HALF_COS]
    hs = p[base + L.S_LINING_HALF_SIN]
    if mx * uy - my * ux < 0.0:
        hs = -hs
    ex = hc * mx - hs * my
    ey = hs * mx + hc * my
    xx = cx + r * ex
    xy = cy + r * ey
    dist = math.sqrt(xx * xx + xy * xy)
    return xx, xy, dist, xx / dist, xy / dist


@njit(cache=True, inline="always")
def shoe_eval(p, base, theta, omega, drum_speed, actuation, mode, locked=0):
    """Forces on one shoe and what they do.

    Args:
        p: packed parameters. base: index of this shoe's block.
        theta, omega: shoe angle (rad) and speed (rad/s), positive outward.
        drum_speed: drum angular speed about +z, rad/s.
        actuation: actuation force on the tip, N (gain already applied).
        mode: CONTACT_AUTO (contact while eps > 0), CONTACT_OFF or CONTACT_ON.
        locked: != 0 when the brake holds the drum at standstill. The drum is held and the
            coupling twist frozen, so no tangential load passes through the linings:
            friction is zero and each shoe settles where Fn d = Fe q.

    Returns:
        (theta_ddot rad/s^2, drum torque N m, eps m, eps_dot m/s, Fn N, Ff N,
         sliding speed m/s, contact x m, contact y m, net applied force x N,
         net applied force y N, friction power W, contact loss power W,
         actuation power W)
        The net applied force is contact + friction + actuation on the shoe.
    """
    s = p[base + L.S_SIGN]
    px = p[base + L.S_PIVOT_X]
    py = p[base + L.S_PIVOT_Y]
    phi = s * theta
    c = math.cos(phi)
    sn = math.sin(phi)
    xx, xy, dist, nx, ny = _contact_point(p, base, c, sn)
    eps = dist - p[L.P_DRUM_RADIUS]
    w = s * omega
    # velocity of the shoe's material point at the contact
    vx = -w * (xy - py)
    vy = w * (xx - px)
    eps_dot = nx * vx + ny * vy
    vt = -ny * vx + nx * vy  # along the counter-clockwise tangent (-ny, nx)
    v_slide = drum_speed * dist - vt  # drum surface relative to the shoe
    in_contact = eps > 0.0 if mode == L.CONTACT_AUTO else mode == L.CONTACT_ON
    enabled = p[base + L.S_ENABLED] > 0.0
    fn = 0.0
    if in_contact and enabled:
        fn = p[L.P_CONTACT_STIFFNESS] * eps + p[L.P_CONTACT_DAMPING] * eps_dot
        if fn < 0.0:
            fn = 0.0  # a contact never pulls
    ff = 0.0
    if fn > 0.0 and not locked:
        ff = p[L.P_FRICTION_COEFFICIENT] * fn * math.tanh(v_slide / p[L.P_FRICTION_SMOOTHING_SPEED])
    fcx = -fn * nx - ff * ny
    fcy = -fn * ny + ff * nx
    # actuation on the tip, fixed world direction
    tdx = p[base + L.S_TIP_X] - px
    tdy = p[base + L.S_TIP_Y] - py
    tx = c * tdx - sn * tdy
    ty = sn * tdx + c * tdy
    fex = actuation * p[base + L.S_ACTUATION_DIR_X]
    fey = actuation * p[base + L.S_ACTUATION_DIR_Y]
    moment = (xx - px) * fcy - (xy - py) * fcx + tx * fey - ty * fex
    theta_ddot = s * moment / p[base + L.S_INERTIA] if enabled else 0.0
    drum_torque = -ff * dist
    p_fric = ff * v_slide
    p_contact = 0.0
    if in_contact and enabled and eps > 0.0:
        # Kelvin-Voigt loss: power into the contact minus the rate of elastic energy
        p_contact = (fn - p[L.P_CONTACT_STIFFNESS] * eps) * eps_dot
    p_act = fex * (-w * ty) + fey * (w * tx)
    return (
        theta_ddot,
        drum_torque,
        eps,
        eps_dot,
        fn,
        ff,
        v_slide,
        xx,
        xy,
        fcx + fex,
        fcy + fey,
        p_fric,
        p_contact,
        p_act,
    )


@njit(cache=True)
def evaluate(y, p, fe_left, fe_right, locked, mode_left, mode_right, dydt, out, row, t):
    """Time derivative of the state ``y`` (layout.Y_*) into ``dydt``; if ``row >= 0``, also
    every recorded quantity at time ``t`` into ``out[row]`` (layout.COLUMNS).

    ``fe_left``/``fe_right`` are the actuation forces after the share gain, N.
    ``locked`` != 0 holds flywheel and drum at rest (brake locked at standstill).
    """
    wd = 0.0 if locked else y[L.Y_DRUM_SPEED]
    bl = L.P_SHOE_BASE
    br = L.P_SHOE_BASE + L.SHOE_STRIDE
    sl = shoe_eval(p, bl, y[L.Y_LEFT_ANGLE], y[L.Y_LEFT_SPEED], wd, fe_left, mode_left, locked)
    sr = shoe_eval(p, br, y[L.Y_RIGHT_ANGLE], y[L.Y_RIGHT_SPEED], wd, fe_right, mode_right, locked)
    dydt[L.Y_LEFT_ANGLE] = y[L.Y_LEFT_SPEED]
    dydt[L.Y_RIGHT_ANGLE] = y[L.Y_RIGHT_SPEED]
    dydt[L.Y_LEFT_SPEED] = sl[0]
    dydt[L.Y_RIGHT_SPEED] = sr[0]
    dydt[L.Y_FRICTION_WORK] = sl[11] + sr[11]
    dydt[L.Y_CONTACT_LOSS] = sl[12] + sr[12]
    dydt[L.Y_ACTUATION_WORK] = sl[13] + sr[13]
    if locked:
        dydt[L.Y_FLYWHEEL_ANGLE] = 0.0
        dydt[L.Y_DRUM_ANGLE] = 0.0
        dydt[L.Y_FLYWHEEL_SPEED] = 0.0
        dydt[L.Y_DRUM_SPEED] = 0.0
        dydt[L.Y_COUPLING_DAMPER_LOSS] = 0.0
    elif p[L.P_RIGID_COUPLING] > 0.0:
        acc = (sl[1] + sr[1]) / (p[L.P_FLYWHEEL_INERTIA] + p[L.P_DRUM_INERTIA])
        dydt[L.Y_FLYWHEEL_ANGLE] = y[L.Y_DRUM_SPEED]
        dydt[L.Y_DRUM_ANGLE] = y[L.Y_DRUM_SPEED]
        dydt[L.Y_FLYWHEEL_SPEED] = acc
        dydt[L.Y_DRUM_SPEED] = acc
        dydt[L.Y_COUPLING_DAMPER_LOSS] = 0.0
    else:
        twist = y[L.Y_FLYWHEEL_ANGLE] - y[L.Y_DRUM_ANGLE]
        slip = y[L.Y_FLYWHEEL_SPEED] - y[L.Y_DRUM_SPEED]
        coupling = p[L.P_COUPLING_STIFFNESS] * twist + p[L.P_COUPLING_DAMPING] * slip
        dydt[L.Y_FLYWHEEL_ANGLE] = y[L.Y_FLYWHEEL_SPEED]
        dydt[L.Y_DRUM_ANGLE] = y[L.Y_DRUM_SPEED]
        dydt[L.Y_FLYWHEEL_SPEED] = -coupling / p[L.P_FLYWHEEL_INERTIA]
        dydt[L.Y_DRUM_SPEED] = (coupling + sl[1] + sr[1]) / p[L.P_DRUM_INERTIA]
        dydt[L.Y_COUPLING_DAMPER_LOSS] = p[L.P_COUPLING_DAMPING] * slip * slip
    if row < 0:
        return
    o = out[row]
    o[0] = t
    for i in range(8):
        o[1 + i] = y[i]
    o[9] = sl[2]
    o[10] = sr[2]
    o[11] = sl[4]
    o[12] = sr[4]
    o[13] = sl[5]
    o[14] = sr[5]
    o[15] = fe_left
    o[16] = fe_right
    rlx, rly = _pivot_force(p, bl, y[L.Y_LEFT_ANGLE], y[L.Y_LEFT_SPEED], sl[0], sl[9], sl[10])
    rrx, rry = _pivot_force(p, br, y[L.Y_RIGHT_ANGLE], y[L.Y_RIGHT_SPEED], sr[0], sr[9], sr[10])
    o[17] = rlx
    o[18] = rly
    o[19] = rrx
    o[20] = rry
    o[21] = sl[7]
    o[22] = sl[8]
    o[23] = sr[7]
    o[24] = sr[8]
    for i in range(4):
        o[25 + i] = y[L.Y_FRICTION_WORK + i]
    o[33] = sl[3]
    o[34] = sr[3]
    o[35] = sl[6]
    o[36] = sr[6]


@njit(cache=True)
def evaluate_rows(ys, times, p, fe_left, fe_right, locked, out):
    """Recorded quantities for many states: ``ys`` (n, N_STATE) at ``times`` into ``out``."""
    dydt = np.empty(ys.shape[1])
    for i in range(ys.shape[0]):
        evaluate(
            ys[i],
            p,
            fe_left[i],
            fe_right[i],
            locked,
            L.CONTACT_AUTO,
            L.CONTACT_AUTO,
            dydt,
            out,
            i,
            times[i],
        )


@njit(cache=True)
def rhs(y, p, fe_left, fe_right, locked, mode_left, mode_right, dydt):
    """Time derivative only (see :func:`evaluate`)."""
    no_out = np.empty((0, L.N_COLUMNS))
    evaluate(y, p, fe_left, fe_right, locked, mode_left, mode_right, dydt, no_out, -1, 0.0)


@njit(cache=True, inline="always")
def _pivot_force(p, base, theta, omega, theta_ddot, fx, fy):
    """Force the pivot pin exerts on the shoe: m a_G - (applied forces), N."""
    s = p[base + L.S_SIGN]
    px = p[base + L.S_PIVOT_X]
    py = p[base + L.S_PIVOT_Y]
    phi = s * theta
    c = math.cos(phi)
    sn = math.sin(phi)
    gx0 = p[base + L.S_MASS_CENTRE_X] - px
    gy0 = p[base + L.S_MASS_CENTRE_Y] - py
    gx = c * gx0 - sn * gy0
    gy = sn * gx0 + c * gy0
    w = s * omega
    a = s * theta_ddot
    m = p[base + L.S_MASS]
    ax = -a * gy - w * w * gx
    ay = a * gx - w * w * gy
    return m * ax - fx, m * ay - fy


@njit(cache=True, inline="always")
def _update_regime(kstate, k_regime, k_flag, k_change, touching, step, settle_steps):
    if touching != kstate[k_flag]:
        kstate[k_flag] = touching
        kstate[k_change] = step
    since = step - kstate[k_change]
    regime = kstate[k_regime]
    if touching:
        if regime == L.REGIME_FREE:
            regime = L.REGIME_IMPACTING
        elif regime == L.REGIME_IMPACTING and since >= settle_steps:
            regime = L.REGIME_CONTACT
    else:
        if regime == L.REGIME_CONTACT:
            regime = L.REGIME_IMPACTING
        elif regime == L.REGIME_IMPACTING and since >= settle_steps:
            regime = L.REGIME_FREE
    kstate[k_regime] = regime


@njit(cache=True)
def rk4_advance(
    y,
    step0,
    dt,
    n_steps,
    p,
    tl,
    fl,
    tr,
    fr,
    gain_override,
    kstate,
    fstate,
    settle_steps,
    record_every,
    out,
):
    """Advance ``y`` in place by ``n_steps`` classical RK4 steps of ``dt`` seconds.

    Time is ``(step0 + i) * dt`` exactly, so runs are reproducible bit for bit.
    Actuation: piecewise-linear knots (tl, fl) and (tr, fr), times in s; they are
    evaluated at every stage time and multiplied by the shoes' gains (layout S_ACTUATION_GAIN)
    unless ``gain_override`` is 0.

    One sample (layout.COLUMNS) is written to ``out`` every ``record_every`` steps, at
    the start of the step, from the same evaluation RK4 needs for its first stage.
    ``kstate`` (int64, layout.K_*) and ``fstate`` (float64: [lock time s, lock loss J])
    carry lock and regime bookkeeping between calls.

    Returns the number of rows written. Stops early (status in kstate) on a non-finite state.
    """
    n = y.shape[0]
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    tmp = np.empty(n)
    gl = p[L.P_SHOE_BASE + L.S_ACTUATION_GAIN]
    gr = p[L.P_SHOE_BASE + L.SHOE_STRIDE + L.S_ACTUATION_GAIN]
    if gain_override != 0:
        gl = 1.0
        gr = 1.0
    v_lock = p[L.P_FRICTION_SMOOTHING_SPEED]
    radius = p[L.P_DRUM_RADIUS]
    rows = 0
    auto = L.CONTACT_AUTO
    for i in range(n_steps):
        step = step0 + i
        t = step * dt
        locked = kstate[L.K_LOCKED]
        fel = gl * _pwl(t, tl, fl)
        fer = gr * _pwl(t, tr, fr)
        record = i % record_every == 0
        evaluate(y, p, fel, fer, locked, auto, auto, k1, out, rows if record else -1, t)
        if record:
            touching_l = 1 if out[rows, 9] > 0.0 and p[L.P_SHOE_BASE + L.S_ENABLED] > 0.0 else 0
            touching_r = (
                1
                if (out[rows, 10] > 0.0 and p[L.P_SHOE_BASE + L.SHOE_STRIDE + L.S_ENABLED] > 0.0)
                else 0
            )
        else:
            # contact flags still drive the regime bookkeeping on unrecorded steps
            touching_l = 1 if _touching(p, L.P_SHOE_BASE, y[L.Y_LEFT_ANGLE]) else 0
            touching_r = 1 if _touching(p, L.P_SHOE_BASE + L.SHOE_STRIDE, y[L.Y_RIGHT_ANGLE]) else 0
        _update_regime(
            kstate,
            L.K_LEFT_REGIME,
            L.K_LEFT_IN_CONTACT,
            L.K_LEFT_LAST_CHANGE_STEP,
            touching_l,
            step,
            settle_steps,
        )
        _update_regime(
            kstate,
            L.K_RIGHT_REGIME,
            L.K_RIGHT_IN_CONTACT,
            L.K_RIGHT_LAST_CHANGE_STEP,
            touching_r,
            step,
            settle_steps,
        )
        if record:
            o = out[rows]
            rl = kstate[L.K_LEFT_REGIME]
            rr = kstate[L.K_RIGHT_REGIME]
            o[31] = rl
            o[32] = rr
            if locked:
                o[30] = L.REGIME_STOPPED
            elif rl == L.REGIME_IMPACTING or rr == L.REGIME_IMPACTING:
                o[30] = L.REGIME_IMPACTING
            elif rl == L.REGIME_CONTACT or rr == L.REGIME_CONTACT:
                o[30] = L.REGIME_CONTACT
            else:
                o[30] = L.REGIME_FREE
            o[29] = fstate[1]
            rows += 1
        th = t + 0.5 * dt
        fel = gl * _pwl(th, tl, fl)
        fer = gr * _pwl(th, tr, fr)
        for j in range(n):
            tmp[j] = y[j] + 0.5 * dt * k1[j]
        evaluate(tmp, p, fel, fer, locked, auto, auto, k2, out, -1, t)
        for j in range(n):
            tmp[j] = y[j] + 0.5 * dt * k2[j]
        evaluate(tmp, p, fel, fer, locked, auto, auto, k3, out, -1, t)
        t1 = (step + 1) * dt
        fel = gl * _pwl(t1, tl, fl)
        fer = gr * _pwl(t1, tr, fr)
        for j in range(n):
            tmp[j] = y[j] + dt * k3[j]
        evaluate(tmp, p, fel, fer, locked, auto, auto, k4, out, -1, t)
        speed_before = y[L.Y_DRUM_SPEED]
        for j in range(n):
            y[j] += dt / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
        if not locked:
            surface = abs(y[L.Y_DRUM_SPEED]) * radius
            if surface <= v_lock and (kstate[L.K_LEFT_IN_CONTACT] or kstate[L.K_RIGHT_IN_CONTACT]):
                # standstill: the brake locks; interpolate the instant |v| reached v_lock
                before = abs(speed_before) * radius
                frac = 1.0
                if before > surface:
                    frac = (before - v_lock) / (before - surface)
                    frac = min(max(frac, 0.0), 1.0)
                fstate[0] = (step + frac) * dt
                fstate[1] += 0.5 * p[L.P_FLYWHEEL_INERTIA] * y[L.Y_FLYWHEEL_SPEED] ** 2
                fstate[1] += 0.5 * p[L.P_DRUM_INERTIA] * y[L.Y_DRUM_SPEED] ** 2
                y[L.Y_FLYWHEEL_SPEED] = 0.0
                y[L.Y_DRUM_SPEED] = 0.0
                kstate[L.K_LOCKED] = 1
        finite = True
        for j in range(8):
            if not math.isfinite(y[j]):
                finite = False
        if not finite:
            kstate[L.K_STATUS] = 1
            return rows
    return rows


@njit(cache=True, inline="always")
def _touching(p, base, theta):
    """Whether the shoe's lining penetrates the drum at angle ``theta`` (geometry only)."""
    phi = p[base + L.S_SIGN] * theta
    dist = _contact_point(p, base, math.cos(phi), math.sin(phi))[2]
    return dist > p[L.P_DRUM_RADIUS] and p[base + L.S_ENABLED] > 0.0
