"""The order-analysis baseline (``orders``): the drum's angle fluctuation at its orders,
from the tone ring, against a healthy reference.

A drum whose radius varies with its angle (out of round: ovality is order 2) makes the
braking torque vary with the angle, so the drum runs ahead of and behind a smooth stop at
those orders; the tone ring's edges, equally spaced in angle, show it as a ripple of their
times (:func:`~brake_sim_ros.monitoring.features.angle_fluctuation_orders`, rad at orders
1-20, over the last :attr:`OrderAnalysis.history_s` = 0.5 s, about 8 revolutions at the
start of the published stop; assessed every 0.1 s).

Fit (healthy training histories with at least two revolutions): per order ``k``, the mean
``m_k`` and standard deviation ``s_k`` of ``log10`` of the amplitude. Score of a history:
``max_k (log10 a_k - m_k) / s_k``, the order that stands out most from healthy in healthy
standard deviations; the alarm threshold is the healthy scores' mean plus ``k`` (default 4)
standard deviations, and the health index the score over that threshold (1: the alarm).
A history with fewer than two revolutions (a slow or stopped drum) scores 0 (no alarm).

Diagnosis on alarm: ``drum_out_of_round`` at ``drum`` (nothing else in the catalogue is
tied to the drum's angle), with the alarmed order's share of the score as confidence. The
shoe defects do not vary with the drum's angle: this detector is not meant to see them.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np

from brake_sim_ros.model.catalogue import DRUM_KIND
from brake_sim_ros.monitoring.detector import Assessment, Diagnosis, TrainingWindow
from brake_sim_ros.monitoring.features import PULSE_CHANNEL, angle_fluctuation_orders
from brake_sim_ros.monitoring.history import HistoryDetector

FLOOR_RAD = 1e-12  # below any quantisation noise: log10 of an exact 0 is kept finite


class OrderAnalysis(HistoryDetector):
    """Order analysis of the tone ring (module docstring)."""

    def __init__(self, *, history_s: float = 0.5, window_s: float = 0.1, k: float = 4.0) -> None:
        super().__init__()
        if not (window_s > 0.0 and history_s >= window_s and k > 0.0):
            raise ValueError(
                f"window_s={window_s!r}, history_s={history_s!r}, k={k!r}: allowed window_s"
                " > 0, history_s >= window_s, k > 0"
            )
        self.name = "orders"
        self.channels = (PULSE_CHANNEL,)
        self.window_s, self.history_s, self.k = float(window_s), float(history_s), float(k)
        self.mean: np.ndarray | None = None
        self.std: np.ndarray | None = None
        self.threshold: float | None = None
        self.healthy_index: np.ndarray = np.zeros(0)  # the healthy training histories'

    def _amplitudes(self, history: Mapping[str, np.ndarray], rate: float) -> np.ndarray | None:
        a = angle_fluctuation_orders(history[PULSE_CHANNEL], rate)
        return None if not a.any() else np.log10(np.maximum(a, FLOOR_RAD))

    def _score(self, log_a: np.ndarray) -> tuple[float, int]:
        assert self.mean is not None and self.std is not None
        z = (log_a - self.mean) / self.std
        j = int(np.argmax(z))
        return float(z[j]), j

    def fit(self, windows: Iterable[TrainingWindow]) -> None:
        """The healthy reference and the threshold (module docstring)."""
        rows = [
            a
            for h, w in self.histories(windows)
            if w.healthy and (a := self._amplitudes(h, w.sample_rate_hz)) is not None
        ]
        if len(rows) < 2:
            raise ValueError(
                f"detector {self.name}: {len(rows)} healthy training histories with two"
                " revolutions of the drum; it needs 2 or more"
            )
        logs = np.array(rows)
        self.mean = logs.mean(axis=0)
        self.std = np.maximum(logs.std(axis=0), 1e-6)
        scores = np.array([self._score(a)[0] for a in logs])
        self.threshold = float(scores.mean() + self.k * scores.std())
        if not self.threshold > 0.0:
            raise ValueError(f"detector {self.name}: healthy scores give no positive threshold")
        self.healthy_index = scores / self.threshold

    def judge(
        self, history: Mapping[str, np.ndarray], last_sample_index: int, sample_rate_hz: float
    ) -> Assessment:
        if self.threshold is None:
            raise RuntimeError(f"detector {self.name} is not fitted: call fit() first")
        time_s = last_sample_index / sample_rate_hz
        log_a = self._amplitudes(history, sample_rate_hz)
        if log_a is None:
            return Assessment(last_sample_index, time_s, 0.0, False)
        score, j = self._score(log_a)
        index = score / self.threshold
        alarm = index >= 1.0
        diagnosis = None
        if alarm:
            z = np.maximum((log_a - self.mean) / self.std, 0.0)
            diagnosis = Diagnosis(DRUM_KIND, "drum", confidence=float(z[j] / z.sum()))
        return Assessment(last_sample_index, time_s, float(index), bool(alarm), diagnosis)
