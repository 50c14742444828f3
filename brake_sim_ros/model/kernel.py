"""Compiled (numba) right-hand side, sample evaluation and fixed-step stepping.

Everything here takes plain floats and float64/int64 arrays laid out as in
:mod:`brake_sim_ros.model.layout`; dataclasses are unpacked at the boundary
(:mod:`brake_sim_ros.model.assembly`). The contact law and geometry live in
:mod:`brake_sim_ros.model.contact`, the stick/slip rule at standstill in
:mod:`brake_sim_ros.model.standstill`; this module assembles the equations of motion
from them and steps them.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from brake_sim_ros.model import (
    actuation,
    contact,
    cycle,
    growth,
    service,
    standstill,
    thermal,
    vehicle,
)
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.compiled import JIT

_pwl = actuation.pwl


@njit(inline="always", **JIT)
def _force(p, base, t, ts, fs, gain):
    """Actuation force on the shoe at ``base`` at ``t`` (s), N: the commanded history
    (knots ``ts``, ``fs``) times ``gain``; shaped by the shoe's actuation defects
    (:func:`_shaped_force`) when it has any. The healthy path stays this one line: the
    shaping is a call, not inlined into every RK4 stage."""
    if p[base + L.S_ACTUATION_SHAPED] <= 0.0:
        return gain * _pwl(t, ts, fs)
    return _shaped_force(p, base, t, ts, fs, gain)


@njit(**JIT)
def _shaped_force(p, base, t, ts, fs, gain):
    """:func:`_force` of a shoe with a delay, lag or pulsation (:func:`.actuation.shaped`)
    or a weakened return spring (:func:`.actuation.spring_release`)."""
    force = gain * actuation.shaped(
        t,
        ts,
        fs,
        p[base + L.S_ACTUATION_DELAY],
        p[base + L.S_ACTUATION_LAG],
        p[base + L.S_PULSATION_AMPLITUDE],
        p[base + L.S_PULSATION_FREQUENCY],
    )
    if p[base + L.S_SPRING_RELEASE] <= 0.0:
        return force
    return actuation.spring_release(
        force, p[base + L.S_SPRING_RELEASE], p[base + L.S_SPRING_MARGIN]
    )


@njit(**JIT)
def _driven_flywheel(p, flywheel_speed, coupling, dydt):
    """The flywheel's acceleration and the drive and road-load powers of a vehicle
    (layout.P_DRIVEN): the step's drive torque minus the road load
    (:func:`.vehicle.road_load_torque`) act on it besides the coupling. A call, not inlined:
    the published model's path stays as it was. Returns the road load, N m (a recorded
    sample reports it without computing it again)."""
    drive = p[L.P_DRIVE_TORQUE]
    road = vehicle.road_load_torque(p, flywheel_speed)
    dydt[L.Y_FLYWHEEL_SPEED] = (drive - road - coupling) / p[L.P_FLYWHEEL_INERTIA]
    dydt[L.Y_DRIVE_WORK] = drive * flywheel_speed
    dydt[L.Y_ROAD_LOAD_WORK] = road * flywheel_speed
    return road


@njit(**JIT)
def evaluate(y, p, fe_left, fe_right, stuck, mode_left, mode_right, dydt, out, row, t):
    """Time derivative of the state ``y`` (layout.Y_*) into ``dydt``; if ``row >= 0``, also
    every recorded quantity at time ``t`` into ``out[row]`` (layout.COLUMNS).

    ``fe_left``/``fe_right`` are the actuation forces after the share gain, N.
    ``stuck`` != 0 while static friction holds the drum (model/standstill.py): the drum is
    at rest, the shoes' friction carries the coupling torque, and the flywheel moves on.
    """
    wd = 0.0 if stuck else y[L.Y_DRUM_SPEED]
    wa = y[L.Y_DRUM_ANGLE]
    kl = contact.kinematics(p, L.P_SHOE_BASE, y[L.Y_LEFT_ANGLE], y[L.Y_LEFT_SPEED], wa, wd)
    kr = contact.kinematics(
        p, L.P_SHOE_BASE + L.SHOE_STRIDE, y[L.Y_RIGHT_ANGLE], y[L.Y_RIGHT_SPEED], wa, wd
    )
    _evaluate_from(y, p, fe_left, fe_right, stuck, mode_left, mode_right, kl, kr, dydt, out, row, t)


@njit(inline="always", **JIT)
def _evaluate_from(
    y, p, fe_left, fe_right, stuck, mode_left, mode_right, kl, kr, dydt, out, row, t
):
    """:func:`evaluate` given the shoes' contact kinematics ``kl`` and ``kr``
    (:func:`.contact.kinematics` of ``y``, at the drum speed :func:`evaluate` uses)."""
    wd = 0.0 if stuck else y[L.Y_DRUM_SPEED]
    bl = L.P_SHOE_BASE
    br = L.P_SHOE_BASE + L.SHOE_STRIDE
    fnl = contact.normal_force(p, bl, kl[0], kl[1], mode_left)
    fnr = contact.normal_force(p, br, kr[0], kr[1], mode_right)
    vl = contact.sliding_speed(kl, wd)
    vr = contact.sliding_speed(kr, wd)
    coupling = standstill.coupling_torque(
        p, y[L.Y_FLYWHEEL_ANGLE], y[L.Y_DRUM_ANGLE], y[L.Y_FLYWHEEL_SPEED], wd
    )
    if stuck:
        share = standstill.stuck_share(
            standstill.held_torque(coupling, fnl, kl, fnr, kr),
            standstill.static_capacity(p, fnl, kl[5], fnr, kr[5]),
        )
        ffl = share * p[bl + L.S_FRICTION_COEFFICIENT] * fnl
        ffr = share * p[br + L.S_FRICTION_COEFFICIENT] * fnr
    else:
        ffl = contact.sliding_friction(p, bl, fnl, vl)
        ffr = contact.sliding_friction(p, br, fnr, vr)
    tip_left = fe_left  # the net force along the cylinder axis at each tip, N
    tip_right = fe_right
    serviced = p[L.P_SERVICE] > 0.0  # the service brake: springs, stops, residual force
    stop_loss = 0.0
    rate_left = 0.0
    rate_right = 0.0
    if serviced:
        fe_left, tip_left, stop_loss, rate_left, fe_right, tip_right, rate_right = _service_tips(
            p, y, kl, kr, fe_left, fe_right
        )
    sl = contact.shoe_forces(p, bl, y[L.Y_LEFT_SPEED], tip_left, kl, fnl, ffl, vl)
    sr = contact.shoe_forces(p, br, y[L.Y_RIGHT_SPEED], tip_right, kr, fnr, ffr, vr)
    contact_power = sl[contact.E_CONTACT_POWER] + sr[contact.E_CONTACT_POWER]
    actuation_power = sl[contact.E_ACTUATION_POWER] + sr[contact.E_ACTUATION_POWER]
    if serviced:
        # the stops' dampers lose energy as contacts do; the actuator's work is the
        # cylinders' alone (the springs and stops store theirs: model/service.py)
        contact_power += stop_loss
        actuation_power = fe_left * rate_left + fe_right * rate_right
    road = _derivatives(
        y,
        p,
        wd,
        stuck,
        coupling,
        sl[contact.E_THETA_DDOT],
        sr[contact.E_THETA_DDOT],
        sl[contact.E_FRICTION_POWER],
        sr[contact.E_FRICTION_POWER],
        contact_power,
        actuation_power,
        sl[contact.E_DRUM_TORQUE] + sr[contact.E_DRUM_TORQUE],
        dydt,
    )
    if row < 0:
        return
    o = out[row]
    o[L.C_TIME] = t
    for i in range(8):
        o[L.C_STATE + i] = y[i]
    for i, sh in enumerate((sl, sr)):
        o[L.C_INDENTATION + L.RIGHT_OF_SCALAR * i] = sh[contact.E_EPS]
        o[L.C_NORMAL_FORCE + L.RIGHT_OF_SCALAR * i] = sh[contact.E_FN]
        o[L.C_FRICTION_FORCE + L.RIGHT_OF_SCALAR * i] = sh[contact.E_FF]
        o[L.C_INDENTATION_RATE + L.RIGHT_OF_SCALAR * i] = sh[contact.E_EPS_DOT]
        o[L.C_SLIDING_SPEED + L.RIGHT_OF_SCALAR * i] = sh[contact.E_V_SLIDE]
        o[L.C_CONTACT_X + L.RIGHT_OF_VECTOR * i] = sh[contact.E_CONTACT_X]
        o[L.C_CONTACT_Y + L.RIGHT_OF_VECTOR * i] = sh[contact.E_CONTACT_Y]
    o[L.C_ACTUATION_FORCE] = fe_left
    o[L.C_ACTUATION_FORCE + L.RIGHT_OF_SCALAR] = fe_right
    rlx, rly = _pivot_force(
        p,
        bl,
        kl[8],
        kl[9],
        y[L.Y_LEFT_SPEED],
        sl[contact.E_THETA_DDOT],
        sl[contact.E_APPLIED_X],
        sl[contact.E_APPLIED_Y],
    )
    rrx, rry = _pivot_force(
        p,
        br,
        kr[8],
        kr[9],
        y[L.Y_RIGHT_SPEED],
        sr[contact.E_THETA_DDOT],
        sr[contact.E_APPLIED_X],
        sr[contact.E_APPLIED_Y],
    )
    o[L.C_PIVOT_FX] = rlx
    o[L.C_PIVOT_FY] = rly
    o[L.C_PIVOT_FX + L.RIGHT_OF_VECTOR] = rrx
    o[L.C_PIVOT_FY + L.RIGHT_OF_VECTOR] = rry
    for i in range(4):
        o[L.C_ENERGY + i] = y[L.Y_FRICTION_WORK + i]
    o[L.C_DRUM_STICKING] = 1.0 if stuck else 0.0
    for i in range(2):
        o[L.C_LINING_WEAR + L.RIGHT_OF_SCALAR * i] = p[
            L.P_LINING_BASE + i * L.LINING_STRIDE + L.LN_WEAR
        ]

    o[L.C_DRIVE_TORQUE] = p[L.P_DRIVE_TORQUE]
    o[L.C_ROAD_LOAD_TORQUE] = road
    o[L.C_DRIVE_WORK] = y[L.Y_DRIVE_WORK]
    o[L.C_ROAD_LOAD_WORK] = y[L.Y_ROAD_LOAD_WORK]
    o[L.C_PHASE] = -1.0  # no cycle; fixed_step_advance writes a cycle's segment
    o[L.C_BRAKE_TEMPERATURE] = (
        y[L.Y_BRAKE_TEMPERATURE] if y.shape[0] > L.Y_BRAKE_TEMPERATURE else p[L.P_HELD_TEMPERATURE]
    )
    o[L.C_FLYWHEEL_INERTIA] = p[L.P_FLYWHEEL_INERTIA]
    o[L.C_LOAD_CHANGE_WORK] = 0.0  # no load change; fixed_step_advance writes a cycle's


@njit(**JIT)
def _service_tips(p, y, kl, kr, fe_left, fe_right):
    """The service brake's tip forces (:mod:`.service`) of both shoes, given their contact
    kinematics ``kl``/``kr`` and commanded forces (N, after their gains): (left cylinder
    force N, left net force at the tip N, both stops' damper loss W, left tip speed m/s,
    then the right shoe's cylinder force, net force and tip speed). A call, not inlined:
    the study brake's path stays as it was."""
    bl = L.P_SHOE_BASE
    br = L.P_SHOE_BASE + L.SHOE_STRIDE
    ul, rate_l, _ = service.tip_travel(p, bl, kl[8], kl[9], y[L.Y_LEFT_SPEED])
    ur, rate_r, _ = service.tip_travel(p, br, kr[8], kr[9], y[L.Y_RIGHT_SPEED])
    cyl_l, net_l, loss_l = service.tip_forces(p, 0, fe_left, ul, rate_l)
    cyl_r, net_r, loss_r = service.tip_forces(p, 1, fe_right, ur, rate_r)
    return cyl_l, net_l, loss_l + loss_r, rate_l, cyl_r, net_r, rate_r


@njit(inline="always", **JIT)
def _derivatives(
    y,
    p,
    wd,
    stuck,
    coupling,
    accel_left,
    accel_right,
    friction_left,
    friction_right,
    contact_power,
    actuation_power,
    drum_torque,
    dydt,
):
    """Write ``dydt`` from the shoes' results: their angular accelerations (rad/s^2), each
    one's friction power and their summed contact and actuation powers (W), their summed
    torque on the drum and the coupling's (N m), for the drum speed ``wd`` the evaluation
    uses (0 while it sticks). Returns the road load of a driven flywheel, N m (0 else)."""
    dydt[L.Y_LEFT_ANGLE] = y[L.Y_LEFT_SPEED]
    dydt[L.Y_RIGHT_ANGLE] = y[L.Y_RIGHT_SPEED]
    dydt[L.Y_LEFT_SPEED] = accel_left
    dydt[L.Y_RIGHT_SPEED] = accel_right
    dydt[L.Y_FRICTION_WORK] = friction_left + friction_right
    dydt[L.Y_CONTACT_LOSS] = contact_power
    dydt[L.Y_ACTUATION_WORK] = actuation_power
    if y.shape[0] > L.Y_LEFT_WEAR:  # a lining wears with its friction work (layout.Y_*_WEAR)
        _wear_rates(p, friction_left, friction_right, dydt)
    if y.shape[0] > L.Y_BRAKE_TEMPERATURE:  # the brake's thermal state (model/thermal.py)
        dydt[L.Y_BRAKE_TEMPERATURE] = thermal.heating_rate(
            p, dydt[L.Y_FRICTION_WORK], wd, y[L.Y_BRAKE_TEMPERATURE]
        )
    dydt[L.Y_DRIVE_WORK] = 0.0
    dydt[L.Y_ROAD_LOAD_WORK] = 0.0
    road = 0.0  # N m, the road load of a driven flywheel
    rigid = p[L.P_RIGID_COUPLING] > 0.0
    if rigid:
        # one rotor body: held as a whole while stuck (its friction share is then 0)
        acc = 0.0 if stuck else drum_torque / (p[L.P_FLYWHEEL_INERTIA] + p[L.P_DRUM_INERTIA])
        dydt[L.Y_FLYWHEEL_ANGLE] = wd
        dydt[L.Y_DRUM_ANGLE] = wd
        dydt[L.Y_FLYWHEEL_SPEED] = acc
        dydt[L.Y_DRUM_SPEED] = acc
        dydt[L.Y_COUPLING_DAMPER_LOSS] = 0.0
    else:
        slip = y[L.Y_FLYWHEEL_SPEED] - wd
        dydt[L.Y_FLYWHEEL_ANGLE] = y[L.Y_FLYWHEEL_SPEED]
        if p[L.P_DRIVEN] > 0.0:
            road = _driven_flywheel(p, y[L.Y_FLYWHEEL_SPEED], coupling, dydt)
        else:
            dydt[L.Y_FLYWHEEL_SPEED] = -coupling / p[L.P_FLYWHEEL_INERTIA]
        dydt[L.Y_DRUM_ANGLE] = wd
        dydt[L.Y_DRUM_SPEED] = 0.0 if stuck else (coupling + drum_torque) / p[L.P_DRUM_INERTIA]
        dydt[L.Y_COUPLING_DAMPER_LOSS] = p[L.P_COUPLING_DAMPING] * slip * slip
    return road


@njit(inline="always", **JIT)
def _free_evaluate(y, p, dydt):
    """:func:`evaluate`'s derivative for a state whose shoes exert nothing: the drum
    slides, no actuation force, and neither shoe presses (its indentation is not positive
    and its contact is not forced on). Every shoe force is then an exact zero, so the
    shoes' accelerations, powers and drum torque are zeros (of either sign: they add to
    the state as +0.0 does) and the rest is the rotors' (same bits as :func:`evaluate`,
    without the contact geometry; :func:`_rides_free` decides when it applies)."""
    wd = y[L.Y_DRUM_SPEED]
    coupling = standstill.coupling_torque(
        p, y[L.Y_FLYWHEEL_ANGLE], y[L.Y_DRUM_ANGLE], y[L.Y_FLYWHEEL_SPEED], wd
    )
    _derivatives(y, p, wd, 0, coupling, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, dydt)


# a free-ride bound that never holds (:func:`_rides_free`): every stage evaluates in full
NOT_FREE = np.ones(4)


@njit(inline="always", **JIT)
def _lining_reach(p, base):
    """Largest distance of the shoe's lining from its pivot, m: at most that of the
    lining's arc centre plus the arc's radius."""
    dx = p[base + L.S_LINING_CENTRE_X] - p[base + L.S_PIVOT_X]
    dy = p[base + L.S_LINING_CENTRE_Y] - p[base + L.S_PIVOT_Y]
    return math.sqrt(dx * dx + dy * dy) + p[base + L.S_LINING_RADIUS]


@njit(inline="always", **JIT)
def _rides_free(y, y0, free_bound, stuck, ml, mr, fel, fer):
    """Whether an RK4 stage at ``y`` of a step from ``y0`` may take :func:`_free_evaluate`:
    the drum slides, no force on either shoe's tip, neither contact forced on, and each
    shoe's indentation provably negative. ``free_bound`` (4,): the indentation at ``y0``
    (m) and the bound of its rate per radian of shoe angle (m/rad) for the left shoe, then
    the right; a positive indentation there disables the test. The lining point farthest
    from the drum centre moves away from it by at most its distance from the pivot per
    radian the shoe turns, so ``eps <= eps0 + bound |theta - theta0|`` on a round drum."""
    if stuck or fel != 0.0 or fer != 0.0 or ml == L.CONTACT_ON or mr == L.CONTACT_ON:
        return False
    dl = abs(y[L.Y_LEFT_ANGLE] - y0[L.Y_LEFT_ANGLE])
    dr = abs(y[L.Y_RIGHT_ANGLE] - y0[L.Y_RIGHT_ANGLE])
    return free_bound[0] + free_bound[1] * dl < 0.0 and free_bound[2] + free_bound[3] * dr < 0.0


@njit(**JIT)
def _wear_rates(p, power_left, power_right, dydt):
    """Wear rates of the linings, m/s: each shoe's wear per joule (layout.LN_WEAR_RATE,
    0 but for a lining that wears with its friction work, from its onset) times its own
    friction power (contact.E_FRICTION_POWER, W)."""
    b = L.P_LINING_BASE + L.LN_WEAR_RATE
    dydt[L.Y_LEFT_WEAR] = p[b] * power_left
    dydt[L.Y_RIGHT_WEAR] = p[b + L.LINING_STRIDE] * power_right


@njit(**JIT)
def evaluate_rows(ys, times, p, fe_left, fe_right, stuck, out):
    """Recorded quantities for many states: ``ys`` (n, N_STATE) at ``times`` into ``out``
    (``stuck``: the drum's stick state for all of them)."""
    dydt = np.empty(ys.shape[1])
    for i in range(ys.shape[0]):
        evaluate(
            ys[i],
            p,
            fe_left[i],
            fe_right[i],
            stuck,
            L.CONTACT_AUTO,
            L.CONTACT_AUTO,
            dydt,
            out,
            i,
            times[i],
        )


@njit(**JIT)
def rhs(y, p, fe_left, fe_right, stuck, mode_left, mode_right, dydt):
    """Time derivative only (see :func:`evaluate`)."""
    no_out = np.empty((0, L.N_COLUMNS))
    evaluate(y, p, fe_left, fe_right, stuck, mode_left, mode_right, dydt, no_out, -1, 0.0)


@njit(inline="always", **JIT)
def _pivot_force(p, base, c, sn, omega, theta_ddot, fx, fy):
    """Force the pivot pin exerts on the shoe: m a_G - (applied forces), N. ``c``, ``sn``:
    cos and sin of the shoe's turn (from :func:`contact.kinematics`)."""
    s = p[base + L.S_SIGN]
    px = p[base + L.S_PIVOT_X]
    py = p[base + L.S_PIVOT_Y]
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


@njit(inline="always", **JIT)
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


@njit(inline="always", **JIT)
def _shoe_switch(p, shoe, y):
    """:func:`contact.switching_function` of shoe 0 (left) or 1 (right) for the state ``y``."""
    return contact.switching_function(
        p,
        L.P_SHOE_BASE + shoe * L.SHOE_STRIDE,
        y[L.Y_LEFT_ANGLE + shoe],
        y[L.Y_LEFT_SPEED + shoe],
        y[L.Y_DRUM_ANGLE],
        y[L.Y_DRUM_SPEED],
    )


@njit(inline="always", **JIT)
def rk4_step(
    y, k1, t0, h, p, gl, tl, fl, gr, tr, fr, stuck, ml, mr, k2, k3, k4, tmp, out, y_out, free
):
    """One classical RK4 step of ``h`` s from ``y`` at ``t0`` (``k1 = f(t0, y)`` given) with
    the contact modes ``ml``/``mr`` into ``y_out`` (may be ``y`` itself). A stage where
    the shoes provably exert nothing (``free``: :func:`_rides_free`'s bound, or
    :data:`NOT_FREE`) skips their contact geometry (:func:`_free_evaluate`, same bits)."""
    n = y.shape[0]
    th = t0 + 0.5 * h
    fel = _force(p, L.P_SHOE_BASE, th, tl, fl, gl)
    fer = _force(p, L.P_SHOE_BASE + L.SHOE_STRIDE, th, tr, fr, gr)
    for j in range(n):
        tmp[j] = y[j] + 0.5 * h * k1[j]
    if _rides_free(tmp, y, free, stuck, ml, mr, fel, fer):
        _free_evaluate(tmp, p, k2)
    else:
        evaluate(tmp, p, fel, fer, stuck, ml, mr, k2, out, -1, t0)
    for j in range(n):
        tmp[j] = y[j] + 0.5 * h * k2[j]
    if _rides_free(tmp, y, free, stuck, ml, mr, fel, fer):
        _free_evaluate(tmp, p, k3)
    else:
        evaluate(tmp, p, fel, fer, stuck, ml, mr, k3, out, -1, t0)
    t1 = t0 + h
    fel = _force(p, L.P_SHOE_BASE, t1, tl, fl, gl)
    fer = _force(p, L.P_SHOE_BASE + L.SHOE_STRIDE, t1, tr, fr, gr)
    for j in range(n):
        tmp[j] = y[j] + h * k3[j]
    if _rides_free(tmp, y, free, stuck, ml, mr, fel, fer):
        _free_evaluate(tmp, p, k4)
    else:
        evaluate(tmp, p, fel, fer, stuck, ml, mr, k4, out, -1, t0)
    for j in range(n):
        y_out[j] = y[j] + h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])


@njit(**JIT)
def _rk4_step_call(
    y, k1, t0, h, p, gl, tl, fl, gr, tr, fr, stuck, ml, mr, k2, k3, k4, tmp, out, y_out, free
):
    """:func:`rk4_step` as a call: the steps that locate a contact switch take it, the
    plain step inlines it. Each inlined copy is compiled on its own, and the two locating
    functions' three copies took a quarter of the kernels' compile time (212 s of CPU
    against 158 s with this call) for a path a step takes at a switch only."""
    rk4_step(
        y, k1, t0, h, p, gl, tl, fl, gr, tr, fr, stuck, ml, mr, k2, k3, k4, tmp, out, y_out, free
    )


@njit(**JIT)
def _locate_switch(
    shoe, on, ya, ka, t0, rem, f_end, p, gl, tl, fl, gr, tr, fr, stuck, ml, mr, work, out, tol
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
        _rk4_step_call(
            ya,
            ka,
            t0,
            s,
            p,
            gl,
            tl,
            fl,
            gr,
            tr,
            fr,
            stuck,
            ml,
            mr,
            k2,
            k3,
            k4,
            tmp,
            out,
            yb,
            NOT_FREE,
        )
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


@njit(**JIT)
def _located_step(y, k1, t, dt, p, gl, tl, fl, gr, tr, fr, stuck, h_start, work, out, h_end):
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
        _rk4_step_call(
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
            stuck,
            ml,
            mr,
            k2,
            k3,
            k4,
            tmp,
            out,
            yb,
            NOT_FREE,
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
                stuck,
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
                stuck,
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
        _rk4_step_call(
            ya,
            ka,
            t + tau,
            s,
            p,
            gl,
            tl,
            fl,
            gr,
            tr,
            fr,
            stuck,
            ml,
            mr,
            k2,
            k3,
            k4,
            tmp,
            out,
            ya,
            NOT_FREE,
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
        fel = _force(p, L.P_SHOE_BASE, t + tau, tl, fl, gl)
        fer = _force(p, L.P_SHOE_BASE + L.SHOE_STRIDE, t + tau, tr, fr, gr)
        evaluate(ya, p, fel, fer, stuck, ml, mr, ka, out, -1, t)
    for j in range(n):
        y[j] = yb[j]
    h_end[0] = el
    h_end[1] = hl
    h_end[2] = er
    h_end[3] = hr
    return switches


@njit(**JIT)
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
    ``kstate`` (int64, layout.K_*) and ``fstate`` (float64, layout.F_*; F_STOP_TIME < 0
    until the drum first sticks) carry the stick state and the regime bookkeeping between
    calls. At the end of every step the drum's stick/slip rule
    (:mod:`brake_sim_ros.model.standstill`) is applied.

    Defects that change during the run (``p``'s growth entries, :mod:`.growth`) are set
    at the start of every step, at its time, in a working copy of ``p`` (the actuation
    gains with them); without entries ``p`` is used as it is.

    A drive cycle (``p``'s P_CYCLE_COUNT > 0, :mod:`.cycle`) replaces the actuation knots
    by its brake force ramp and sets the drive torque and the vehicle's load: its
    controller runs at the start of every step, from the state then, in the working copy
    (its state in kstate/fstate).
    Without a cycle, a live target speed (P_LIVE_SPEED_CONTROL) sets the drive torque so,
    by the same speed controller (:func:`.cycle.live_control`).

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
    growing = p[L.P_GROWTH_COUNT] > 0.0
    # a vehicle's controller writes the step's drive torque into the working copy
    cycling = p[L.P_CYCLE_COUNT] > 0.0
    speed_held = p[L.P_LIVE_SPEED_CONTROL] > 0.0  # a live target speed (cycle.LiveDrive)
    # the brake's temperature sets the linings' friction (model/thermal.py)
    heating = n > L.Y_BRAKE_TEMPERATURE
    pw = growth.working_copy(p) if growing or cycling or speed_held or heating else p
    ramp_t = np.zeros(2)
    ramp_f = np.zeros(2)
    if cycling:  # the cycle commands both shoes' brake force (model/cycle.py)
        tl = ramp_t
        fl = ramp_f
        tr = ramp_t
        fr = ramp_f
    if growing:
        gl, gr, _ = growth.apply(p, pw, step0 * dt, y)
    if gain_override != 0:
        gl = 1.0
        gr = 1.0
    radius = p[L.P_DRUM_RADIUS]
    rows = 0
    auto = L.CONTACT_AUTO
    located = scheme == L.SCHEME_RK4_LOCATED
    if located:
        h_end[0], h_end[1] = _shoe_switch(pw, 0, y)
        h_end[2], h_end[3] = _shoe_switch(pw, 1, y)
    # The located scheme tests the contact switches on the state that ends a step; the
    # next step's first evaluation needs the same contact kinematics of the same state, so
    # it takes them (kin_l, kin_r; same bits) while nothing changed the state or the
    # geometry in between (held: a step without a located switch, no lock). Not with
    # growing defects (they move the geometry each step) or a shoe removed (its switching
    # function is not its kinematics'); the kinematics read the drum speed, which the
    # evaluation takes as 0 while the drum sticks, only on an out-of-round drum. The
    # other schemes take the contact flags from the first evaluation's kinematics.
    bl = L.P_SHOE_BASE
    br = L.P_SHOE_BASE + L.SHOE_STRIDE
    can_hold = located and not growing and p[bl + L.S_ENABLED] > 0.0 and p[br + L.S_ENABLED] > 0.0
    round_drum = p[L.P_DRUM_WAVE_COUNT] <= 0.0 and p[L.P_FLAT_DEPTH] <= 0.0
    # a service brake's shoes are never free: the spring holds each on its stop
    serviced = p[L.P_SERVICE] > 0.0
    held = False
    kin_l = contact.kinematics(pw, bl, 0.0, 0.0, 0.0, 0.0)
    kin_r = kin_l
    # RK4 stages skip the contact geometry where the shoes provably exert nothing
    # (_rides_free): on a round drum with a fixed geometry, each shoe's indentation at the
    # step's start and twice the largest distance of its lining from its pivot
    free = NOT_FREE.copy()
    free[1] = 2.0 * _lining_reach(pw, bl)
    free[3] = 2.0 * _lining_reach(pw, br)
    for i in range(n_steps):
        step = step0 + i
        t = step * dt
        if growing and i > 0:
            gl, gr, moved = growth.apply(p, pw, t, y)
            if gain_override != 0:
                gl = 1.0
                gr = 1.0
            if located and moved:  # the contact modes of the step follow the geometry now
                h_end[0], h_end[1] = _shoe_switch(pw, 0, y)
                h_end[2], h_end[3] = _shoe_switch(pw, 1, y)
        if heating:
            thermal.fade_linings(p, pw, y[L.Y_BRAKE_TEMPERATURE])
        if cycling:
            cycle.control(pw, p, y, kstate, fstate, t, dt)
            ramp_t[0] = fstate[L.F_RAMP_T0]
            ramp_t[1] = fstate[L.F_RAMP_T1]
            ramp_f[0] = fstate[L.F_RAMP_F0]
            ramp_f[1] = fstate[L.F_RAMP_F1]
        elif speed_held:
            cycle.live_control(pw, y)
        stuck = kstate[L.K_STUCK]
        fel = _force(pw, L.P_SHOE_BASE, t, tl, fl, gl)
        fer = _force(pw, L.P_SHOE_BASE + L.SHOE_STRIDE, t, tr, fr, gr)
        record = i % record_every == 0
        if not (held and (round_drum or not stuck)):
            wa = y[L.Y_DRUM_ANGLE]
            wd = 0.0 if stuck else y[L.Y_DRUM_SPEED]
            kin_l = contact.kinematics(pw, bl, y[L.Y_LEFT_ANGLE], y[L.Y_LEFT_SPEED], wa, wd)
            kin_r = contact.kinematics(pw, br, y[L.Y_RIGHT_ANGLE], y[L.Y_RIGHT_SPEED], wa, wd)
        held = False
        row = rows if record else -1
        _evaluate_from(y, pw, fel, fer, stuck, auto, auto, kin_l, kin_r, k1, out, row, t)
        if located:
            touching_l = 1 if h_end[0] > 0.0 else 0
            touching_r = 1 if h_end[2] > 0.0 else 0
            h_start[0] = h_end[1]
            h_start[1] = h_end[3]
        else:
            # the indentation of the evaluation's kinematics: the switching function's
            # (it does not read the drum speed), of a shoe in the model
            touching_l = 1 if pw[bl + L.S_ENABLED] > 0.0 and kin_l[0] > 0.0 else 0
            touching_r = 1 if pw[br + L.S_ENABLED] > 0.0 and kin_r[0] > 0.0 else 0
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
            o[L.C_SHOE_REGIME] = rl
            o[L.C_SHOE_REGIME + L.RIGHT_OF_SCALAR] = rr
            if stuck:
                o[L.C_REGIME] = L.REGIME_STOPPED
            elif rl == L.REGIME_IMPACTING or rr == L.REGIME_IMPACTING:
                o[L.C_REGIME] = L.REGIME_IMPACTING
            elif rl == L.REGIME_CONTACT or rr == L.REGIME_CONTACT:
                o[L.C_REGIME] = L.REGIME_CONTACT
            else:
                o[L.C_REGIME] = L.REGIME_FREE
            o[L.C_LOCK_LOSS] = fstate[L.F_LOCK_LOSS]
            if cycling:
                o[L.C_PHASE] = kstate[L.K_SEGMENT]
                o[L.C_LOAD_CHANGE_WORK] = fstate[L.F_LOAD_CHANGE_WORK]
            rows += 1
        surface_before = abs(y[L.Y_DRUM_SPEED]) * radius
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
            if round_drum and not growing and not serviced:
                free[0] = kin_l[0]
                free[2] = kin_r[0]
            rk4_step(
                y,
                k1,
                t,
                dt,
                pw,
                gl,
                tl,
                fl,
                gr,
                tr,
                fr,
                stuck,
                ml,
                mr,
                k2,
                k3,
                k4,
                tmp,
                out,
                y_new,
                free,
            )
            accept = True
            if located:
                if can_hold:
                    wa = y_new[L.Y_DRUM_ANGLE]
                    wn = y_new[L.Y_DRUM_SPEED]
                    kin_l = contact.kinematics(
                        pw, bl, y_new[L.Y_LEFT_ANGLE], y_new[L.Y_LEFT_SPEED], wa, wn
                    )
                    kin_r = contact.kinematics(
                        pw, br, y_new[L.Y_RIGHT_ANGLE], y_new[L.Y_RIGHT_SPEED], wa, wn
                    )
                    el, hl = contact.switching_of(pw, kin_l)
                    er, hr = contact.switching_of(pw, kin_r)
                else:
                    el, hl = _shoe_switch(pw, 0, y_new)
                    er, hr = _shoe_switch(pw, 1, y_new)
                if (hl > 0.0) != (h_start[0] > 0.0) or (hr > 0.0) != (h_start[1] > 0.0):
                    # a contact switches inside this step: redo it split at the switches
                    fstate[L.F_SWITCHES] += _located_step(
                        y, k1, t, dt, pw, gl, tl, fl, gr, tr, fr, stuck, h_start, work, out, h_end
                    )
                    accept = False
                else:
                    h_end[0] = el
                    h_end[1] = hl
                    h_end[2] = er
                    h_end[3] = hr
                    held = can_hold
            if accept:
                for j in range(n):
                    y[j] = y_new[j]
        if stuck:
            if standstill.slips(pw, y):
                kstate[L.K_STUCK] = 0
                kstate[L.K_BREAKAWAYS] += 1
        elif standstill.sticks(pw, y, surface_before):
            t_stick = standstill.interpolated_stick_time(
                t,
                dt,
                surface_before,
                abs(y[L.Y_DRUM_SPEED]) * radius,
                p[L.P_FRICTION_SMOOTHING_SPEED],
            )
            if fstate[L.F_WHEEL_LOCK_TIME] < 0.0:
                fstate[L.F_WHEEL_LOCK_TIME] = t_stick
            loss = standstill.stick(pw, y)
            held = False
            fstate[L.F_LOCK_LOSS] += loss
            if heating:  # the kinetic energy the lock removes heats the brake
                y[L.Y_BRAKE_TEMPERATURE] += loss / p[L.P_HEAT_CAPACITY]
            kstate[L.K_STUCK] = 1
            if fstate[L.F_STOP_TIME] < 0.0 and standstill.at_rest(pw, y):
                fstate[L.F_STOP_TIME] = t_stick
        if kstate[L.K_STUCK] and fstate[L.F_STOP_TIME] < 0.0 and standstill.at_rest(pw, y):
            fstate[L.F_STOP_TIME] = t + dt
        for j in range(8):
            if not math.isfinite(y[j]):
                kstate[L.K_STATUS] = 1
                return rows
    return rows


# The shoe's force law is defined once, in model/contact.py; callers that evaluate a single
# shoe (assembly checks, step limits, the quasi-static level) reach it through here too.
shoe_eval = contact.shoe_eval
