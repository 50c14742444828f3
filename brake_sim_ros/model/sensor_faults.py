"""Sensor faults: injectable, labelled events on one channel, kept apart from brake defects.

A brake defect changes the physics (``model/defects.py``); a sensor fault changes only what
one channel reports. Each fault has a kind, an onset time (s, simulated time), a size in
the kind's unit and a duration (s; infinite by default: the fault stays). While a fault is
active the channel's per-sample label carries its bit (:data:`FAULT_BIT`), so ground truth
tells "sensor fault" from "brake defect" sample by sample.

Kinds, and what ``size`` means:

* ``bias_drift``: an offset growing at ``size`` channel units per second from the onset
  (added before the range and the ADC: a drifting sensor still clips at its range).
* ``gain_error``: the sensitivity is off by the fraction ``size`` (reported = (1 + size)
  x true; the sensor's own noise is unchanged). ``size > -1``.
* ``dropout``: no data: the channel reports NaN. ``size`` unused (0).
* ``stuck``: the channel repeats the value it reported at the last sample before the
  onset. ``size`` unused (0).
* ``saturation``: the signal path saturates at +-``size`` channel units (below the
  nominal range): an overloaded amplifier or a damaged element.
* ``loose_mount``: the mounted resonance falls to ``size`` times its nominal frequency
  (0 < size < 1), with the same damping ratio: it moves down into the measured band,
  where the response near it rises by the resonance's quality factor. Accelerometers
  with a mounted resonance only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from brake_sim_ros.errors import ParameterError

FAULT_KINDS: tuple[str, ...] = (
    "bias_drift",
    "gain_error",
    "dropout",
    "stuck",
    "saturation",
    "loose_mount",
)
FAULT_BIT: dict[str, int] = {kind: 1 << i for i, kind in enumerate(FAULT_KINDS)}
LABEL_DTYPE = np.uint8  # one bit per kind; 0: no sensor fault at that sample
# kinds whose size is unused (must be 0)
_NO_SIZE = ("dropout", "stuck")


@dataclass(frozen=True)
class SensorFault:
    """One fault on one channel (the channel that lists it).

    Attributes:
        kind: one of :data:`FAULT_KINDS`.
        onset_s: simulated time it starts, s.
        size: its size, in the unit its kind gives (module docstring).
        duration_s: how long it lasts, s (inf: to the end).
    """

    kind: str
    onset_s: float
    size: float = 0.0
    duration_s: float = math.inf

    def __post_init__(self) -> None:
        def bad(what: str, value: object, allowed: str) -> ParameterError:
            return ParameterError(
                f"sensor fault {self.kind!r}: {what} = {value!r} is invalid: allowed {allowed}"
            )

        if self.kind not in FAULT_KINDS:
            raise ParameterError(
                f"sensor fault kind {self.kind!r} is invalid: allowed one of {list(FAULT_KINDS)}"
            )
        if not (math.isfinite(self.onset_s) and self.onset_s >= 0.0):
            raise bad("onset_s", self.onset_s, "a finite time >= 0 s")
        if not (self.duration_s > 0.0) or math.isnan(self.duration_s):
            raise bad("duration_s", self.duration_s, "> 0 s (inf: to the end)")
        if not math.isfinite(self.size):
            raise bad("size", self.size, "a finite number")
        if self.kind in _NO_SIZE and self.size != 0.0:
            raise bad("size", self.size, "0 (unused for this kind)")
        if self.kind == "gain_error" and self.size <= -1.0:
            raise bad("size", self.size, "a fraction > -1")
        if self.kind == "saturation" and self.size <= 0.0:
            raise bad("size", self.size, "a limit > 0 in the channel's unit")
        if self.kind == "loose_mount" and not 0.0 < self.size < 1.0:
            raise bad("size", self.size, "a factor on the resonance frequency, > 0 and < 1")

    def active(self, time_s: np.ndarray) -> np.ndarray:
        """Whether the fault is active at each time of ``time_s`` (bool array)."""
        return (time_s >= self.onset_s) & (time_s < self.onset_s + self.duration_s)


def labels(faults: tuple[SensorFault, ...], time_s: np.ndarray) -> np.ndarray:
    """Per-sample fault label: OR of :data:`FAULT_BIT` of every active fault."""
    out = np.zeros(time_s.shape[0], dtype=LABEL_DTYPE)
    for fault in faults:
        out[fault.active(time_s)] |= LABEL_DTYPE(FAULT_BIT[fault.kind])
    return out


def of_kind(faults: tuple[SensorFault, ...], kind: str) -> tuple[SensorFault, ...]:
    return tuple(f for f in faults if f.kind == kind)


def gain_factor(faults: tuple[SensorFault, ...], time_s: np.ndarray) -> np.ndarray:
    """The factor on the true signal: product of ``1 + size`` of active gain errors."""
    out = np.ones(time_s.shape[0])
    for f in of_kind(faults, "gain_error"):
        out[f.active(time_s)] *= 1.0 + f.size
    return out


def bias(faults: tuple[SensorFault, ...], time_s: np.ndarray) -> np.ndarray:
    """The offset of active bias drifts, ``size (t - onset)``, channel units."""
    out = np.zeros(time_s.shape[0])
    for f in of_kind(faults, "bias_drift"):
        on = f.active(time_s)
        out[on] += f.size * (time_s[on] - f.onset_s)
    return out


def saturation_limit(faults: tuple[SensorFault, ...], time_s: np.ndarray) -> np.ndarray:
    """The saturation limit of active saturation faults, channel units (inf where none)."""
    out = np.full(time_s.shape[0], np.inf)
    for f in of_kind(faults, "saturation"):
        on = f.active(time_s)
        out[on] = np.minimum(out[on], f.size)
    return out


def loose(faults: tuple[SensorFault, ...], time_s: np.ndarray) -> tuple[np.ndarray, float]:
    """Where a loose mount is active (bool array) and its resonance factor (1.0: none).
    One loose-mount fault per channel (the loader refuses more)."""
    found = of_kind(faults, "loose_mount")
    if not found:
        return np.zeros(time_s.shape[0], dtype=bool), 1.0
    return found[0].active(time_s), found[0].size


class HoldState:
    """What :func:`apply_hold` carries between blocks: the last value reported, whether a
    stuck fault was active at the last sample, and the value it holds."""

    def __init__(self) -> None:
        self.last_value = 0.0
        self.was_stuck = False
        self.held = 0.0


def apply_hold(
    faults: tuple[SensorFault, ...], time_s: np.ndarray, values: np.ndarray, state: HoldState
) -> np.ndarray:
    """Stuck and dropout, applied to the reported ``values`` of one block (a copy)."""
    out = values.copy()
    if values.shape[0] == 0:
        return out
    stuck = np.zeros(time_s.shape[0], dtype=bool)
    for f in of_kind(faults, "stuck"):
        stuck |= f.active(time_s)
    if stuck.any() or state.was_stuck:
        n = time_s.shape[0]
        previous = np.concatenate(([state.last_value], values[:-1]))
        was = np.concatenate(([state.was_stuck], stuck[:-1]))
        starts = stuck & ~was
        # the value held by each stuck sample: the value before its run began
        run_start = np.maximum.accumulate(np.where(starts, np.arange(n), -1))
        held = np.where(run_start >= 0, previous[np.maximum(run_start, 0)], state.held)
        out[stuck] = held[stuck]
        if stuck[-1]:
            state.held = float(held[-1])
    state.last_value = float(values[-1])
    state.was_stuck = bool(stuck[-1])
    for f in of_kind(faults, "dropout"):
        out[f.active(time_s)] = np.nan
    return out
