"""Compiled (numba) RK4 step of the equations of motion (:mod:`.kernel`) with frozen
contact modes, and the location of a shoe's contact switch within a step: the steps that
:func:`.advance.fixed_step_advance` takes.
"""

from __future__ import annotations

from numba import njit

from brake_sim_ros.model import contact, kernel, lining
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.compiled import JIT


@njit(**JIT)
def shoe_switch(p, shoe, y, signs_only):
    """:func:`contact.switching_function` of shoe 0 (left) or 1 (right) for the state ``y``
    (the service brake's lining over its arc: :func:`.lining.switching`, a call, which
    skips its nodes where it is clear of the drum and ``signs_only``: a step's end, which
    reads the signs alone besides an upper bound of the indentation; the location of a
    switch, whose values steer it, passes False). A call itself, not inlined: the steps
    test it at a dozen places, and each inlined copy compiles on its own."""
    if p[L.P_LINING_NODE_STIFFNESS] > 0.0:
        return lining.switching(
            p,
            L.P_SHOE_BASE + shoe * L.SHOE_STRIDE,
            y[L.Y_LEFT_ANGLE + shoe],
            y[L.Y_LEFT_SPEED + shoe],
            y[L.Y_DRUM_ANGLE],
            y[L.Y_DRUM_SPEED],
            signs_only,
        )
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
    the shoes provably exert nothing (``free``: :func:`.kernel.rides_free`'s bound and
    :func:`.kernel.stage_evaluate`'s, or :data:`.kernel.NOT_FREE`) skips their contact
    geometry (:func:`.kernel.free_evaluate`, the service brake's in
    :func:`.kernel.stage_evaluate`; same bits)."""
    n = y.shape[0]
    th = t0 + 0.5 * h
    fel = kernel.force(p, L.P_SHOE_BASE, th, tl, fl, gl)
    fer = kernel.force(p, L.P_SHOE_BASE + L.SHOE_STRIDE, th, tr, fr, gr)
    for j in range(n):
        tmp[j] = y[j] + 0.5 * h * k1[j]
    if kernel.rides_free(tmp, y, free, stuck, ml, mr, fel, fer):
        kernel.free_evaluate(tmp, p, k2)
    else:
        kernel.stage_evaluate(tmp, y, p, free, fel, fer, stuck, ml, mr, k2, out, t0)
    for j in range(n):
        tmp[j] = y[j] + 0.5 * h * k2[j]
    if kernel.rides_free(tmp, y, free, stuck, ml, mr, fel, fer):
        kernel.free_evaluate(tmp, p, k3)
    else:
        kernel.stage_evaluate(tmp, y, p, free, fel, fer, stuck, ml, mr, k3, out, t0)
    t1 = t0 + h
    fel = kernel.force(p, L.P_SHOE_BASE, t1, tl, fl, gl)
    fer = kernel.force(p, L.P_SHOE_BASE + L.SHOE_STRIDE, t1, tr, fr, gr)
    for j in range(n):
        tmp[j] = y[j] + h * k3[j]
    if kernel.rides_free(tmp, y, free, stuck, ml, mr, fel, fer):
        kernel.free_evaluate(tmp, p, k4)
    else:
        kernel.stage_evaluate(tmp, y, p, free, fel, fer, stuck, ml, mr, k4, out, t0)
    for j in range(n):
        y_out[j] = y[j] + h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])


@njit(**JIT)
def rk4_step_call(y, k1, t0, h, p, gl, tl, fl, gr, tr, fr, stuck, ml, mr, work, out, y_out, free):
    """:func:`rk4_step` as a call, the one compiled copy of it: every scheme's step and the
    steps that locate a contact switch take it (each inlined copy compiled on its own; the
    plain step's inlined copy and this call's took 33 s and 30 s of the fixed-step
    kernel's 98 s of compile). Its stages' k2, k3, k4 and the stage state are ``work``'s
    rows 0-3 (a 2-D array of rows of the state's length; the kernel's scratch). ``free`` is
    a writable array wherever it is called (the kernel's bound, or a copy of
    :data:`.kernel.NOT_FREE`): one signature, which the tests' calls from Python share."""
    rk4_step(
        y,
        k1,
        t0,
        h,
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
        work[0],
        work[1],
        work[2],
        work[3],
        out,
        y_out,
        free,
    )


@njit(**JIT)
def _locate_switch(
    shoe,
    on,
    ya,
    ka,
    t0,
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
    never,
):
    """Instant (s after ``t0``) where ``shoe`` leaves its contact mode ``on``.

    The RK4 step from ``ya`` (with ``ka = f(ya)``) of length ``s`` and frozen modes is a
    smooth function of ``s``, and so is the shoe's switching function along it. Its sign
    change in ``(0, rem]`` (``f_end``: the mode-signed value at ``rem``, <= 0) is
    bracketed by the Illinois variant of regula falsi to a width ``tol``; the right end of
    the bracket (the first instant at or past the switch) is returned.
    """
    sign = 1.0 if on else -1.0
    yb = work[4]
    a = 0.0
    fa = max(sign * shoe_switch(p, shoe, ya, False)[1], 0.0)
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
        rk4_step_call(
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
            work,
            out,
            yb,
            never,
        )
        fs = sign * shoe_switch(p, shoe, yb, False)[1]
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
def located_step(y, k1, t, dt, p, gl, tl, fl, gr, tr, fr, stuck, h_start, work, out, h_end, never):
    """RK4 step of ``dt`` from ``y`` (in place) with contact switches located in the step.

    The step runs with each shoe's contact mode frozen (the force law is then smooth); a
    trial step whose end has a shoe on the wrong side of its switching function is cut at
    the located switch, the mode flipped there, and the rest of the step taken with the new
    mode: the Kelvin-Voigt jump at onset and the kink at separation never fall inside an RK4
    stage, so RK4 keeps its fourth order. At most ``MAX_SWITCHES_PER_STEP`` switches are
    located per step (a Zeno bounce sequence); beyond that the step finishes with the last
    modes. ``h_start`` (2,) holds the switching functions at ``y``; ``h_end`` (4,) receives
    (eps left, h left, eps right, h right) at the end of the step. ``never``: a free-ride
    bound that never holds (a writable copy of :data:`.kernel.NOT_FREE`): its sub-steps
    start where the caller's bound does not hold.
    """
    n = y.shape[0]
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
        rk4_step_call(
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
            work,
            out,
            yb,
            never,
        )
        el, hl = shoe_switch(p, 0, yb, False)
        er, hr = shoe_switch(p, 1, yb, False)
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
                never,
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
                never,
            )
        s = min(s_l, s_r)
        # shoes switching together (a symmetric brake's) flip together
        flip_l = bad_l and s_l <= s + 2.0 * tol
        flip_r = bad_r and s_r <= s + 2.0 * tol
        rk4_step_call(
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
            work,
            out,
            ya,
            never,
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
            el, hl = shoe_switch(p, 0, yb, False)
            er, hr = shoe_switch(p, 1, yb, False)
            break
        ml = L.CONTACT_ON if on_l else L.CONTACT_OFF
        mr = L.CONTACT_ON if on_r else L.CONTACT_OFF
        fel = kernel.force(p, L.P_SHOE_BASE, t + tau, tl, fl, gl)
        fer = kernel.force(p, L.P_SHOE_BASE + L.SHOE_STRIDE, t + tau, tr, fr, gr)
        kernel.evaluate(ya, p, fel, fer, stuck, ml, mr, ka, out, -1, t)
    for j in range(n):
        y[j] = yb[j]
    h_end[0] = el
    h_end[1] = hl
    h_end[2] = er
    h_end[3] = hr
    return switches
