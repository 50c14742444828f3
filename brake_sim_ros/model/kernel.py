"""Compiled (numba) right-hand side, sample evaluation and fixed-step stepping.

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
    if enabled and eps > 0.0:
        # Kelvin-Voigt loss: power into the contact minus the rate of the elastic energy
        # k eps^2 / 2 (booked whenever eps > 0, also while the force is off: with fn = 0
        # the elastic energy the balance counts is lost, not returned)
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


@njit(cache=True, inline="always")
def _contact_switch(p, base, theta, omega):
    """Indentation ``eps`` and switching function ``h`` of one shoe, both in m.

    ``h = min(eps, eps + (c_c / k_c) eps_dot)``: the Kelvin-Voigt force of
    :func:`shoe_eval` is on exactly when ``h > 0`` (the lining penetrates and the force
    would push). Both arguments of the min are lengths, so ``h`` is continuous in the state
    and its zero is the switching instant: ``eps = 0`` at an onset (where the force jumps
    from 0 to ``c_c eps_dot``), ``k_c eps + c_c eps_dot = 0`` at a separation (where it
    reaches 0 continuously, with a kink). A removed shoe returns (-1, -1): never on.
    """
    if p[base + L.S_ENABLED] <= 0.0:
        return -1.0, -1.0
    s = p[base + L.S_SIGN]
    px = p[base + L.S_PIVOT_X]
    py = p[base + L.S_PIVOT_Y]
    phi = s * theta
    xx, xy, dist, nx, ny = _contact_point(p, base, math.cos(phi), math.sin(phi))
    eps = dist - p[L.P_DRUM_RADIUS]
    w = s * omega
    eps_dot = nx * (-w * (xy - py)) + ny * (w * (xx - px))
    g = eps + p[L.P_CONTACT_DAMPING] / p[L.P_CONTACT_STIFFNESS] * eps_dot
    return eps, min(eps, g)


@njit(cache=True, inline="always")
def _shoe_switch(p, shoe, y):
    """:func:`_contact_switch` of shoe 0 (left) or 1 (right) for the state ``y``."""
    return _contact_switch(
        p, L.P_SHOE_BASE + shoe * L.SHOE_STRIDE, y[L.Y_LEFT_ANGLE + shoe], y[L.Y_LEFT_SPEED + shoe]
    )


@njit(cache=True, inline="always")
def _rk4_sub(y, k1, t0, h, p, gl, tl, fl, gr, tr, fr, locked, ml, mr, k2, k3, k4, tmp, out, y_out):
    """One classical RK4 step of ``h`` s from ``y`` at ``t0`` (``k1 = f(t0, y)`` given) with
    the contact modes ``ml``/``mr`` into ``y_out`` (may be ``y`` itself)."""
    n = y.shape[0]
    th = t0 + 0.5 * h
    fel = gl * _pwl(th, tl, fl)
    fer = gr * _pwl(th, tr, fr)
    for j in range(n):
        tmp[j] = y[j] + 0.5 * h * k1[j]
    evaluate(tmp, p, fel, fer, locked, ml, mr, k2, out, -1, t0)
    for j in range(n):
        tmp[j] = y[j] + 0.5 * h * k2[j]
    evaluate(tmp, p, fel, fer, locked, ml, mr, k3, out, -1, t0)
    t1 = t0 + h
    fel = gl * _pwl(t1, tl, fl)
    fer = gr * _pwl(t1, tr, fr)
    for j in range(n):
        tmp[j] = y[j] + h * k3[j]
    evaluate(tmp, p, fel, fer, locked, ml, mr, k4, out, -1, t0)
    for j in range(n):
        y_out[j] = y[j] + h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])


@njit(cache=True)
def _locate_switch(
    shoe, on, ya, ka, t0, rem, f_end, p, gl, tl, fl, gr, tr, fr, locked, ml, mr, work, out, tol
):
    """Instant (s after ``t0``) where ``shoe`` leaves its contact mode ``on``.

    The RK4 step from ``ya`` (with ``ka = f(ya)``) of length ``s`` and frozen modes is a
    smooth function of ``s``, and so is the shoe's switching function along it. Its sign
    change in ``(0, rem]`` (``f_end``: the mode-signed value at ``rem``, <= 0) is
    bracketed by the Illinois variant of regula falsi to a width ``tol``; the right end of
    the bracket (the first instant at or past the switch) is returned.
    """
    sign = 1.0 if on else -1.0
    k2 = work[0]
    k3 = work[1]
    k4 = work[2]
    tmp = work[3]
    yb = work[4]
    a = 0.0
    fa = max(sign * _shoe_switch(p, shoe, ya)[1], 0.0)
    b = rem
    fb = f_end
    side = 0
    for _ in range(80):
        if b - a <= tol:
            break
        s = 0.5 * (a + b)
        if fa > 0.0 and fb < 0.0:
            s = b - fb * (b - a) / (fb - fa)
            if not (a < s < b):
                s = 0.5 * (a + b)
        _rk4_sub(ya, ka, t0, s, p, gl, tl, fl, gr, tr, fr, locked, ml, mr, k2, k3, k4, tmp, out, yb)
        fs = sign * _shoe_switch(p, shoe, yb)[1]
        if fs > 0.0:
            a = s
            fa = fs
            if side == 1:
                fb *= 0.5
            side = 1
        else:
            b = s
            fb = fs
            if side == -1:
                fa *= 0.5
            side = -1
    return b


@njit(cache=True)
def _located_step(y, k1, t, dt, p, gl, tl, fl, gr, tr, fr, locked, h_start, work, out, h_end):
    """RK4 step of ``dt`` from ``y`` (in place) with contact switches located in the step.

    The step runs with each shoe's contact mode frozen (the force law is then smooth); a
    trial step whose end has a shoe on the wrong side of its switching function is cut at
    the located switch, the mode flipped there, and the rest of the step taken with the new
    mode: the Kelvin-Voigt jump at onset and the kink at separation never fall inside an RK4
    stage, so RK4 keeps its fourth order. At most ``MAX_SWITCHES_PER_STEP`` switches are
    located per step (a Zeno bounce sequence); beyond that the step finishes with the last
    modes. ``h_start`` (2,) holds the switching functions at ``y``; ``h_end`` (4,) receives
    (eps left, h left, eps right, h right) at the end of the step.
    """
    n = y.shape[0]
    k2 = work[0]
    k3 = work[1]
    k4 = work[2]
    tmp = work[3]
    ya = work[5]
    yb = work[6]
    ka = work[7]
    on_l = h_start[0] > 0.0
    on_r = h_start[1] > 0.0
    for j in range(n):
        ya[j] = y[j]
        ka[j] = k1[j]
    tol = 1e-10 * dt
    tau = 0.0
    switches = 0
    while True:
        rem = dt - tau
        ml = L.CONTACT_ON if on_l else L.CONTACT_OFF
        mr = L.CONTACT_ON if on_r else L.CONTACT_OFF
        _rk4_sub(
            ya,
            ka,
            t + tau,
            rem,
            p,
            gl,
            tl,
            fl,
            gr,
            tr,
            fr,
            locked,
            ml,
            mr,
            k2,
            k3,
            k4,
            tmp,
            out,
            yb,
        )
        el, hl = _shoe_switch(p, 0, yb)
        er, hr = _shoe_switch(p, 1, yb)
        bad_l = (hl > 0.0) != on_l
        bad_r = (hr > 0.0) != on_r
        if not (bad_l or bad_r) or switches >= L.MAX_SWITCHES_PER_STEP:
            break
        s_l = 2.0 * rem
        s_r = 2.0 * rem
        if bad_l:
            f_end = hl if on_l else -hl
            s_l = _locate_switch(
                0,
                on_l,
                ya,
                ka,
                t + tau,
                rem,
                f_end,
                p,
                gl,
                tl,
                fl,
                gr,
                tr,
                fr,
                locked,
                ml,
                mr,
                work,
                out,
                tol,
            )
        if bad_r:
            f_end = hr if on_r else -hr
            s_r = _locate_switch(
                1,
                on_r,
                ya,
                ka,
                t + tau,
                rem,
                f_end,
                p,
                gl,
                tl,
                fl,
                gr,
                tr,
                fr,
                locked,
                ml,
                mr,
                work,
                out,
                tol,
            )
        s = min(s_l, s_r)
        # shoes switching together (a symmetric brake's) flip together
        flip_l = bad_l and s_l <= s + 2.0 * tol
        flip_r = bad_r and s_r <= s + 2.0 * tol
        _rk4_sub(
            ya, ka, t + tau, s, p, gl, tl, fl, gr, tr, fr, locked, ml, mr, k2, k3, k4, tmp, out, ya
        )
        tau += s
        if flip_l:
            on_l = not on_l
        if flip_r:
            on_r = not on_r
        switches += 1
        if dt - tau <= tol:
            for j in range(n):
                yb[j] = ya[j]
            el, hl = _shoe_switch(p, 0, yb)
            er, hr = _shoe_switch(p, 1, yb)
            break
        ml = L.CONTACT_ON if on_l else L.CONTACT_OFF
        mr = L.CONTACT_ON if on_r else L.CONTACT_OFF
        fel = gl * _pwl(t + tau, tl, fl)
        fer = gr * _pwl(t + tau, tr, fr)
        evaluate(ya, p, fel, fer, locked, ml, mr, ka, out, -1, t)
    for j in range(n):
        y[j] = yb[j]
    h_end[0] = el
    h_end[1] = hl
    h_end[2] = er
    h_end[3] = hr
    return switches


@njit(cache=True)
def fixed_step_advance(
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
    scheme,
):
    """Advance ``y`` in place by ``n_steps`` fixed steps of ``dt`` seconds.

    ``scheme`` (layout.SCHEME_*): classical RK4; RK4 with contact switches located inside
    the step (:func:`_located_step`); or symplectic (semi-implicit) Euler, which updates the
    speeds with the accelerations at the step start and the angles with the new speeds
    (one evaluation per step, first order, the energy quadratures by explicit Euler).

    Time is ``(step0 + i) * dt`` exactly, so runs are reproducible bit for bit.
    Actuation: piecewise-linear knots (tl, fl) and (tr, fr), times in s; they are
    evaluated at every stage time and multiplied by the shoes' gains (layout S_ACTUATION_GAIN)
    unless ``gain_override`` is 0.

    One sample (layout.COLUMNS) is written to ``out`` every ``record_every`` steps, at
    the start of the step, from the same evaluation the scheme needs for its first stage,
    so the output stays on the uniform grid whatever happens inside a step.
    ``kstate`` (int64, layout.K_*) and ``fstate`` (float64: [lock time s, lock loss J,
    located switches]) carry lock and regime bookkeeping between calls.

    Returns the number of rows written. Stops early (status in kstate) on a non-finite state.
    """
    n = y.shape[0]
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    tmp = np.empty(n)
    y_new = np.empty(n)
    work = np.empty((8, n))
    h_start = np.empty(2)
    h_end = np.empty(4)
    gl = p[L.P_SHOE_BASE + L.S_ACTUATION_GAIN]
    gr = p[L.P_SHOE_BASE + L.SHOE_STRIDE + L.S_ACTUATION_GAIN]
    if gain_override != 0:
        gl = 1.0
        gr = 1.0
    v_lock = p[L.P_FRICTION_SMOOTHING_SPEED]
    radius = p[L.P_DRUM_RADIUS]
    rows = 0
    auto = L.CONTACT_AUTO
    located = scheme == L.SCHEME_RK4_LOCATED
    if located:
        h_end[0], h_end[1] = _shoe_switch(p, 0, y)
        h_end[2], h_end[3] = _shoe_switch(p, 1, y)
    for i in range(n_steps):
        step = step0 + i
        t = step * dt
        locked = kstate[L.K_LOCKED]
        fel = gl * _pwl(t, tl, fl)
        fer = gr * _pwl(t, tr, fr)
        record = i % record_every == 0
        evaluate(y, p, fel, fer, locked, auto, auto, k1, out, rows if record else -1, t)
        if located:
            touching_l = 1 if h_end[0] > 0.0 else 0
            touching_r = 1 if h_end[2] > 0.0 else 0
            h_start[0] = h_end[1]
            h_start[1] = h_end[3]
        elif record:
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
        speed_before = y[L.Y_DRUM_SPEED]
        if scheme == L.SCHEME_SEMI_IMPLICIT_EULER:
            for j in range(4, 8):
                y[j] += dt * k1[j]
            for j in range(4):
                y[j] += dt * y[j + 4]
            for j in range(8, n):
                y[j] += dt * k1[j]
        else:
            ml = auto
            mr = auto
            if located:
                # modes frozen for the step; k1 (auto) equals k1 with these modes
                ml = L.CONTACT_ON if h_start[0] > 0.0 else L.CONTACT_OFF
                mr = L.CONTACT_ON if h_start[1] > 0.0 else L.CONTACT_OFF
            th = t + 0.5 * dt
            fel = gl * _pwl(th, tl, fl)
            fer = gr * _pwl(th, tr, fr)
            for j in range(n):
                tmp[j] = y[j] + 0.5 * dt * k1[j]
            evaluate(tmp, p, fel, fer, locked, ml, mr, k2, out, -1, t)
            for j in range(n):
                tmp[j] = y[j] + 0.5 * dt * k2[j]
            evaluate(tmp, p, fel, fer, locked, ml, mr, k3, out, -1, t)
            t1 = (step + 1) * dt
            fel = gl * _pwl(t1, tl, fl)
            fer = gr * _pwl(t1, tr, fr)
            for j in range(n):
                tmp[j] = y[j] + dt * k3[j]
            evaluate(tmp, p, fel, fer, locked, ml, mr, k4, out, -1, t)
            for j in range(n):
                y_new[j] = y[j] + dt / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
            accept = True
            if located:
                el, hl = _shoe_switch(p, 0, y_new)
                er, hr = _shoe_switch(p, 1, y_new)
                if (hl > 0.0) != (h_start[0] > 0.0) or (hr > 0.0) != (h_start[1] > 0.0):
                    # a contact switches inside this step: redo it split at the switches
                    fstate[2] += _located_step(
                        y, k1, t, dt, p, gl, tl, fl, gr, tr, fr, locked, h_start, work, out, h_end
                    )
                    accept = False
                else:
                    h_end[0] = el
                    h_end[1] = hl
                    h_end[2] = er
                    h_end[3] = hr
            if accept:
                for j in range(n):
                    y[j] = y_new[j]
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
