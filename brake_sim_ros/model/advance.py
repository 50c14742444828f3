"""Compiled (numba) fixed-step loop: every scheme of the fixed-step stepper over a block of
samples (:func:`fixed_step_advance`), with the contact regimes, the stick and slip at
standstill, the growth of defects, a drive cycle's control and the thermal state.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from brake_sim_ros.model import (
    contact,
    cycle,
    growth,
    growth_energy,
    kernel,
    ratchet,
    rk4,
    standstill,
    thermal,
)
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.compiled import JIT, JIT_ALLOCATING

# by name, not as kernel.NOT_FREE: numba cannot resolve a module's array attribute in a call
from brake_sim_ros.model.kernel import NOT_FREE


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


@njit(**JIT_ALLOCATING)
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
    the step (:func:`.rk4.located_step`); or symplectic (semi-implicit) Euler, which updates the
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
    gains with them); without entries ``p`` is used as it is. Where a lining's wear grows
    on the service brake, its self-adjuster steps then too (:mod:`.ratchet`, its teeth
    in fstate). The energy a law of time's step of the geometry moves is booked in the
    contact loss (:mod:`.growth_energy`).

    A drive cycle (``p``'s P_CYCLE_COUNT > 0, :mod:`.cycle`) replaces the actuation knots
    by its brake force ramp and sets the drive torque and the vehicle's load: its
    controller runs at the start of every step, from the state then, in the working copy
    (its state in kstate/fstate).
    Without a cycle, a live target speed (P_LIVE_SPEED_CONTROL) sets the drive torque so,
    by the same speed controller (:func:`.cycle.live_control`).

    Returns the number of rows written. Stops early (status in kstate) on a non-finite state.

    This shell allocates the loop's arrays (scratch, and the working copy of ``p`` where
    the run changes it) and hands them to :func:`_advance`, which is compiled without
    numba's reference counting (:mod:`.compiled`): allocating here, it would count the
    arrays of every call in the loop.
    """
    n = y.shape[0]
    growing, cycling, speed_held, heating = _changes(p, n)
    pw = growth.working_copy(p) if growing or cycling or speed_held or heating else p
    return _advance(
        y,
        step0,
        dt,
        n_steps,
        p,
        pw,
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
        np.empty((_WORK_ROWS, n)),
        np.empty(2),
        np.empty(4),
        np.zeros(2),
        np.zeros(2),
        NOT_FREE.copy(),
        NOT_FREE.copy(),
    )


@njit(inline="always", **JIT)
def _changes(p, n):
    """What changes ``p`` during a run (into the loop's working copy) for a state of ``n``
    entries: (defects grow; a drive cycle's controller sets the drive torque and the brake
    force; a live target speed sets the drive torque (cycle.LiveDrive); the brake's
    temperature sets the linings' friction, model/thermal.py: a service run carries the
    temperature slot without a thermal state, P_THERMAL 0)."""
    return (
        p[L.P_GROWTH_COUNT] > 0.0,
        p[L.P_CYCLE_COUNT] > 0.0,
        p[L.P_LIVE_SPEED_CONTROL] > 0.0,
        n > L.Y_BRAKE_TEMPERATURE and p[L.P_THERMAL] > 0.0,
    )


# the rows of _advance's scratch: the RK4 stages' and the located steps' (rk4.py), then
# the first stage's derivative and the step's new state
_WORK_ROWS = 10


@njit(**JIT)
def _advance(
    y,
    step0,
    dt,
    n_steps,
    p,
    pw,
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
    work,
    h_start,
    h_end,
    ramp_t,
    ramp_f,
    free,
    never,
):
    """:func:`fixed_step_advance`'s loop, given its arrays: ``pw`` (``p`` itself, or its
    working copy where the run changes it), ``work`` (``_WORK_ROWS`` rows of the state's
    length), the located scheme's switching functions at a step's start (2,) and end (4,),
    a cycle's ramp knots (2,), and two writable copies of :data:`.kernel.NOT_FREE`."""
    n = y.shape[0]
    k1 = work[8]
    y_new = work[9]
    gl = p[L.P_SHOE_BASE + L.S_ACTUATION_GAIN]
    gr = p[L.P_SHOE_BASE + L.SHOE_STRIDE + L.S_ACTUATION_GAIN]
    growing, cycling, speed_held, heating = _changes(p, n)
    if cycling:  # the cycle commands both shoes' brake force (model/cycle.py)
        tl = ramp_t
        fl = ramp_f
        tr = ramp_t
        fr = ramp_f
    # the service brake's self-adjuster steps within the run (model/ratchet.py): only where
    # a lining's wear grows, so the working copy is there
    adjusting = growing and ratchet.ratcheting(p)
    # a law of time's steps of the geometry are booked (model/growth_energy.py): from the
    # step before the block's first, as that step had its parameters
    book_shoes, worked = growth_energy.booked(p)  # the shoes whose energy they move
    if growing:
        resumed = book_shoes if step0 > 0 else 0
        if resumed:
            growth_energy.previous_step(p, pw, (step0 - 1) * dt, y, fstate, adjusting)
        gl, gr, _ = growth_energy.grow(p, pw, step0 * dt, y, fstate, adjusting, resumed, worked)
    if gain_override != 0:
        gl = 1.0
        gr = 1.0
    radius = p[L.P_DRUM_RADIUS]
    rows = 0
    auto = L.CONTACT_AUTO
    located = scheme == L.SCHEME_RK4_LOCATED
    if located:
        h_end[0], h_end[1] = rk4.shoe_switch(pw, 0, y, True)
        h_end[2], h_end[3] = rk4.shoe_switch(pw, 1, y, True)
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
    # the lining over its arc switches on its nodes' (rk4.shoe_switch), not the kinematics'
    can_hold = can_hold and p[L.P_LINING_NODE_STIFFNESS] <= 0.0
    round_drum = p[L.P_DRUM_WAVE_COUNT] <= 0.0 and p[L.P_FLAT_DEPTH] <= 0.0
    # the service brake's tips push (springs, stops, pistons): its free stages evaluate them
    # (kernel.stage_evaluate); with its lining over the arc, its located steps bound them
    # by the deepest node (the switch test's, of the state that starts the step: no step
    # changes the geometry, and a stuck drum, whose evaluation differs, never rides free)
    lined = p[L.P_LINING_NODE_STIFFNESS] > 0.0
    bound = 4 if p[L.P_SERVICE] > 0.0 else 0  # its slots in the bound (kernel.NOT_FREE)
    held = False
    kin_l, kin_r = contact.kinematics_pair(pw, y, 0.0)  # their types: the first step computes them
    # RK4 stages skip the contact geometry where the shoes provably exert nothing
    # (rides_free): on a round drum with a fixed geometry, each shoe's indentation at the
    # step's start and twice the largest distance of its lining from its pivot
    # never: the located sub-steps' (writable: one signature of rk4_step_call)
    free[bound + 1] = 2.0 * kernel.lining_reach(pw, bl)
    free[bound + 3] = 2.0 * kernel.lining_reach(pw, br)
    for i in range(n_steps):
        step = step0 + i
        t = step * dt
        if growing and i > 0:
            gl, gr, moved = growth_energy.grow(p, pw, t, y, fstate, adjusting, book_shoes, worked)
            if gain_override != 0:
                gl = 1.0
                gr = 1.0
            if located and moved:  # the contact modes of the step follow the geometry now
                h_end[0], h_end[1] = rk4.shoe_switch(pw, 0, y, True)
                h_end[2], h_end[3] = rk4.shoe_switch(pw, 1, y, True)
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
        fel = kernel.force(pw, L.P_SHOE_BASE, t, tl, fl, gl)
        fer = kernel.force(pw, L.P_SHOE_BASE + L.SHOE_STRIDE, t, tr, fr, gr)
        record = i % record_every == 0
        if not (held and (round_drum or not stuck)):
            kin_l, kin_r = contact.kinematics_pair(pw, y, 0.0 if stuck else y[L.Y_DRUM_SPEED])
        held = False
        row = rows if record else -1
        kernel.evaluate_from(y, pw, fel, fer, stuck, auto, auto, kin_l, kin_r, k1, out, row, t)
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
            if round_drum and not growing:
                if not lined:
                    free[bound] = kin_l[0]
                    free[bound + 2] = kin_r[0]
                elif located:  # the lining's deepest node at the step's start (h_end)
                    free[bound] = h_end[0]
                    free[bound + 2] = h_end[2]
            rk4.rk4_step_call(
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
                work,
                out,
                y_new,
                free,
            )
            accept = True
            if located:
                if can_hold:
                    # inlined here, the path of every held step; a call elsewhere
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
                    el, hl = rk4.shoe_switch(pw, 0, y_new, True)
                    er, hr = rk4.shoe_switch(pw, 1, y_new, True)
                if (hl > 0.0) != (h_start[0] > 0.0) or (hr > 0.0) != (h_start[1] > 0.0):
                    # a contact switches inside this step: redo it split at the switches
                    fstate[L.F_SWITCHES] += rk4.located_step(
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
                        h_start,
                        work,
                        out,
                        h_end,
                        never,
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
        if stuck:  # the held drum's torques, once a step (its rules' own copies are calls)
            coupling, capacity = standstill.hold_torques(pw, y)
            if standstill.slips_held(pw, coupling, capacity):
                kstate[L.K_STUCK] = 0
                kstate[L.K_BREAKAWAYS] += 1
            elif fstate[L.F_STOP_TIME] < 0.0 and standstill.rests_held(pw, y, capacity):
                fstate[L.F_STOP_TIME] = t + dt
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
        for j in range(8):
            if not math.isfinite(y[j]):
                kstate[L.K_STATUS] = 1
                return rows
    return rows
