"""Compiled (numba) equations of motion: the actuation force, the right-hand side, sample
evaluation and the free-ride bound.

Everything here takes plain floats and float64/int64 arrays laid out as in
:mod:`brake_sim_ros.model.layout`; dataclasses are unpacked at the boundary
(:mod:`brake_sim_ros.model.assembly`). The contact law and geometry live in
:mod:`brake_sim_ros.model.contact`, the stick/slip rule at standstill in
:mod:`brake_sim_ros.model.standstill`; this module assembles the equations of motion
from them. The RK4 step and the location of a contact switch within it are
:mod:`brake_sim_ros.model.rk4`, the fixed-step loop over a block :mod:`brake_sim_ros.model.advance`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from brake_sim_ros.model import actuation, contact, lining, service, standstill, thermal, vehicle
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.compiled import JIT, JIT_ALLOCATING

_pwl = actuation.pwl


@njit(inline="always", **JIT)
def force(p, base, t, ts, fs, gain):
    """Actuation force on the shoe at ``base`` at ``t`` (s), N: the commanded history
    (knots ``ts``, ``fs``) times ``gain``; shaped by the shoe's actuation defects
    (:func:`_shaped_force`) when it has any. The healthy path stays this one line: the
    shaping is a call, not inlined into every RK4 stage."""
    if p[base + L.S_ACTUATION_SHAPED] <= 0.0:
        return gain * _pwl(t, ts, fs)
    return _shaped_force(p, base, t, ts, fs, gain)


@njit(**JIT)
def _shaped_force(p, base, t, ts, fs, gain):
    """:func:`force` of a shoe with a delay, lag or pulsation (:func:`.actuation.shaped`)
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
    evaluate_from(y, p, fe_left, fe_right, stuck, mode_left, mode_right, kl, kr, dydt, out, row, t)


@njit(inline="always", **JIT)
def evaluate_from(y, p, fe_left, fe_right, stuck, mode_left, mode_right, kl, kr, dydt, out, row, t):
    """:func:`evaluate` given the shoes' contact kinematics ``kl`` and ``kr``
    (:func:`.contact.kinematics` of ``y``, at the drum speed :func:`evaluate` uses)."""
    wd = 0.0 if stuck else y[L.Y_DRUM_SPEED]
    bl = L.P_SHOE_BASE
    br = L.P_SHOE_BASE + L.SHOE_STRIDE
    serviced = p[L.P_SERVICE] > 0.0  # the service brake: springs, stops, hydraulics
    stop_loss = 0.0
    service_power = 0.0
    line_rate = 0.0
    if p[L.P_LINING_NODE_STIFFNESS] > 0.0:
        # the service brake's lining over its arc (model/lining.py)
        (
            sl,
            sr,
            coupling,
            tyre_work,
            tyre_rate,
            fe_left,
            fe_right,
            stop_loss,
            service_power,
            line_rate,
        ) = _lined_shoes(p, y, wd, stuck, mode_left, mode_right, kl, kr, fe_left, fe_right)
    else:
        fnl = contact.normal_force(p, bl, kl[0], kl[1], mode_left)
        fnr = contact.normal_force(p, br, kr[0], kr[1], mode_right)
        vl = contact.sliding_speed(kl, wd)
        vr = contact.sliding_speed(kr, wd)
        # the study brake's torsional coupling, or the service brake's tyre (its work and
        # deflection rate: model/tyre.py)
        coupling, tyre_work, tyre_rate = standstill.rotor_coupling(p, y, wd)
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
        if serviced:
            fe_left, tip_left, fe_right, tip_right, stop_loss, service_power, line_rate = (
                _service_tips(p, y, kl[8], kl[9], kr[8], kr[9], fe_left, fe_right)
            )
        sl = contact.shoe_forces(p, bl, y[L.Y_LEFT_SPEED], tip_left, kl, fnl, ffl, vl)
        sr = contact.shoe_forces(p, br, y[L.Y_RIGHT_SPEED], tip_right, kr, fnr, ffr, vr)
    contact_power = sl[contact.E_CONTACT_POWER] + sr[contact.E_CONTACT_POWER]
    actuation_power = sl[contact.E_ACTUATION_POWER] + sr[contact.E_ACTUATION_POWER]
    if serviced:
        # the stops' dampers and the line lose energy as contacts do; the actuator's work
        # is the source's and the pistons' own (the springs, stops and the circuit's
        # compliance store theirs: model/service.py)
        contact_power += stop_loss
        actuation_power = service_power
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
        tyre_work,
        tyre_rate,
        dydt,
    )
    if serviced:
        dydt[L.Y_LINE_PRESSURE] = line_rate
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
    # a service run carries the temperature slot without a thermal state (layout.P_THERMAL)
    heating = y.shape[0] > L.Y_BRAKE_TEMPERATURE and p[L.P_THERMAL] > 0.0
    o[L.C_BRAKE_TEMPERATURE] = y[L.Y_BRAKE_TEMPERATURE] if heating else p[L.P_HELD_TEMPERATURE]
    o[L.C_FLYWHEEL_INERTIA] = p[L.P_FLYWHEEL_INERTIA]
    o[L.C_LOAD_CHANGE_WORK] = 0.0  # no load change; fixed_step_advance writes a cycle's


@njit(**JIT)
def _service_tips(p, y, cl, snl, cr, snr, fe_left, fe_right):
    """The service brake's tip forces (:mod:`.service`) of both shoes, given the cos and
    sin of their turns (``cl``, ``snl``, ``cr``, ``snr``: :func:`.contact.kinematics`'
    slots 8 and 9) and commanded forces (N, after their gains): (left piston
    force N, left net force at the tip N, right piston force N, right net force N, the
    stops' dampers' and the line's loss W, the actuation's power W, the line pressure's
    rate Pa/s). A call, not inlined: the study brake's path stays as it was."""
    bl = L.P_SHOE_BASE
    br = L.P_SHOE_BASE + L.SHOE_STRIDE
    ul, rate_l, _ = service.tip_travel(p, bl, cl, snl, y[L.Y_LEFT_SPEED])
    ur, rate_r, _ = service.tip_travel(p, br, cr, snr, y[L.Y_RIGHT_SPEED])
    cyl_l, cyl_r, line_rate, line_loss, power = service.hydraulics(
        p, y[L.Y_LINE_PRESSURE], fe_left, fe_right, rate_l, rate_r
    )
    net_l, loss_l = service.tip_forces(p, 0, cyl_l, ul, rate_l)
    net_r, loss_r = service.tip_forces(p, 1, cyl_r, ur, rate_r)
    return cyl_l, net_l, cyl_r, net_r, loss_l + loss_r + line_loss, power, line_rate


@njit(**JIT)
def _lined_shoes(p, y, wd, stuck, mode_left, mode_right, kl, kr, fe_left, fe_right):
    """Both shoes of the service brake with its lining distributed over the arc
    (:func:`.lining.shoe_contact`), for the drum speed ``wd`` the evaluation uses: (left and
    right :data:`.contact.N_EVAL` slots, the tyre's coupling N m, work rate W and deflection
    rate m/s, then :func:`_service_tips`' left and right piston forces N, loss W, actuation
    power W and line-pressure rate Pa/s). A call, not inlined: the study brake's path stays
    as it was."""
    bl = L.P_SHOE_BASE
    br = L.P_SHOE_BASE + L.SHOE_STRIDE
    wa = y[L.Y_DRUM_ANGLE]
    coupling, tyre_work, tyre_rate = standstill.rotor_coupling(p, y, wd)
    share = 0.0
    if stuck:
        tl, cl = lining.hold(p, bl, y[L.Y_LEFT_ANGLE], wa)
        tr, cr = lining.hold(p, br, y[L.Y_RIGHT_ANGLE], wa)
        share = standstill.stuck_share(coupling + tl + tr, cl + cr)
    cyl_l, tip_l, cyl_r, tip_r, loss, power, line_rate = _service_tips(
        p, y, kl[8], kl[9], kr[8], kr[9], fe_left, fe_right
    )
    sl = lining.shoe_contact(
        p, bl, y[L.Y_LEFT_ANGLE], y[L.Y_LEFT_SPEED], wd, tip_l, mode_left, stuck, share, wa
    )
    sr = lining.shoe_contact(
        p, br, y[L.Y_RIGHT_ANGLE], y[L.Y_RIGHT_SPEED], wd, tip_r, mode_right, stuck, share, wa
    )
    return sl, sr, coupling, tyre_work, tyre_rate, cyl_l, cyl_r, loss, power, line_rate


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
    tyre_work,
    tyre_rate,
    dydt,
):
    """Write ``dydt`` from the shoes' results: their angular accelerations (rad/s^2), each
    one's friction power and their summed contact and actuation powers (W), their summed
    torque on the drum and the coupling's (N m), for the drum speed ``wd`` the evaluation
    uses (0 while it sticks); on the service brake the coupling is its tyre's, whose work
    rate (W, what the rotors give it: :func:`.tyre.coupling`) the coupling loss books and
    whose deflection rate (m/s) is ``tyre_rate``. Returns the road load of a driven
    flywheel, N m (0 else)."""
    dydt[L.Y_LEFT_ANGLE] = y[L.Y_LEFT_SPEED]
    dydt[L.Y_RIGHT_ANGLE] = y[L.Y_RIGHT_SPEED]
    dydt[L.Y_LEFT_SPEED] = accel_left
    dydt[L.Y_RIGHT_SPEED] = accel_right
    dydt[L.Y_FRICTION_WORK] = friction_left + friction_right
    dydt[L.Y_CONTACT_LOSS] = contact_power
    dydt[L.Y_ACTUATION_WORK] = actuation_power
    if y.shape[0] > L.Y_LEFT_WEAR:  # a lining wears with its friction work (layout.Y_*_WEAR)
        _wear_rates(p, friction_left, friction_right, dydt)
    if y.shape[0] > L.Y_BRAKE_TEMPERATURE:
        if p[L.P_THERMAL] > 0.0:  # the brake's thermal state (model/thermal.py)
            dydt[L.Y_BRAKE_TEMPERATURE] = thermal.heating_rate(
                p, dydt[L.Y_FRICTION_WORK], wd, y[L.Y_BRAKE_TEMPERATURE]
            )
        else:  # a service run without one: its slot stays at the held temperature
            dydt[L.Y_BRAKE_TEMPERATURE] = 0.0
    if y.shape[0] > L.Y_TYRE_DEFLECTION:  # the service brake's states (layout.N_STATE_SERVICE)
        _service_rates(dydt)
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
    if p[L.P_SERVICE] > 0.0:  # the tyre couples them (model/tyre.py): its work and state
        dydt[L.Y_COUPLING_DAMPER_LOSS] = tyre_work
        dydt[L.Y_TYRE_DEFLECTION] = tyre_rate
    return road


@njit(inline="always", **JIT)
def free_evaluate(y, p, dydt):
    """:func:`evaluate`'s derivative for a state whose shoes exert nothing: the drum
    slides, no actuation force, and neither shoe presses (its indentation is not positive
    and its contact is not forced on). Every shoe force is then an exact zero, so the
    shoes' accelerations, powers and drum torque are zeros (of either sign: they add to
    the state as +0.0 does) and the rest is the rotors' (same bits as :func:`evaluate`,
    without the contact geometry; :func:`rides_free` decides when it applies)."""
    wd = y[L.Y_DRUM_SPEED]
    coupling, tyre_work, tyre_rate = standstill.rotor_coupling(p, y, wd)
    _derivatives(
        y, p, wd, 0, coupling, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, tyre_work, tyre_rate, dydt
    )


@njit(**JIT)
def _free_service(y, p, fe_left, fe_right, dydt):
    """The free ride of the service brake (its point contact; :func:`stage_evaluate`): what
    :func:`evaluate_from` computes where neither lining presses, by the same expressions.
    The tips (springs, stops, pistons and the line: :func:`_service_tips`) turn the shoes
    (:func:`.contact.free_acceleration`: the same bits but for the sign of a zero, where
    the tips' moment is an exact zero), their losses are the contact loss (the linings'
    are zeros), the source's power the actuation's, and the tyre couples the rotors. A
    call, not inlined."""
    bl = L.P_SHOE_BASE
    br = L.P_SHOE_BASE + L.SHOE_STRIDE
    wd = y[L.Y_DRUM_SPEED]
    coupling, tyre_work, tyre_rate = standstill.rotor_coupling(p, y, wd)
    # the turns as contact.kinematics computes them (its slots 8 and 9)
    phi_l = p[bl + L.S_SIGN] * y[L.Y_LEFT_ANGLE]
    phi_r = p[br + L.S_SIGN] * y[L.Y_RIGHT_ANGLE]
    cl = math.cos(phi_l)
    snl = math.sin(phi_l)
    cr = math.cos(phi_r)
    snr = math.sin(phi_r)
    _, tip_l, _, tip_r, stop_loss, service_power, line_rate = _service_tips(
        p, y, cl, snl, cr, snr, fe_left, fe_right
    )
    _derivatives(
        y,
        p,
        wd,
        0,
        coupling,
        contact.free_acceleration(p, bl, tip_l, cl, snl),
        contact.free_acceleration(p, br, tip_r, cr, snr),
        0.0,
        0.0,
        0.0 + stop_loss,
        service_power,
        0.0,
        tyre_work,
        tyre_rate,
        dydt,
    )
    dydt[L.Y_LINE_PRESSURE] = line_rate


# a free-ride bound that never holds (:func:`rides_free`, :func:`stage_evaluate`): every
# stage evaluates in full. The study brake's bound in slots 0-3, the service brake's in 4-7
# (each brake leaves the other's at 1: its own test never passes there)
NOT_FREE = np.ones(8)


@njit(inline="always", **JIT)
def lining_reach(p, base):
    """Largest distance of the shoe's lining from its pivot, m: at most that of the
    lining's arc centre plus the arc's radius."""
    dx = p[base + L.S_LINING_CENTRE_X] - p[base + L.S_PIVOT_X]
    dy = p[base + L.S_LINING_CENTRE_Y] - p[base + L.S_PIVOT_Y]
    return math.sqrt(dx * dx + dy * dy) + p[base + L.S_LINING_RADIUS]


@njit(inline="always", **JIT)
def rides_free(y, y0, free_bound, stuck, ml, mr, fel, fer):
    """Whether an RK4 stage at ``y`` of a step from ``y0`` may take :func:`free_evaluate`:
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
def stage_evaluate(
    y, y0, p, free_bound, fe_left, fe_right, stuck, mode_left, mode_right, dydt, out, t
):
    """:func:`evaluate`'s derivative of an RK4 stage at ``y`` of a step from ``y0`` that
    :func:`rides_free` (the study brake's) refused: the service brake's free ride
    (:func:`_free_service`) where its bound (``free_bound`` slots 4-7, as
    :func:`rides_free`'s 0-3: the indentation at ``y0`` and twice the lining's reach, per
    shoe) proves that neither lining presses, the drum slides and no contact is forced on;
    else the full evaluation (``out`` and ``t`` as :func:`evaluate`'s, no row). A call, so
    that the study brake's stages compile as before. Returns whether it rode free."""
    dl = abs(y[L.Y_LEFT_ANGLE] - y0[L.Y_LEFT_ANGLE])
    dr = abs(y[L.Y_RIGHT_ANGLE] - y0[L.Y_RIGHT_ANGLE])
    free = (
        not stuck
        and mode_left != L.CONTACT_ON
        and mode_right != L.CONTACT_ON
        and free_bound[4] + free_bound[5] * dl < 0.0
        and free_bound[6] + free_bound[7] * dr < 0.0
    )
    if free:
        _free_service(y, p, fe_left, fe_right, dydt)
    else:
        evaluate(y, p, fe_left, fe_right, stuck, mode_left, mode_right, dydt, out, -1, t)
    return free


@njit(**JIT)
def _service_rates(dydt):
    """The rates of the service brake's states, 0 until set: the tyre's deflection, which
    :func:`_derivatives` sets after on the service brake; the line pressure's, which
    :func:`evaluate_from` sets after."""
    dydt[L.Y_TYRE_DEFLECTION] = 0.0
    dydt[L.Y_LINE_PRESSURE] = 0.0


@njit(**JIT)
def _wear_rates(p, power_left, power_right, dydt):
    """Wear rates of the linings, m/s: each shoe's wear per joule (layout.LN_WEAR_RATE,
    0 but for a lining that wears with its friction work, from its onset) times its own
    friction power (contact.E_FRICTION_POWER, W)."""
    b = L.P_LINING_BASE + L.LN_WEAR_RATE
    dydt[L.Y_LEFT_WEAR] = p[b] * power_left
    dydt[L.Y_RIGHT_WEAR] = p[b + L.LINING_STRIDE] * power_right


@njit(**JIT_ALLOCATING)
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


@njit(**JIT_ALLOCATING)
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


# The shoe's force law is defined once, in model/contact.py; callers that evaluate a single
# shoe (assembly checks, step limits, the quasi-static level) reach it through here too.
shoe_eval = contact.shoe_eval
