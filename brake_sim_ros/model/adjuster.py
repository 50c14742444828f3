"""The service brake's self-adjuster: how much of a lining's wear it has taken up when a
run starts, its ratchet's step within the run, and the seized adjuster's refusal on the
study brake.

The mechanism (:attr:`.service_parameters.ServiceBrakeParameters.adjuster_step_m`): a
ratchet strut between the shoes at the wheel cylinder. Its slot gives the shoe the free
play of the running clearance; an application that carries the shoe further (the lining
has worn) turns the quadrant by a tooth, which lengthens the strut by one step. Repeated
applications thus take the wear up in whole steps, until the shoe's travel to the drum is
back within the free play: the running clearance at rest is the adjusted one (the new
lining's, ``SERVICE_RUNNING_CLEARANCE_M``) plus less than one step.

In the model: a wear ``w`` present when the run starts (the ``lining_wear`` defect at
t = 0) has been taken up by applications before it, in ``n = floor(w / s)`` whole steps
of the clearance ``s`` a tooth takes up at the lining. The takeup ``n s`` is put back on
the lining's radius at rest (the gap it closes), not on the shoe's rest angle: the
clearance the piston closes is the same; the lining arc stays concentric with the drum at
rest, where the real strut turns the shoe about its pin (1 mm at the lining, 1.92 mm at
the tip 284 mm from the pin, tilts it by 0.39 deg). Within a run the ratchet steps on as
the wear grows (:mod:`.ratchet`): an application that carries the shoe a step past the
free play picks up a tooth, taken up on the lining's radius in the same way once the shoe
is back at rest; this module packs its step and free play where a lining's wear grows.

A seized adjuster (``adjuster_seized``, a shoe's defect, service brake only) has failed to
take up ``y`` mm of that wear: it takes up ``max(w - y, 0)`` in whole steps, and where
``y`` exceeds the stated wear the surplus is wear the lining has beyond it (the kind
alone: ``y`` mm of wear the adjuster did not follow). Either way the clearance at rest
grows by ``y`` over the adjusted one: the pistons travel further and the circuit takes
more fluid before the lining touches (the low pedal mechanics find it by). A seized
adjuster does not step within the run either: a wear that grows opens the clearance by
all of it.

Pure logic: no files.
"""

from __future__ import annotations

import math

import numpy as np

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.growth_law import Growth
from brake_sim_ros.model.parameters import BrakeParameters

ADJUSTER_KIND = "adjuster_seized"
# a step count a hair under a whole number is that number (wear stated in mm, steps in m)
_STEP_ROUNDING = 1e-9


def takeup_m(wear_m: float, seized_m: float, step_m: float) -> float:
    """The running clearance the adjuster has taken up at the lining, m: the wear
    ``wear_m`` (m) less what a seized adjuster failed to take up (``seized_m``, m), in
    whole steps of ``step_m`` (m); 0 for none."""
    taken = wear_m - seized_m
    if taken <= 0.0:
        return 0.0
    return step_m * math.floor(taken / step_m + _STEP_ROUNDING)


def starting_wear_mm(final_mm: float, growth: Growth) -> float:
    """A lining's wear when the run starts, mm: the stated wear ``final_mm`` (a step at
    0 s), or where it grows during the run (``growth``), its law's at t = 0 (0 for a wear
    that follows the friction work, a state from 0)."""
    if not growth.follows_time:
        return 0.0
    return growth.severity(0.0, final_mm)


def pack_adjuster(
    params: BrakeParameters, shoe: object, side: str, wear_growth: Growth, p: np.ndarray
) -> None:
    """Put the adjuster's takeup of shoe ``side`` (``shoe``: its
    :class:`.defects.ShoeDefect`; ``wear_growth``: its lining wear's law) back on its
    lining's radius in ``p`` (layout ``S_LINING_RADIUS`` and the unworn ``LN_RADIUS`` a
    growing wear is taken from), on the service brake; the study brake has none. Where the
    wear grows during the run and the adjuster is not seized, its ratchet steps within the
    run too (:mod:`.ratchet`): its step and free play go to layout ``P_ADJUSTER_*``."""
    spec = params.service
    if spec is None:
        return
    wear = starting_wear_mm(shoe.lining_wear_mm, wear_growth) * 1e-3
    seized = shoe.adjuster_seized_mm * 1e-3
    i = L.SIDES.index(side)
    if wear_growth != Growth() and seized == 0.0:  # the ratchet steps within the run
        p[L.P_ADJUSTER_STEP + i] = spec.adjuster_step_m
        p[L.P_ADJUSTER_FREE_PLAY] = params.shoe.running_clearance_m
    if wear == 0.0 and seized == 0.0:
        return  # the new lining: nothing to take up (the healthy brake's arithmetic)
    takeup = takeup_m(wear, seized, spec.adjuster_step_m)
    beyond = seized - wear if seized > wear else 0.0
    p[L.P_SHOE_BASE + i * L.SHOE_STRIDE + L.S_LINING_RADIUS] += takeup - beyond
    p[L.P_LINING_BASE + i * L.LINING_STRIDE + L.LN_RADIUS] += takeup - beyond


def refuse_on_study(side: str, seized_mm: float) -> None:
    """Refuse, in one line, a seized adjuster on the study brake (it has no adjuster)."""
    if seized_mm:
        raise ParameterError(
            f"defect {side} adjuster_seized_mm={seized_mm:g} is invalid on the study brake (no"
            ' self-adjuster, a fixed running clearance): allowed only with brake = "service"'
        )
