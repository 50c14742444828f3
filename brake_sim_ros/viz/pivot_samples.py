"""Pivot-force samples as the sink receives them: one chunk read from its message, and
the window of recent samples the impact markers and the drawing's force arrows look up.

Forces are in N, frame ``brake_backing_plate``; samples are known by their sample index
(``first_sample_index`` of the chunk plus the position in it).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np

from brake_sim_ros.viz import entities as E
from brake_sim_ros.viz.settings import RerunSinkError
from brake_sim_ros.viz.timeline import NS_PER_S, stamp_ns


@dataclass(frozen=True)
class PivotChunk:
    """The pivot forces of one PivotForceChunk message.

    Attributes:
        first_index: sample index of the first sample.
        rate_hz: sample rate (Hz).
        start_ns: simulated time of the first sample (ns, the message's stamp).
        columns: per (side, series) of :data:`.entities.PIVOT_SERIES`, the samples (N),
            all of one length.
    """

    first_index: int
    rate_hz: float
    start_ns: int
    columns: dict[tuple[str, str], np.ndarray]

    @classmethod
    def from_msg(cls, msg: Any) -> PivotChunk:
        """Read a PivotForceChunk; raises RerunSinkError on a bad rate or unequal arrays."""
        rate = float(msg.sample_rate_hz)
        if not (math.isfinite(rate) and rate > 0):
            raise RerunSinkError(f"PivotForceChunk sample_rate_hz={rate!r}: allowed > 0")
        first = int(msg.first_sample_index)
        cols = {}
        for side in E.SIDES:
            for series, field in E.PIVOT_MESSAGE_FIELDS.items():
                cols[(side, series)] = np.asarray(getattr(msg, f"{side}_{field}"), dtype=float)
        lengths = {a.size for a in cols.values()}
        if len(lengths) != 1:
            raise RerunSinkError(
                f"PivotForceChunk at sample {first}: arrays of different lengths {sorted(lengths)}"
            )
        return cls(first_index=first, rate_hz=rate, start_ns=stamp_ns(msg), columns=cols)

    @property
    def size(self) -> int:
        """Number of samples."""
        return self.columns[(E.SIDES[0], E.PIVOT_SERIES[0])].size

    @property
    def end_ns(self) -> int:
        """Simulated time of the last sample (ns), from the stamp and the rate."""
        return self.start_ns + round((self.size - 1) * NS_PER_S / self.rate_hz)


class RecentPivotForces:
    """The pivot-force samples from the previous BrakeState's sample on (whole chunks, at
    least the last one), per side (fx, fy, |F|) in N, looked up by sample index."""

    def __init__(self) -> None:
        self._chunks: deque[tuple[int, dict[str, tuple[np.ndarray, ...]]]] = deque()

    def add(self, chunk: PivotChunk) -> None:
        """Hold the samples of ``chunk`` (chunks come in increasing sample order)."""
        cols = chunk.columns
        self._chunks.append(
            (
                chunk.first_index,
                {s: tuple(cols[(s, k)] for k in ("fx", "fy", "magnitude")) for s in E.SIDES},
            )
        )

    def clear(self) -> None:
        """Forget every sample (the simulation restarted)."""
        self._chunks.clear()

    def keep_after(self, index: int) -> None:
        """Drop the chunks whose samples all precede sample ``index`` (the last chunk
        stays)."""
        while len(self._chunks) > 1 and _chunk_end(self._chunks[0]) <= index:
            self._chunks.popleft()

    def at(self, index: int) -> dict[str, tuple[float, float]] | None:
        """Pivot force (fx, fy) per side at sample ``index``, if still held."""
        for first, sides in reversed(self._chunks):
            k = index - first
            if 0 <= k < sides["left"][0].size:
                return {s: (float(v[0][k]), float(v[1][k])) for s, v in sides.items()}
        return None

    def peak_since(self, side: str, after: int | None, upto: int) -> tuple[int, float] | None:
        """(index, value) of the largest |F_pivot| of ``side`` in samples (after, upto];
        ``after`` None: every held sample up to ``upto``."""
        best: tuple[int, float] | None = None
        for first, sides in self._chunks:
            mag = sides[side][2]
            idx = first + np.arange(mag.size)
            mask = idx <= upto if after is None else (idx > after) & (idx <= upto)
            if mask.any():
                k = int(np.argmax(np.where(mask, mag, -np.inf)))
                if best is None or mag[k] > best[1]:
                    best = (int(idx[k]), float(mag[k]))
        return best


def _chunk_end(entry: tuple[int, dict[str, tuple[np.ndarray, ...]]]) -> int:
    first, sides = entry
    return first + sides["left"][2].size
