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
beyond the start and resets. Pure logic on arrays: no transport.
"""

from __future__ import annotations

import numpy as np

from brake_sim_ros.model.catalogue import KINDS
from brake_sim_ros.model.defects import Defects

PUBLISH_FRACTION = 0.05  # of the kind's service limit
PUBLISH_PERIOD_S = 1.0  # longest silence while a severity changes, simulated s


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

    def published(self, defects: Defects, time_s: float) -> None:
        """A ``DefectState`` of ``defects`` went out at ``time_s`` (start, reset, change)."""
        self._defects = defects
        self._final = np.array(list(defects.severities().values()))
        self._last = np.array(list(defects.severities(time_s).values()))
        self._last_time = float(time_s)

    def due_rows(self, times_s: np.ndarray) -> list[int]:
        """Rows of ``times_s`` (s, ascending: a block's sample times) at which a
        ``DefectState`` is due, in order; each is recorded as published."""
        if self._defects.is_static or len(times_s) == 0:
            return []
        values = np.column_stack(list(self._defects.label_series(times_s).values()))
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
