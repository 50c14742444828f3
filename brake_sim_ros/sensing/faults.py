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

This module holds what a fault is; the per-sample loops that apply faults and labels are
compiled with the signal paths in :mod:`.paths`.
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


def of_kind(faults: tuple[SensorFault, ...], kind: str) -> tuple[SensorFault, ...]:
    return tuple(f for f in faults if f.kind == kind)
