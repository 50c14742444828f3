"""The time series, sent as columns (``send_columns``) once ``batch_s`` of simulated time
is buffered:

* pivot forces of both shoes, |F|, fx, fy (N, frame ``brake_backing_plate``): every
  sample; with ``force_envelope_hz`` (live viewers) only the smallest and largest sample
  of each ``1 / force_envelope_hz`` bucket, at their own times, so every peak stays
  visible;
* BrakeState at the state rate: speeds (rad/s), shoe angles (deg), indentations (um),
  contact and actuation forces (N), contact flags (0/1) and regime (0..3).

Memory: at most ``batch_s`` of samples are held (plus a bucket's remainder).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import rerun as rr

from brake_sim_ros.viz import entities as E
from brake_sim_ros.viz.pivot_samples import PivotChunk
from brake_sim_ros.viz.timeline import NS_PER_S, send_scalar_columns


def envelope_positions(values: np.ndarray, bucket: int) -> np.ndarray:
    """Positions of the smallest and largest value of each run of ``bucket`` samples, in
    increasing order (one position when they coincide). A last partial bucket counts."""
    n = values.size
    if bucket <= 1 or n == 0:
        return np.arange(n)
    starts = np.arange(0, n, bucket)
    lo = np.minimum.reduceat(values, starts)
    hi = np.maximum.reduceat(values, starts)
    ends = np.append(starts[1:], n)
    picks = []
    for s, e, vmin, vmax in zip(starts, ends, lo, hi, strict=True):
        seg = values[s:e]
        picks.append(s + int(np.argmax(seg == vmin)))
        picks.append(s + int(np.argmax(seg == vmax)))
    return np.unique(np.asarray(picks, dtype=np.int64))


def state_scalars(msg: Any) -> dict[str, float]:
    """The scalars of one BrakeState per entity path (units as in :mod:`.entities`)."""
    values = {
        f"{E.SPEED}/flywheel": float(msg.flywheel_speed_rad_s),
        f"{E.SPEED}/drum": float(msg.drum_speed_rad_s),
        f"{E.CONTACT}/regime": float(int(msg.regime)),
    }
    for side in E.SIDES:
        values[f"{E.SHOE_ANGLE}/{side}"] = math.degrees(
            float(getattr(msg, f"{side}_shoe_angle_rad"))
        )
        values[f"{E.INDENTATION}/{side}"] = float(1e6 * getattr(msg, f"{side}_indentation_m"))
        values[f"{E.CONTACT_FORCE}/{side}/normal"] = float(getattr(msg, f"{side}_normal_force_n"))
        values[f"{E.CONTACT_FORCE}/{side}/friction"] = float(
            getattr(msg, f"{side}_friction_force_n")
        )
        values[f"{E.ACTUATION}/{side}"] = float(getattr(msg, f"{side}_actuation_force_n"))
        values[f"{E.CONTACT}/{side}"] = float(bool(getattr(msg, f"{side}_in_contact")))
    return values


class _Buffer:
    """Buffered scalar rows of one entity: times (ns) and values."""

    def __init__(self) -> None:
        self.ns: list[np.ndarray] = []
        self.values: list[np.ndarray] = []

    def add(self, ns: np.ndarray, values: np.ndarray) -> None:
        self.ns.append(ns)
        self.values.append(values)

    def take(self) -> tuple[np.ndarray, np.ndarray]:
        ns = np.concatenate(self.ns) if self.ns else np.zeros(0, np.int64)
        values = np.concatenate(self.values) if self.values else np.zeros(0)
        self.ns, self.values = [], []
        return ns, values


class TimeSeries:
    """Pivot forces and BrakeState scalars, buffered and sent as columns.

    Args:
        rec: where to send.
        batch_s: simulated seconds of samples per ``send_columns`` call.
        force_envelope_hz: None = every pivot-force sample; else the min/max envelope of
            each ``1 / force_envelope_hz`` s of simulated time.

    Attributes:
        rate_hz: sample rate of the last pivot-force chunk (Hz), None before the first.
        next_index: the sample index the next chunk should start at, None before the first.
    """

    def __init__(
        self, rec: rr.RecordingStream, *, batch_s: float, force_envelope_hz: float | None
    ) -> None:
        self._rec = rec
        self._batch_s = batch_s
        self._envelope_hz = force_envelope_hz
        self._states: dict[str, _Buffer] = {}
        self._batch_start_ns: int | None = None
        self.rate_hz: float | None = None
        self.next_index: int | None = None
        self._pivot: dict[str, list[np.ndarray]] = {}  # raw pivot samples not yet sent
        self._pivot_index: list[np.ndarray] = []

    def add_pivot(self, chunk: PivotChunk) -> None:
        """Buffer a chunk's samples; a change of sample rate first sends all held."""
        if self.rate_hz is not None and chunk.rate_hz != self.rate_hz:
            self.flush(final=True)
        self.rate_hz = chunk.rate_hz
        self.next_index = chunk.first_index + chunk.size
        if chunk.size == 0:
            return
        self._pivot_index.append(chunk.first_index + np.arange(chunk.size, dtype=np.int64))
        for (side, series), values in chunk.columns.items():
            self._pivot.setdefault(f"{side}/{series}", []).append(values)

    def add_state(self, msg: Any, ns: int) -> None:
        """Buffer the scalars of a BrakeState stamped ``ns``."""
        t = np.array([ns], dtype=np.int64)
        for path, value in state_scalars(msg).items():
            self._states.setdefault(path, _Buffer()).add(t, np.array([value]))

    def due(self, ns: int) -> None:
        """Send what is held once ``batch_s`` of simulated time is buffered (``ns``: the
        latest time received)."""
        if self._batch_start_ns is None:
            self._batch_start_ns = ns
        elif ns - self._batch_start_ns >= self._batch_s * NS_PER_S:
            self.flush(final=False)
            self._batch_start_ns = ns

    def flush(self, *, final: bool) -> None:
        """Send what is held; unless ``final``, the pivot samples of an unfinished
        envelope bucket stay until the bucket is complete."""
        self._flush_pivot(final=final)
        for path, buffer in self._states.items():
            ns, values = buffer.take()
            if ns.size:
                send_scalar_columns(self._rec, path, ns, values)

    def _flush_pivot(self, *, final: bool) -> None:
        if not self._pivot_index or self.rate_hz is None:
            return
        rate = self.rate_hz
        index = np.concatenate(self._pivot_index)
        cols = {k: np.concatenate(v) for k, v in self._pivot.items()}
        env = self._envelope_hz
        bucket = 1 if env is None else max(1, round(rate / env))
        usable = index.size if final or bucket == 1 else (index.size // bucket) * bucket
        self._pivot_index = [index[usable:]] if usable < index.size else []
        self._pivot = {k: [v[usable:]] for k, v in cols.items()} if usable < index.size else {}
        if usable == 0:
            return
        ns_all = np.rint(index[:usable] * (NS_PER_S / rate)).astype(np.int64)
        for key, values in cols.items():
            side, series = key.split("/")
            keep = envelope_positions(values[:usable], bucket)
            send_scalar_columns(
                self._rec, E.pivot_path(side, series), ns_all[keep], values[:usable][keep]
            )
