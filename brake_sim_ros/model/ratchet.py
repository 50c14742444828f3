"""The service brake's self-adjuster stepping within a run, compiled (numba): the ratchet
strut picks up a tooth when an application carries the shoe past its free play by a step,
and the shoe, back at rest, rests one step further out.

The mechanism (:mod:`.adjuster`, which takes up the wear a run starts with): the strut's
slot lets the shoe travel its free play ``c0`` (the new lining's running clearance) at
the lining; a shoe that travels further pulls the quadrant past the next tooth, and the
quadrant stays there when the shoe returns, so the strut is one step ``s`` longer and the
shoe comes to rest one step further out.

In the model the shoe's travel at the lining is how much further from the drum centre its
lining point farthest out reaches, ``x = |X(phi)| - |X(0)|`` (the gap it closes where the
lining meets the drum), less the lining's indentation into the round drum while it
touches (``d``, that point's reach past the drum's radius): the slot is
sized, as a real one is, so that the lining's compression under a hard application does
not step it. An application picks up ``n = floor((x - d - c0) / s)`` teeth in all (never
fewer than it had): whole steps, only once the wear has opened the clearance at rest by
a step or more (``x - d`` is that clearance while the lining touches). The teeth picked
up are taken up, as the adjuster at the start of a run takes its wear up, on the lining's
radius (the arc stays concentric with the drum at rest, :mod:`.adjuster`), once the shoe
is back at rest (``x`` within a tenth of a step: where the lengthened strut holds it)
with its lining clear of the drum (less the drum's runout) by more than the take-up. So
the lining never moves into the drum: the contact neither stores nor releases energy by
it, and the springs and stops, which act on the shoe's angle, do not see it. Between
applications the shoe does not travel: nothing is picked up. A shoe that never returns to
rest (a drag held throughout) keeps its teeth pending until it does.

The state, whole teeth per shoe (taken up; picked up and pending), lives in the stepper's
float bookkeeping (layout ``F_ADJUSTER_*``), carried between blocks; :func:`take_up` runs
at the start of every physics step, after :func:`.growth.apply` (which writes the worn
lining's radius), in the one kernel every fixed-step scheme runs (the only one that
grows defects): a run steps the same bits whatever its blocks. The take-up shows in the
recorded indentation (:mod:`brake_sim_ros.analysis.adjuster` reads it back).
"""

from __future__ import annotations

import math

from numba import njit

from brake_sim_ros.model import contact
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.compiled import JIT

# a tooth count a hair under a whole number is that number (the adjuster.takeup_m rule)
_STEP_ROUNDING = 1e-9
# a shoe whose lining has travelled less than this fraction of a step from its rest is
# back at rest: the take-up then moves the lining where the strut holds it, to within it
_AT_REST = 0.1


@njit(**JIT)
def lining_travel(p, base, c, sn):
    """Outward travel at the lining of the shoe at ``base`` turned by phi (cos ``c``, sin
    ``sn``; phi = sign x its angle) from its assembled place, m, and the reach of its
    lining point farthest from the drum centre then, m: the travel is how much that reach
    has grown, ``|X(phi)| - |X(0)|`` (:func:`.contact.contact_point`), the gap it closes
    where the lining meets the drum."""
    reach = contact.contact_point(p, base, c, sn)[2]
    return reach - contact.contact_point(p, base, 1.0, 0.0)[2], reach


@njit(**JIT)
def ratcheting(p):
    """Whether either shoe's adjuster steps within the run (layout ``P_ADJUSTER_STEP``)."""
    return p[L.P_ADJUSTER_STEP] > 0.0 or p[L.P_ADJUSTER_STEP + 1] > 0.0


@njit(**JIT)
def _runout(p):
    """The drum's largest outward departure from its round radius, m: its harmonics'
    amplitudes summed (a flat only takes the surface in)."""
    out = 0.0
    for w in range(int(p[L.P_DRUM_WAVE_COUNT])):
        out += abs(p[L.P_DRUM_WAVE_BASE + w * L.DRUM_WAVE_STRIDE + L.W_AMPLITUDE])
    return out


@njit(**JIT)
def hold(p, pw, fstate):
    """Write each shoe's lining radius with the teeth its adjuster has taken up so far into
    ``pw`` (``p``'s unworn radius less ``pw``'s wear, layout ``LN_*``, plus the teeth
    taken), where it took any: :func:`.growth.apply` writes the worn radius alone."""
    for shoe in range(2):
        taken = fstate[L.F_ADJUSTER_TAKEN + shoe]
        if taken > 0.0:
            base = L.P_SHOE_BASE + shoe * L.SHOE_STRIDE
            lb = L.P_LINING_BASE + shoe * L.LINING_STRIDE
            step = p[L.P_ADJUSTER_STEP + shoe]
            pw[base + L.S_LINING_RADIUS] = p[lb + L.LN_RADIUS] - pw[lb + L.LN_WEAR] + taken * step


@njit(**JIT)
def take_up(p, pw, fstate, y):
    """Step each shoe's adjuster at the state ``y`` (the start of a physics step): pick up
    the teeth the shoe's travel passed, take the pending ones up on the lining's radius in
    ``pw`` once the shoe is back at the strut and clear of the drum, and write the radius
    with the take-up so far (``p``'s unworn radius less ``pw``'s wear, layout ``LN_*``,
    plus the teeth taken). ``p``: the packed parameters; ``pw``: the step's working copy
    (:func:`.growth.apply` has written it); ``fstate``: layout ``F_ADJUSTER_*``.

    Returns whether a take-up moved a lining now (the contact's switching functions must
    be re-evaluated).
    """
    hold(p, pw, fstate)  # the radius the growth wrote, less the wear taken up so far
    moved = False
    free_play = p[L.P_ADJUSTER_FREE_PLAY]
    for shoe in range(2):
        step = p[L.P_ADJUSTER_STEP + shoe]
        if step <= 0.0:
            continue
        base = L.P_SHOE_BASE + shoe * L.SHOE_STRIDE
        lb = L.P_LINING_BASE + shoe * L.LINING_STRIDE
        taken = fstate[L.F_ADJUSTER_TAKEN + shoe]
        phi = pw[base + L.S_SIGN] * y[L.Y_LEFT_ANGLE + shoe]
        c, sn = math.cos(phi), math.sin(phi)
        travel, reach = lining_travel(pw, base, c, sn)
        # the travel to the round drum's surface: the lining's indentation not counted
        pressed = reach - p[L.P_DRUM_RADIUS]
        pending = fstate[L.F_ADJUSTER_PENDING + shoe]
        teeth = math.floor((travel - max(pressed, 0.0) - free_play) / step + _STEP_ROUNDING)
        if teeth > pending:
            pending = teeth
            fstate[L.F_ADJUSTER_PENDING + shoe] = pending
        # back at rest (where the lengthened strut now holds it), clear of the drum (less
        # what it may stand out) by more than the take-up
        at_rest = pending > 0.0 and travel <= _AT_REST * step
        if at_rest and -pressed - _runout(p) > pending * step:
            taken += pending
            fstate[L.F_ADJUSTER_TAKEN + shoe] = taken
            fstate[L.F_ADJUSTER_PENDING + shoe] = 0.0
            pw[base + L.S_LINING_RADIUS] = p[lb + L.LN_RADIUS] - pw[lb + L.LN_WEAR] + taken * step
            moved = True
    return moved
