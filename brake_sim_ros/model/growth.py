"""Defects that change during a run, compiled (numba): the shoe placement for a pivot
where it is now, and the update of the packed parameters at a simulated time.

The packed vector ``p`` (:mod:`brake_sim_ros.model.layout`) holds every defect at its
final severity; its growth entries (``P_GROWTH_*``) say which of them change and how
(:func:`brake_sim_ros.model.catalogue.severity_at`, the one definition of the laws).
:func:`apply` writes the parameters at time ``t`` into a working copy ``pw``; the
fixed-step kernel calls it at the start of every physics step, so the physics sees each
severity as it is at that step (held over the step, as the step's contact modes are).
A vector without entries is never copied nor touched: a run whose defects are all present
from the start takes exactly the arithmetic it took before defects could grow.
"""

from __future__ import annotations

import math

from numba import njit

from brake_sim_ros.model import layout as L
from brake_sim_ros.model.compiled import JIT, JIT_ALLOCATING
from brake_sim_ros.model.growth_law import LAW_FRICTION_WORK, severity_at

# mm of wear per MJ of friction work (the scenario's unit) -> m per J (the kernel's)
_MM_PER_MJ_TO_M_PER_J = 1e-9


@njit(**JIT)
def shoe_placement(shift, mirror, pose, px, py, tx, ty, mcx, mcy, inertia0, mass, mid0):
    """Assemble a shoe whose pin sits ``shift`` (a fraction of its nominal radius) out of
    place by the pose rule ``pose``: the rules of
    :func:`brake_sim_ros.model.placement.place_shoe` (documented there).

    Args:
        shift: the pin's radial displacement over its nominal distance from the drum
            centre, 1 (``pct / 100``).
        mirror: +1 for the left shoe, -1 for the right one (the mirror image about y).
        pose: ``layout.POSE_TIP_ABUTMENT`` or ``layout.POSE_EYE_PISTON``.
        px, py: the nominal pin of the left shoe, m. tx, ty: its tip, m.
        mcx, mcy: its mass centre, m. inertia0: its inertia about the nominal pin, kg m^2.
        mass: the shoe's mass, kg. mid0: the polar angle of its lining arc's middle, rad.

    Returns:
        (pin x, pin y, lining centre x, lining centre y, lining middle angle rad, mass
        centre x, mass centre y, inertia about the pin kg m^2, tip x, tip y, turn rad,
        heel seat offset m), in the backing-plate frame (m), for the shoe ``mirror`` says.
        The turn is the body's, about the tip (tip abutment) or about the moved pin (eye),
        in the shoe's own sense.
    """
    qx, qy = px * (1.0 + shift), py * (1.0 + shift)  # the displaced pin P'
    if pose == L.POSE_EYE_PISTON:
        # the body goes with its pin, then turns about it until the tip is back on the
        # piston's stop, x = tx: (a cos - b sin)(turn) = tx - qx for (a, b) = T - P, the
        # root through 0 at no shift
        ax, ay = tx - px, ty - py
        lean = math.atan2(ay, ax)
        reach = math.acos(min(1.0, max(-1.0, (tx - qx) / math.hypot(ax, ay))))
        turn = (reach if lean >= 0.0 else -reach) - lean
        c, s = math.cos(turn), math.sin(turn)
        cx, cy = qx - c * px + s * py, qy - s * px - c * py
        gx = qx + c * (mcx - px) - s * (mcy - py)
        gy = qy + s * (mcx - px) + c * (mcy - py)
        tipy = qy + s * ax + c * ay
        inertia, seat = inertia0, 0.0
    else:
        ax, ay = px - tx, py - ty  # tip -> nominal pin
        bx, by = qx - tx, qy - ty  # tip -> displaced pin
        turn = math.atan2(ax * by - ay * bx, ax * bx + ay * by)
        c, s = math.cos(turn), math.sin(turn)
        # points of the shoe body after the turn about the tip: the lining centre (the
        # drum centre at rest) and the mass centre
        cx = tx + c * (0.0 - tx) - s * (0.0 - ty)
        cy = ty + s * (0.0 - tx) + c * (0.0 - ty)
        gx = tx + c * (mcx - tx) - s * (mcy - ty)
        gy = ty + s * (mcx - tx) + c * (mcy - ty)
        chord = math.hypot(ax, ay)
        seat = (math.hypot(bx, by) - chord) if chord > 0.0 else 0.0
        # parallel-axis theorem: the inertia about the mass centre is the shoe's own
        arm0 = (mcx - px) ** 2 + (mcy - py) ** 2
        arm1 = (gx - qx) ** 2 + (gy - qy) ** 2
        inertia = inertia0 + mass * (arm1 - arm0)
        tipy = ty
    mid = mid0 + turn
    if mirror < 0.0:
        return -qx, qy, -cx, cy, math.pi - mid, -gx, gy, inertia, -tx, tipy, turn, seat
    return qx, qy, cx, cy, mid, gx, gy, inertia, tx, tipy, turn, seat


@njit(**JIT)
def lining_friction(mu, change_pct):
    """Friction coefficient of a lining whose coefficient ``mu`` changed by ``change_pct``
    percent (fade, contamination: negative), 1."""
    return mu * (1.0 + change_pct / 100.0)


@njit(**JIT)
def write_placement(p, base, px, py, cx, cy, mid, gx, gy, inertia, tipx, tipy):
    """Write a shoe's placement (pin, lining centre and middle, mass centre, inertia, tip;
    as :func:`shoe_placement` returns them) into its block at ``base`` of ``p``."""
    p[base + L.S_PIVOT_X] = px
    p[base + L.S_PIVOT_Y] = py
    p[base + L.S_LINING_CENTRE_X] = cx
    p[base + L.S_LINING_CENTRE_Y] = cy
    p[base + L.S_LINING_MID_ANGLE] = mid
    p[base + L.S_LINING_MID_COS] = math.cos(mid)
    p[base + L.S_LINING_MID_SIN] = math.sin(mid)
    p[base + L.S_MASS_CENTRE_X] = gx
    p[base + L.S_MASS_CENTRE_Y] = gy
    p[base + L.S_INERTIA] = inertia
    p[base + L.S_TIP_X] = tipx
    p[base + L.S_TIP_Y] = tipy


@njit(**JIT_ALLOCATING)
def working_copy(p):
    """A copy of ``p`` for :func:`apply`, with no severity set yet."""
    pw = p.copy()
    for j in range(int(p[L.P_GROWTH_COUNT])):
        pw[L.P_GROWTH_BASE + j * L.GROWTH_STRIDE + L.G_NOW] = math.nan
    return pw


@njit(**JIT)
def lining_wear(p, pw, g, shoe, t, y, severity):
    """Lining wear of ``shoe`` (0 left, 1 right) at time ``t`` (s) for the growth entry at
    ``g`` of ``p``, m: ``severity`` (mm, :func:`severity_at` of the entry) for a law of
    time; for a wear driven by friction work (``LAW_FRICTION_WORK``) also sets
    the shoe's wear per joule in ``pw`` (``LN_WEAR_RATE``, used by the motion's wear state
    ``y[Y_LEFT_WEAR + shoe]``): the entry's rate (mm/MJ) from the onset on, 0 before it and
    once the final wear is reached, where the wear is held.
    """
    final = p[g + L.G_FINAL] * 1e-3
    if int(p[g + L.G_LAW]) != LAW_FRICTION_WORK:
        return severity * 1e-3
    worn = y[L.Y_LEFT_WEAR + shoe]
    rate = 0.0
    if t >= p[g + L.G_ONSET] and worn < final:
        rate = p[g + L.G_RATE] * _MM_PER_MJ_TO_M_PER_J
    pw[L.P_LINING_BASE + shoe * L.LINING_STRIDE + L.LN_WEAR_RATE] = rate
    return worn if worn < final else final


# which growth entries :func:`apply` writes: all, only the linings' wears driven by
# friction work (whose geometry follows the motion's wear state), or all but those (the
# laws of time, whose steps of the geometry growth_energy books)
ALL_ENTRIES, WORK_ENTRIES, TIMED_ENTRIES = 0, 1, 2


@njit(**JIT)
def apply(p, pw, t, y, entries):
    """Write the parameters at simulated time ``t`` (s) of every growing defect of ``p``
    into ``pw`` (:func:`working_copy` of ``p``); return the shoes' actuation gains (left,
    right) and whether any geometry changed since the last call (the contact's switching
    functions must then be re-evaluated). ``y``: the state at ``t`` (a lining that wears
    with friction work reads its wear there, :func:`lining_wear`). ``entries``: which
    entries (``ALL_ENTRIES``, ``WORK_ENTRIES``, ``TIMED_ENTRIES``); the gains are
    those of the entries written (``p``'s unless a share or gain grows among them).

    A pivot re-places its shoe (:func:`shoe_placement`); an actuation share sets this
    shoe's share to ``0.5 + s`` and the other's to ``0.5 - s``, an actuation gain change
    its pressure factor ``1 + s/100`` (the gain is ``2 share factor``,
    :func:`.actuation.shoe_gain`); a pulsation sets its amplitude; a friction change
    sets the shoe's lining coefficient (:func:`lining_friction`); a drum out of round
    scales every harmonic by ``s / s_final``, a drum flat sets its depth, a lining wear
    the shoe's lining radius (the unworn one less the wear). A severity equal to the one
    set last (before the onset, once the final one is reached) is not written again.
    """
    bl = L.P_SHOE_BASE
    br = L.P_SHOE_BASE + L.SHOE_STRIDE
    gain_l = p[bl + L.S_ACTUATION_GAIN]
    gain_r = p[br + L.S_ACTUATION_GAIN]
    share_l = p[bl + L.S_SHARE]
    share_r = p[br + L.S_SHARE]
    pressure_l = p[bl + L.S_PRESSURE_FACTOR]
    pressure_r = p[br + L.S_PRESSURE_FACTOR]
    regain = False
    nb = L.P_NOMINAL_BASE
    moved = False
    for j in range(int(p[L.P_GROWTH_COUNT])):
        g = L.P_GROWTH_BASE + j * L.GROWTH_STRIDE
        if entries != ALL_ENTRIES and (entries == WORK_ENTRIES) != (
            int(p[g + L.G_LAW]) == LAW_FRICTION_WORK
        ):
            continue
        final = p[g + L.G_FINAL]
        s = severity_at(
            t, int(p[g + L.G_LAW]), p[g + L.G_ONSET], p[g + L.G_RATE], p[g + L.G_START], final
        )
        kind = int(p[g + L.G_KIND])
        shoe = int(p[g + L.G_SHOE])
        if kind == L.GK_WEAR:
            s = lining_wear(p, pw, g, shoe, t, y, s)
        if kind == L.GK_SHARE:
            share_l = 0.5 + s if shoe == 0 else 0.5 - s
            share_r = 0.5 - s if shoe == 0 else 0.5 + s
            regain = True
            continue
        if kind == L.GK_GAIN:
            if shoe == 0:
                pressure_l = 1.0 + s / 100.0
            else:
                pressure_r = 1.0 + s / 100.0
            regain = True
            continue
        if s == pw[g + L.G_NOW]:
            continue
        pw[g + L.G_NOW] = s
        moved = True
        if kind == L.GK_PIVOT:
            base = L.P_SHOE_BASE + shoe * L.SHOE_STRIDE
            pl = shoe_placement(
                s / 100.0,
                p[base + L.S_SIGN],
                p[nb + L.N_POSE],
                p[nb + L.N_PIVOT_X],
                p[nb + L.N_PIVOT_Y],
                p[nb + L.N_TIP_X],
                p[nb + L.N_TIP_Y],
                p[nb + L.N_MASS_CENTRE_X],
                p[nb + L.N_MASS_CENTRE_Y],
                p[nb + L.N_INERTIA],
                p[nb + L.N_MASS],
                p[nb + L.N_LINING_MID],
            )
            write_placement(
                pw, base, pl[0], pl[1], pl[2], pl[3], pl[4], pl[5], pl[6], pl[7], pl[8], pl[9]
            )
        elif kind == L.GK_FRICTION:
            base = L.P_SHOE_BASE + shoe * L.SHOE_STRIDE
            pw[base + L.S_FRICTION_COEFFICIENT] = lining_friction(p[L.P_FRICTION_COEFFICIENT], s)
            pw[L.P_COOL_FRICTION + shoe] = pw[base + L.S_FRICTION_COEFFICIENT]  # model/thermal.py
        elif kind == L.GK_PULSATION:
            pw[L.P_SHOE_BASE + shoe * L.SHOE_STRIDE + L.S_PULSATION_AMPLITUDE] = s / 100.0
        elif kind == L.GK_DRUM:
            fraction = s / final
            for w in range(int(p[L.P_DRUM_WAVE_COUNT])):
                a = L.P_DRUM_WAVE_BASE + w * L.DRUM_WAVE_STRIDE + L.W_AMPLITUDE
                pw[a] = p[a] * fraction
        elif kind == L.GK_FLAT:
            pw[L.P_FLAT_DEPTH] = s * 1e-6
        elif kind == L.GK_WEAR:
            lb = L.P_LINING_BASE + shoe * L.LINING_STRIDE
            pw[lb + L.LN_WEAR] = s
            pw[L.P_SHOE_BASE + shoe * L.SHOE_STRIDE + L.S_LINING_RADIUS] = p[lb + L.LN_RADIUS] - s
    if regain:
        gain_l = 2.0 * share_l * pressure_l
        gain_r = 2.0 * share_r * pressure_r
    return gain_l, gain_r, moved
