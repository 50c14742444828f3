"""Baseline detectors a reader can follow (the registry that names every built-in
detector is :mod:`.registry`).

* :class:`VibrationThreshold` (``rms``, ``kurtosis``, ``crest``): one statistic of one
  measured channel per window (default 0.1 s of the backing plate's y acceleration);
  fitted on healthy training windows, it alarms when the statistic exceeds their mean by
  ``k`` standard deviations (default 4). Its health index is the statistic over that
  threshold, so 1 is the alarm. It detects, it does not isolate: no diagnosis.
* ``orders``: order analysis of the tone ring (:mod:`.order_analysis`), for a drum that
  is out of round.
* ``impact``: each stop judged by the shoes' first impacts after the brake is applied
  (:mod:`.impact`), which detects and isolates the defects of shoe geometry and actuation.
* ``learned``: a random forest on the shared window features (:mod:`.learned`), which
  detects and isolates.

All of them read their features through :mod:`.features`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np

from brake_sim_ros.detection.detector import Assessment, Detector, TrainingWindow
from brake_sim_ros.detection.features import STATISTICS, crest_factor, kurtosis, rms

DEFAULT_CHANNEL = "backing_plate_accel_y"


class VibrationThreshold(Detector):
    """Threshold on a vibration statistic of one channel (module docstring)."""

    def __init__(
        self,
        statistic: str = "rms",
        channel: str = DEFAULT_CHANNEL,
        *,
        window_s: float = 0.1,
        k: float = 4.0,
    ) -> None:
        super().__init__()
        if statistic not in STATISTICS:
            raise ValueError(f"statistic {statistic!r}: allowed one of {sorted(STATISTICS)}")
        if not (window_s > 0.0 and k > 0.0):
            raise ValueError(f"window_s={window_s!r}, k={k!r}: allowed > 0")
        self.statistic = statistic
        self.name = statistic
        self.channels = (channel,)
        self.window_s = float(window_s)
        self.k = float(k)
        self.threshold: float | None = None
        self.unjudged_windows = 0  # healthy training windows without a finite sample

    def fit(self, windows: Iterable[TrainingWindow]) -> None:
        """Threshold = mean + k std of the statistic over the healthy windows."""
        f = STATISTICS[self.statistic]
        values = [f(w.channels[self.channels[0]]) for w in windows if w.healthy]
        # windows without a finite sample (a dropout throughout) are left out, and counted
        self.unjudged_windows = sum(not np.isfinite(v) for v in values)
        values = [v for v in values if np.isfinite(v)]
        if len(values) < 2:
            raise ValueError(
                f"detector {self.name}: {len(values)} healthy training windows; it needs 2 or more"
            )
        self.threshold = float(np.mean(values) + self.k * np.std(values))

    def assess(
        self, window: Mapping[str, np.ndarray], last_sample_index: int, sample_rate_hz: float
    ) -> Assessment:
        if self.threshold is None:
            raise RuntimeError(f"detector {self.name} is not fitted: call fit() first")
        value = STATISTICS[self.statistic](window[self.channels[0]])
        index = value / self.threshold if self.threshold > 0.0 else np.inf
        return Assessment(
            sample_index=last_sample_index,
            time_s=last_sample_index / sample_rate_hz,
            health_index=float(index),
            alarm=bool(index >= 1.0),
        )


__all__ = ["STATISTICS", "VibrationThreshold", "crest_factor", "kurtosis", "rms"]
