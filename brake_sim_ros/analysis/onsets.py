"""Contact onsets and separations from sampled indentations: the one definition.

Every consumer of recorded samples (the impact metrics of :mod:`.impacts`, the contact
events of :mod:`.contact_events` that the node publishes, the ``in_contact`` flags of the
BrakeState message, the Rerun sink's fallback for streams without contact events, and the
studies built on these) detects contact with the functions below, so they agree sample for
sample:

* a shoe is *in contact* at a sample when its indentation (``<side>_indentation_m``, m,
  positive = the lining penetrates the drum) is > 0 (:func:`in_contact`);
* an *onset* is a sample in contact whose predecessor is not, a *separation* a sample out
  of contact whose predecessor is in contact (:func:`contact_changes`); the predecessor of
  a block's first sample is given by the caller (the flag carried from the previous block,
  or unknown, in which case the first sample is no change);
* the *instant* of an onset or separation is the zero crossing of the indentation,
  interpolated linearly between the sample before it and its sample
  (:func:`crossing_times`).

The located events of the steppers (``rk4-located``, the reference solver) find the
crossing on the continuous state instead; these functions see only the samples.
Indentations must be finite (the steppers refuse a non-finite state). Pure numpy.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import overload

import numpy as np

CONTACT_THRESHOLD_M = 0.0  # indentation above which a shoe touches the drum, m


@overload
def in_contact(indentation_m: float) -> bool: ...
@overload
def in_contact(indentation_m: np.ndarray) -> np.ndarray: ...
def in_contact(indentation_m):
    """Whether the lining touches the drum: indentation (m) > 0; elementwise on arrays."""
    return indentation_m > CONTACT_THRESHOLD_M


@dataclass(frozen=True)
class ContactChanges:
    """Positions (0-based, within the flags given) where the contact flag changes.

    Attributes:
        onsets: positions of the first sample of each contact, increasing, int64.
        separations: positions of the first sample out of contact again, increasing, int64.
        positions: onsets and separations together, increasing (never both at one).
    """

    onsets: np.ndarray
    separations: np.ndarray
    positions: np.ndarray


def contact_changes(contact: np.ndarray, *, before: bool | None = None) -> ContactChanges:
    """Onsets and separations in a run of contact flags (:func:`in_contact`).

    Args:
        contact: bool flags of consecutive samples, shape (n,).
        before: the flag of the sample just before ``contact[0]`` (carried from the previous
            block); None when it is unknown: the first sample is then no change.
    """
    contact = np.asarray(contact, dtype=bool)
    if contact.size == 0:
        empty = np.zeros(0, dtype=np.int64)
        return ContactChanges(empty, empty, empty)
    previous = np.empty_like(contact)
    previous[0] = contact[0] if before is None else before
    previous[1:] = contact[:-1]
    changed = contact != previous
    return ContactChanges(
        onsets=np.flatnonzero(changed & contact),
        separations=np.flatnonzero(changed & previous),
        positions=np.flatnonzero(changed),
    )


def crossing_times(t: np.ndarray, indentation_m: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """Instants (units of ``t``) where the indentation crosses zero just before each of
    ``positions`` (onsets or separations, each >= 1), linearly interpolated."""
    before = np.asarray(positions) - 1
    x0, x1 = indentation_m[before], indentation_m[before + 1]
    frac = -x0 / (x1 - x0)
    return t[before] + frac * (t[before + 1] - t[before])
