"""The energy a growing defect's step of the geometry moves, booked, compiled (numba).

A defect that grows with a law of time (a pivot moving, a drum going out of round or
gaining a flat, a lining wearing at a set rate) is written into the step's parameters at
each physics step's start (:func:`.growth.apply`), with the state held: the contact's
indentation, the springs' stretch at the shoe's angle and the shoe's inertia about its
moved pivot change with no motion, and so does the energy they store. What that step
releases goes with the defect that took it (the worn layer's strain, the strain of a
contact whose surface moved away); what it stores came from it. The kernel books the
difference, the energy :func:`stored` at the state before the step less after it, in
``contact_loss_j``, as :func:`.contact.wear_loss` books the strain a lining that wears
with its friction work loses continuously (that wear's geometry is written first and is
not booked here again). The energy books (:mod:`brake_sim_ros.analysis.energy`) read the
stored energy at a sample with the parameters in force then (:func:`.growth.apply` at its
time), so they close whatever grows.

A shoe's self-adjuster (:mod:`.ratchet`) moves its lining only while the lining is clear
of the drum: that moves no energy, and its radius is written (:func:`.ratchet.hold`)
before the energy is taken on either side of the step. The energy is taken only where a
severity changes at the step (:func:`_moves`) and only of the shoes the defect moves (a
pivot or a wear its own, a drum both): a defect growing through a whole stop steps about
a fifth slower, before its onset and at its final severity by a check of its severity.
"""

from __future__ import annotations

from numba import njit

from brake_sim_ros.model import contact, growth, lining, ratchet, service
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.compiled import JIT
from brake_sim_ros.model.growth_law import LAW_FRICTION_WORK, severity_at


@njit(inline="always", **JIT)
def _shoes_moved(p, g):
    """The shoes whose energy the growth entry at ``g`` of ``p`` moves at its steps, a
    mask (1 left, 2 right, 3 both), if :func:`grow` books them: a kind that moves the
    geometry or a shoe's inertia growing with a law of time (a pivot or a lining wear:
    its own shoe; a drum out of round or a flat: both); else 0."""
    if int(p[g + L.G_LAW]) == LAW_FRICTION_WORK:
        return 0
    kind = int(p[g + L.G_KIND])
    if kind == L.GK_DRUM or kind == L.GK_FLAT:
        return 3
    if kind == L.GK_PIVOT or kind == L.GK_WEAR:
        return 1 << int(p[g + L.G_SHOE])
    return 0


@njit(**JIT)
def booked(p):
    """The shoes whose energy the growth entries of ``p`` that :func:`grow` books move
    (a mask, :func:`_shoes_moved`; 0: none), and whether a lining wears with its friction
    work (its geometry written apart)."""
    shoes = 0
    worked = False
    for j in range(int(p[L.P_GROWTH_COUNT])):
        g = L.P_GROWTH_BASE + j * L.GROWTH_STRIDE
        shoes |= _shoes_moved(p, g)
        worked = worked or int(p[g + L.G_LAW]) == LAW_FRICTION_WORK
    return shoes, worked


@njit(**JIT)
def _moves(p, pw, t, y):
    """Whether a booked entry's severity at ``t`` (s) differs from the one ``pw`` holds:
    :func:`.growth.apply` would move the geometry now (its severity, as it computes it)."""
    for j in range(int(p[L.P_GROWTH_COUNT])):
        g = L.P_GROWTH_BASE + j * L.GROWTH_STRIDE
        if _shoes_moved(p, g) == 0:
            continue
        law = int(p[g + L.G_LAW])
        s = severity_at(
            t, law, p[g + L.G_ONSET], p[g + L.G_RATE], p[g + L.G_START], p[g + L.G_FINAL]
        )
        if int(p[g + L.G_KIND]) == L.GK_WEAR:  # a law of time: the severity in m, nothing written
            s = growth.lining_wear(p, pw, g, int(p[g + L.G_SHOE]), t, y, s)
        if s != pw[g + L.G_NOW]:
            return True
    return False


@njit(**JIT)
def stored(p, y, shoes):
    """Energy the state ``y`` stores in what the parameters ``p`` place for the shoes of
    the mask ``shoes`` (1 left, 2 right, 3 both), J: their kinetic energy about their
    pivots (``p``'s inertias), their contacts' elastic energy (``k max(eps, 0)^2 / 2``; a
    lining over its arc: its nodes', :func:`.lining.shoe_energy`) and, on the service
    brake, their return springs' and rest stops' (:func:`.service.shoe_energy`). The
    rotors and the line store what no geometry moves."""
    lined = p[L.P_LINING_NODE_STIFFNESS] > 0.0
    k = p[L.P_CONTACT_STIFFNESS]
    wa = y[L.Y_DRUM_ANGLE]
    eps_l = eps_r = 0.0
    if not lined:
        kin_l, kin_r = contact.kinematics_pair(p, y, 0.0)
        eps_l, eps_r = kin_l[0], kin_r[0]
    energy = 0.0
    for shoe in range(2):
        if not shoes & (1 << shoe):
            continue
        base = L.P_SHOE_BASE + shoe * L.SHOE_STRIDE
        theta = y[L.Y_LEFT_ANGLE + shoe]
        omega = y[L.Y_LEFT_SPEED + shoe]
        energy += 0.5 * p[base + L.S_INERTIA] * omega * omega
        eps = eps_l if shoe == 0 else eps_r
        if lined:
            energy += lining.shoe_energy(p, base, theta, wa)
        elif p[base + L.S_ENABLED] > 0.0 and eps > 0.0:
            energy += 0.5 * k * eps * eps
        if p[L.P_SERVICE] > 0.0:
            energy += service.shoe_energy(p, shoe, theta)
    return energy


@njit(**JIT)
def grow(p, pw, t, y, fstate, adjusting, shoes, worked):
    """The growing defects' parameters at the step that starts at ``t`` (s) in ``pw``
    (:func:`.growth.apply`), the self-adjuster's take-up after them if ``adjusting``
    (:func:`.ratchet.take_up`). With ``shoes`` (:func:`booked`'s mask; 0: nothing
    booked), the energy the laws of time's step moved (:func:`stored` before less after,
    where :func:`_moves` says it moves) is added to ``y``'s contact loss, and ``worked``
    says whether a lining wears with its friction work; ``pw`` must then hold the
    previous step's parameters.

    Returns the shoes' actuation gains (left, right) and whether any geometry moved.
    """
    if shoes == 0:
        gl, gr, moved = growth.apply(p, pw, t, y, growth.ALL_ENTRIES)
        if adjusting and ratchet.take_up(p, pw, fstate, y):
            moved = True
        return gl, gr, moved
    worn = False
    if worked:  # the wear that follows the wear state is booked continuously (wear_loss)
        worn = growth.apply(p, pw, t, y, growth.WORK_ENTRIES)[2]
        if adjusting:
            ratchet.hold(p, pw, fstate)
    if _moves(p, pw, t, y):
        before = stored(pw, y, shoes)
        gl, gr, moved = growth.apply(p, pw, t, y, growth.TIMED_ENTRIES)
        if adjusting:
            ratchet.hold(p, pw, fstate)
        y[L.Y_CONTACT_LOSS] += before - stored(pw, y, shoes)
    else:
        gl, gr, moved = growth.apply(p, pw, t, y, growth.TIMED_ENTRIES)
    if adjusting and ratchet.take_up(p, pw, fstate, y):
        moved = True
    return gl, gr, moved or worn


@njit(**JIT)
def previous_step(p, pw, t, y, fstate, adjusting):
    """Write into ``pw`` (a fresh :func:`.growth.working_copy`) the parameters of the step
    that started at ``t`` (s), the one before a block's first, as that step had them:
    :func:`grow` then books the block's first step from them."""
    growth.apply(p, pw, t, y, growth.ALL_ENTRIES)
    if adjusting:
        ratchet.hold(p, pw, fstate)
