"""The order-analysis baseline (``orders``): the drum's angle fluctuation at its orders,
from the tone ring, against a healthy reference.

A drum whose radius varies with its angle (out of round: ovality is order 2) makes the
braking torque vary with the angle, so the drum runs ahead of and behind a smooth stop at
those orders; the tone ring's edges, equally spaced in angle, show it as a ripple of their
times (:func:`~brake_sim_ros.detection.features.angle_fluctuation_orders`, rad at orders
1-20, over the last :attr:`OrderAnalysis.history_s` = 1 s, about 16 revolutions at the
start of the published stop; assessed every 0.1 s). At 5120 Hz the edge times' rounding to
the samples is the noise floor (about 3e-4 rad at order 2 over 0.5 s of sliding on the
reference campaign's healthy brakes, against 1e-3 rad for 75 um of ovality): a second of
history halves its share against 0.5 s and separates 75 um from healthy.

Fit (healthy training histories with at least two revolutions): per order ``k``, the median
``m_k`` of ``log10`` of the amplitude and its spread ``s_k`` (1.4826 times the median
absolute deviation: the impacts at the start of a stop stir every order of a few
histories, which would widen a standard deviation). Score of a history:
``max_k (log10 a_k - m_k) / s_k``, the order that stands out most from healthy; the alarm
threshold is the ``quantile`` (default 0.995) of the healthy training histories' scores,
and the health index the score over that threshold (1: the alarm).
A history with fewer than two revolutions (a slow or stopped drum) scores 0 (no alarm).

Like with like: the shoes' impacts at the start of a stop jolt the drum and stir every
order, far more than a drum's runout does, so a history is judged only while the backing
plate is quiet: its y acceleration's rms at most :data:`GATE_FACTOR` times the quiet level
of the healthy training histories (their :data:`QUIET_QUANTILE` quantile); a louder
history scores 0 (not judged, no alarm). ``gate_channel=None`` judges every history.

Diagnosis on alarm: ``drum_out_of_round`` at ``drum`` (nothing else in the catalogue is
tied to the drum's angle), with the alarmed order's share of the score as confidence. The
shoe defects do not vary with the drum's angle: this detector is not meant to see them.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np

from brake_sim_ros.detection.detector import Assessment, Diagnosis, TrainingWindow
from brake_sim_ros.detection.features import PULSE_CHANNEL, angle_fluctuation_orders, rms
from brake_sim_ros.detection.history import HistoryDetector
from brake_sim_ros.model.catalogue import DRUM_KIND

MAD_TO_STD = 1.4826  # a normal distribution's standard deviation over its median |deviation|
FLOOR_RAD = 1e-12
GATE_CHANNEL = "backing_plate_accel_y"
QUIET_QUANTILE = 0.1  # of the healthy histories' rms of the gate channel: its quiet level
GATE_FACTOR = 3.0  # a history louder than this times the quiet level is not judged


class OrderAnalysis(HistoryDetector):
    """Order analysis of the tone ring (module docstring)."""

    def __init__(
        self,
        *,
        history_s: float = 1.0,
        window_s: float = 0.1,
        quantile: float = 0.995,
        gate_channel: str | None = GATE_CHANNEL,
    ) -> None:
        super().__init__()
        if not (window_s > 0.0 and history_s >= window_s and 0.5 <= quantile <= 1.0):
            raise ValueError(
                f"window_s={window_s!r}, history_s={history_s!r}, quantile={quantile!r}:"
                " allowed window_s > 0, history_s >= window_s, quantile 0.5 to 1"
            )
        self.name = "orders"
        self.gate_channel = gate_channel
        self.channels = (PULSE_CHANNEL,) + ((gate_channel,) if gate_channel else ())
        self.gate: float = np.inf  # rms of the gate channel above which nothing is judged
        self.window_s, self.history_s = float(window_s), float(history_s)
        self.quantile = float(quantile)
        self.mean: np.ndarray | None = None
        self.std: np.ndarray | None = None
        self.threshold: float | None = None
        self.healthy_index: np.ndarray = np.zeros(0)  # the healthy training histories'

    def _amplitudes(self, history: Mapping[str, np.ndarray], rate: float) -> np.ndarray | None:
        if self.gate_channel and not rms(history[self.gate_channel]) <= self.gate:
            return None  # the impacts: not judged
        a = angle_fluctuation_orders(history[PULSE_CHANNEL], rate)
        return None if not a.any() else np.log10(np.maximum(a, FLOOR_RAD))

    def _score(self, log_a: np.ndarray) -> tuple[float, int]:
        assert self.mean is not None and self.std is not None
        z = (log_a - self.mean) / self.std
        j = int(np.argmax(z))
        return float(z[j]), j

    def fit(self, windows: Iterable[TrainingWindow]) -> None:
        """The healthy reference and the threshold (module docstring)."""
        healthy = [(h, w.sample_rate_hz) for h, w in self.histories(windows) if w.healthy]
        self.gate = np.inf
        if self.gate_channel and healthy:
            levels = [rms(h[self.gate_channel]) for h, _ in healthy]
            self.gate = GATE_FACTOR * float(np.nanquantile(levels, QUIET_QUANTILE))
        rows = [a for h, rate in healthy if (a := self._amplitudes(h, rate)) is not None]
        if len(rows) < 2:
            raise ValueError(
                f"detector {self.name}: {len(rows)} healthy training histories with two"
                " revolutions of the drum; it needs 2 or more"
            )
        logs = np.array(rows)
        # robust: the impacts at the start of a stop stir every order of a few histories
        self.mean = np.median(logs, axis=0)
        mad = np.median(np.abs(logs - self.mean), axis=0)
        self.std = np.maximum(MAD_TO_STD * mad, 1e-6)
        scores = np.array([self._score(a)[0] for a in logs])
        self.threshold = float(np.quantile(scores, self.quantile))
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
