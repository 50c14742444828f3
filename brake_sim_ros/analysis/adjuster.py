"""The service brake's self-adjuster read from a recorded run: the wear it has taken up
within the run at every sample, from the recorded columns alone.

The ratchet (:mod:`brake_sim_ros.model.ratchet`) takes its teeth up on the lining's
radius, so a sample's recorded indentation (``*_indentation_m``, the lining's reach past
the drum at the shoe's recorded angle) is the worn lining's (its recorded wear,
``*_lining_wear_m``) plus the take-up so far. The take-up is their difference, which
comes out in whole steps of the adjuster (to rounding, about 1e-15 m); the clearance at
rest is minus the recorded indentation of a shoe at rest.

Pure logic on sample arrays: no files.
"""

from __future__ import annotations

import numpy as np

from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import SIDES, indentation_at
from brake_sim_ros.model.run_setup import SampleBlock

# the columns a take-up is read from, for a shoe ``{side}``
ADJUSTER_COLUMNS: tuple[str, ...] = (
    "drum_angle_rad",
    *(f"{s}_{name}" for s in SIDES for name in ("angle_rad", "indentation_m", "lining_wear_m")),
)


def takeup_steps(block: SampleBlock, packed: np.ndarray, side: str) -> np.ndarray:
    """Whole steps the ``side`` shoe's self-adjuster has taken up within the run at every
    row of ``block`` (int64, shape (n,)), for the run's packed parameters ``packed`` (its
    stepper's ``packed_parameters``).

    Raises:
        ValueError: ``side`` is not a shoe, the shoe's adjuster does not step within the
            run (layout ``P_ADJUSTER_STEP``: the study brake, a seized adjuster, a wear
            that does not grow), or a row's take-up is not a whole number of steps (the
            block is not this run's).
        KeyError: ``block`` lacks one of :data:`ADJUSTER_COLUMNS`.
    """
    if side not in SIDES:
        raise ValueError(f"side {side!r}: allowed {', '.join(SIDES)}")
    i = SIDES.index(side)
    step = float(packed[L.P_ADJUSTER_STEP + i])
    if step <= 0.0:
        raise ValueError(
            f"the {side} shoe's self-adjuster does not step within this run (study brake,"
            " seized adjuster or a wear that does not grow): it has taken nothing up"
        )
    base = L.P_SHOE_BASE + i * L.SHOE_STRIDE
    lining = L.P_LINING_BASE + i * L.LINING_STRIDE
    worn = packed.copy()
    names = (
        f"{side}_angle_rad",
        f"{side}_indentation_m",
        f"{side}_lining_wear_m",
        "drum_angle_rad",
    )
    angle, reach, wear, drum = (np.asarray(block[name], dtype=float) for name in names)
    out = np.empty(len(block), dtype=np.int64)
    for r in range(len(block)):
        worn[base + L.S_LINING_RADIUS] = packed[lining + L.LN_RADIUS] - wear[r]
        taken = (reach[r] - indentation_at(worn, base, angle[r], drum[r])) / step
        out[r] = round(taken)
        if abs(taken - out[r]) > 1e-6:
            raise ValueError(
                f"row {r}: the {side} lining reaches {taken:.6f} steps past its recorded"
                " wear, not a whole number: the block is not this run's (pass its stepper's"
                " packed_parameters)"
            )
    return out
