"""An example detector of one's own: the peak of the backing plate's accelerations.

Use it as a template. It is named on the command line by its file and class, with no
change to ``PYTHONPATH``::

    brake-sim fit data/demo --detector examples/peak_detector.py:PeakAcceleration \
        --out models/peak.json
    brake-sim score data/demo --detector examples/peak_detector.py:PeakAcceleration \
        --model models/peak.json
    brake-sim monitor --detector examples/peak_detector.py:PeakAcceleration \
        --model models/peak.json

What a detector sees: the measured channels by name, ``backing_plate_accel_x``, not the
dataset's Parquet column ``measured:backing_plate_accel_x [m/s^2]`` (the prefix and the
unit are dropped; ``brake-sim scenarios --channels`` lists them). Values are float64 in
the channel's unit, NaN where a channel gave no value.

It learns one number, the alarm level of the peak, from the healthy training windows,
and saves it as data (``saved_state``/``load_state``): the saved file never names this
file, so loading it needs the class named again with ``--detector``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from brake_sim_ros.detection.detector import Assessment, Detector, TrainingWindow


class PeakAcceleration(Detector):
    """Alarm when the largest absolute acceleration of the backing plate (x or y) in a
    0.1 s window exceeds ``margin`` times the healthy windows' ``quantile``."""

    name = "peak_acceleration"
    channels = ("backing_plate_accel_x", "backing_plate_accel_y")
    window_s = 0.1
    quantile = 0.99
    margin = 1.5

    def __init__(self) -> None:
        super().__init__()
        self.threshold: float | None = None  # m/s^2
        self.healthy_peaks = np.zeros(0)  # m/s^2, one per healthy training window

    @staticmethod
    def _peak(window: Mapping[str, np.ndarray]) -> float:
        values = np.abs(np.concatenate([np.asarray(v) for v in window.values()]))
        return float(np.nanmax(values)) if np.any(np.isfinite(values)) else float("nan")

    def fit(self, windows: Iterable[TrainingWindow]) -> None:
        healthy = [w for w in windows if w.healthy]
        peaks = np.array([self._peak({c: w.channels[c] for c in self.channels}) for w in healthy])
        peaks = peaks[np.isfinite(peaks)]
        if peaks.size < 2:
            raise ValueError(f"detector {self.name}: {peaks.size} healthy windows; it needs 2")
        self.healthy_peaks = peaks
        self.threshold = self.margin * float(np.quantile(peaks, self.quantile))

    def assess(
        self, window: Mapping[str, np.ndarray], last_sample_index: int, sample_rate_hz: float
    ) -> Assessment:
        if self.threshold is None:
            raise RuntimeError(f"detector {self.name} is not fitted")
        index = self._peak(window) / self.threshold
        return Assessment(
            sample_index=last_sample_index,
            time_s=last_sample_index / sample_rate_hz,
            health_index=index,
            alarm=bool(index >= 1.0),
        )

    # the saved form: JSON values and numpy arrays, restored bit for bit
    def saved_state(self) -> dict[str, Any] | None:
        if self.threshold is None:
            return None
        return {"threshold": self.threshold, "healthy_peaks": self.healthy_peaks}

    def load_state(self, state: Mapping[str, Any]) -> None:
        threshold = state.get("threshold")
        if not (isinstance(threshold, float) and np.isfinite(threshold) and threshold > 0.0):
            raise ValueError("threshold: allowed a finite number > 0 (m/s^2)")
        peaks = state.get("healthy_peaks")
        if not (isinstance(peaks, np.ndarray) and peaks.ndim == 1):
            raise ValueError("healthy_peaks: allowed a 1-D array")
        self.threshold, self.healthy_peaks = threshold, peaks
