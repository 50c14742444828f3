"""Detectors that judge each window on a longer history of samples.

Order analysis needs several revolutions of the drum (about 8 in 0.5 s at the start of the
published stop), more than the 0.1 s between assessments. A :class:`HistoryDetector`
assesses every ``window_s`` as the streaming contract asks, but on the last ``history_s``
of consecutive samples: its own windows joined. At a run's start, or after a gap in the
sample index, it judges what it has (shorter histories) and the history restarts, the
same offline, replayed or live. Training joins a run's consecutive training windows the
same way (:meth:`HistoryDetector.histories`), so a detector is fitted on what it will see.
"""

from __future__ import annotations

import abc
from collections.abc import Iterable, Iterator, Mapping

import numpy as np

from brake_sim_ros.detection.detector import Assessment, Detector, TrainingWindow


class HistoryDetector(Detector):
    """Judges the last :attr:`history_s` of samples at every window (module docstring).
    Subclasses implement :meth:`judge`."""

    history_s: float = 0.5

    def __init__(self) -> None:
        super().__init__()
        self._history: list[Mapping[str, np.ndarray]] = []
        self._last_index: int | None = None

    def history_windows(self) -> int:
        """How many of its windows make a history."""
        return max(1, round(self.history_s / self.window_s))

    def reset(self) -> None:
        super().reset()
        self._history, self._last_index = [], None

    @abc.abstractmethod
    def judge(
        self, history: Mapping[str, np.ndarray], last_sample_index: int, sample_rate_hz: float
    ) -> Assessment:
        """The verdict on a history (consecutive samples ending at ``last_sample_index``)."""

    def assess(
        self, window: Mapping[str, np.ndarray], last_sample_index: int, sample_rate_hz: float
    ) -> Assessment:
        n = self.window_samples(sample_rate_hz)
        if self._last_index is None or last_sample_index - n != self._last_index:
            self._history = []  # a new run or a gap
        self._history = [*self._history, window][-self.history_windows() :]
        self._last_index = last_sample_index
        return self.judge(_join(self._history), last_sample_index, sample_rate_hz)

    def histories(
        self, windows: Iterable[TrainingWindow]
    ) -> Iterator[tuple[Mapping[str, np.ndarray], TrainingWindow]]:
        """``(history, window)`` for each training window: the history the detector would
        judge at its end (consecutive windows of one run joined, as :meth:`assess` does;
        windows without a ``run_id`` and sample index stand alone)."""
        history: list[Mapping[str, np.ndarray]] = []
        last: tuple[str, int] | None = None
        for w in windows:
            n = len(next(iter(w.channels.values()), ()))
            known = bool(w.run_id) and w.last_sample_index >= 0
            if not known or last != (w.run_id, w.last_sample_index - n):
                history = []
            history = [*history, w.channels][-self.history_windows() :]
            last = (w.run_id, w.last_sample_index) if known else None
            yield _join(history), w


def _join(parts: list[Mapping[str, np.ndarray]]) -> dict[str, np.ndarray]:
    if len(parts) == 1:
        return dict(parts[0])
    return {c: np.concatenate([p[c] for p in parts]) for c in parts[0]}
