"""When the ground truth (``DefectState``) is published: the rule for defects that change
during a run, written once for the node and the offline stream.

A ``DefectState`` is published at the start and at each reset or change of the defects
(the caller's, :meth:`TruthUpdates.published`), and then, on the sample grid, at the first
sample where

* a defect appears (its onset: the first sample with a non-zero severity) or is gone;
* a severity reaches its final value;
* a severity has moved by more than :data:`PUBLISH_FRACTION` of its kind's service limit
  (``catalogue.DefectKind.service_limit``) since the last publication;
* at least :data:`PUBLISH_PERIOD_S` of simulated time has passed since the last
  publication and a severity has changed since then.

Each message carries the severities at its own sample's time (``Defects.active``), so a
subscriber holds the truth to within that fraction of the service limit, and knows it at
least once a second while anything changes. Defects present from the start publish nothing
beyond the start and resets. A lining wearing with its friction work is read from the
samples' recorded wear (:func:`recorded_wear`), not from time. Pure logic on arrays: no
transport.
"""

from __future__ import annotations

import numpy as np

from brake_sim_ros.model.catalogue import KINDS
from brake_sim_ros.model.defects import Defects
from brake_sim_ros.model.layout import N_STATE_WEAR, SIDES, Y_LEFT_WEAR
from brake_sim_ros.model.run_setup import SampleBlock

PUBLISH_FRACTION = 0.05  # of the kind's service limit
PUBLISH_PERIOD_S = 1.0  # longest silence while a severity changes, simulated s


def wear_column(side: str) -> str:
    """The samples' column of a shoe's lining wear, m (``layout.COLUMNS``)."""
    return f"{side}_lining_wear_m"


def recorded_wear(samples: SampleBlock, row: int | None = None) -> dict:
    """The linings' wear the model recorded in ``samples`` (m, by shoe: each column, or
    its value at ``row``), for :meth:`Defects.label_series` and :meth:`Defects.active`;
    empty when the samples do not carry it."""
    names = [wear_column(side) for side in SIDES]
    if not samples.has(*names):
        return {}
    if row is None:
        return {side: samples[name] for side, name in zip(SIDES, names, strict=True)}
    return {side: float(samples[name][row]) for side, name in zip(SIDES, names, strict=True)}


def state_wear(y: np.ndarray) -> dict[str, float]:
    """The linings' wear in a stepper's state ``y`` (layout ``Y_*_WEAR``), m by shoe; 0
    for a state without them (no lining wears with its friction work)."""
    if y.shape[0] < N_STATE_WEAR:
        return dict.fromkeys(SIDES, 0.0)
    return {side: float(y[Y_LEFT_WEAR + i]) for i, side in enumerate(SIDES)}


class TruthUpdates:
    """The samples at which a new ``DefectState`` is due (module doc), block by block.

    Args:
        defects: the brake's defects (their growth laws).
    """

    def __init__(self, defects: Defects) -> None:
        self._thresholds = np.array(
            [PUBLISH_FRACTION * abs(k.service_limit) for k in KINDS for _ in k.locations]
        )
        self.published(defects, 0.0)

    def published(
        self, defects: Defects, time_s: float, wear_m: dict[str, float] | None = None
    ) -> None:
        """A ``DefectState`` of ``defects`` went out at ``time_s`` (start, reset, change);
        ``wear_m``: the linings' wear then, m (:meth:`Defects.active`; default: unworn, as
        at the start of a run)."""
        self._defects = defects
        self._final = np.array(list(defects.severities().values()))
        if wear_m is None:
            wear_m = dict.fromkeys(SIDES, 0.0)
        self._last = np.array(list(defects.severities(time_s, wear_m).values()))
        self._last_time = float(time_s)

    def due_rows(self, times_s: np.ndarray, wear_m: dict | None = None) -> list[int]:
        """Rows of ``times_s`` (s, ascending: a block's sample times) at which a
        ``DefectState`` is due, in order; each is recorded as published. ``wear_m``: the
        block's recorded wear (:func:`recorded_wear`), for a lining wearing with its
        friction work."""
        if self._defects.is_static or len(times_s) == 0:
            return []
        series = self._defects.label_series(times_s, wear_m)
        values = np.column_stack(list(series.values()))
        rows: list[int] = []
        start = 0
        while start < len(times_s):
            v = values[start:]
            moved = v != self._last
            due = (
                ((v != 0.0) != (self._last != 0.0))
                | ((v == self._final) & moved)
                | (np.abs(v - self._last) > self._thresholds)
            ).any(axis=1)
            # a nanosecond short of the period counts: sample times are rounded products
            late = times_s[start:] - self._last_time >= PUBLISH_PERIOD_S - 1e-9
            due |= late & moved.any(axis=1)
            hits = np.flatnonzero(due)
            if hits.size == 0:
                break
            row = start + int(hits[0])
            rows.append(row)
            self._last = values[row].copy()
            self._last_time = float(times_s[row])
            start = row + 1
        return rows
