"""The detector interface: one streaming contract, the same offline and live.

A detector receives the measured channels of one brake as consecutive chunks of samples
(:class:`SampleChunk`: from a dataset's Parquet rows, from a recording, or from the
node's ``~/measured`` messages) and returns an :class:`Assessment` per window of
``window_samples`` samples: a health index (higher: less healthy; 1 is the detector's
alarm threshold), an alarm flag and, when it decides, a :class:`Diagnosis`.

Windows are aligned to the run's sample index (window ``w`` holds samples
``w N .. (w + 1) N - 1``), whatever the chunks: the same samples give the same
assessments at the same sample indices offline, replayed or live, however they were cut
into chunks. A gap in the sample index drops the partial window and restarts at the next
aligned window.

A user's detector subclasses :class:`Detector` (``name``, ``channels``, ``assess``;
``fit`` when it learns) and is named on the command line by ``module:Class``.
"""

from __future__ import annotations

import abc
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class SampleChunk:
    """Consecutive samples of measured channels.

    Attributes:
        first_sample_index: the run's index of the first sample.
        sample_rate_hz: samples per second (the scenario's rate).
        channels: channel name -> values, shape (n,), float64, in the channel's unit (NaN
            where the channel gave no value: a dropout, or a slower channel between its
            samples).
    """

    first_sample_index: int
    sample_rate_hz: float
    channels: Mapping[str, np.ndarray]

    def __post_init__(self) -> None:
        lengths = {np.shape(v) for v in self.channels.values()}
        if len(lengths) > 1 or any(len(s) != 1 for s in lengths):
            raise ValueError(f"channels of shapes {sorted(lengths)}: allowed one 1-D length")
        if not (math.isfinite(self.sample_rate_hz) and self.sample_rate_hz > 0.0):
            raise ValueError(f"sample_rate_hz={self.sample_rate_hz!r}: allowed > 0")
        if self.first_sample_index < 0:
            raise ValueError(f"first_sample_index={self.first_sample_index}: allowed >= 0")

    def __len__(self) -> int:
        return next((len(v) for v in self.channels.values()), 0)


@dataclass(frozen=True)
class Diagnosis:
    """What a detector says is wrong: a kind of the defect catalogue (``brake-sim
    defects``) at a location, its estimated severity in the kind's unit, confidence 0-1."""

    kind: str
    location: str
    severity: float = math.nan
    confidence: float = math.nan


@dataclass(frozen=True)
class Assessment:
    """A detector's verdict on the window ending at ``sample_index`` (time ``time_s``)."""

    sample_index: int
    time_s: float
    health_index: float
    alarm: bool
    diagnosis: Diagnosis | None = None


@dataclass(frozen=True)
class TrainingWindow:
    """One window for :meth:`Detector.fit`: channel values, shape (n,) each, and the truth
    at its last sample (the active defect kinds with their locations; empty: healthy).
    ``run_id`` and ``last_sample_index`` (the run's index of its last sample; -1: not
    known) let a detector that judges a longer history join consecutive windows."""

    channels: Mapping[str, np.ndarray]
    sample_rate_hz: float
    defects: tuple[tuple[str, str], ...] = field(default=())
    run_id: str = ""
    last_sample_index: int = -1

    @property
    def healthy(self) -> bool:
        return not self.defects


class Detector(abc.ABC):
    """The streaming contract (module docstring). Subclasses set :attr:`name`,
    :attr:`channels` and :attr:`window_s` and implement :meth:`assess`; learning detectors
    override :meth:`fit`."""

    name: str = "detector"
    channels: tuple[str, ...] = ()
    window_s: float = 0.1

    def __init__(self) -> None:
        self._rate: float | None = None
        self._buffer: dict[str, list[np.ndarray]] = {}
        self._buffered = 0
        self._next_index: int | None = None

    # -- what subclasses provide --------------------------------------------------------
    def fit(self, windows: Iterable[TrainingWindow]) -> None:  # noqa: B027 - optional
        """Learn from training windows (default: nothing to learn)."""

    @abc.abstractmethod
    def assess(
        self, window: Mapping[str, np.ndarray], last_sample_index: int, sample_rate_hz: float
    ) -> Assessment:
        """The verdict on one window (``window_samples`` values per channel)."""

    # -- the streaming part -------------------------------------------------------------
    def window_samples(self, sample_rate_hz: float) -> int:
        return max(1, round(self.window_s * sample_rate_hz))

    def reset(self) -> None:
        """Forget the partial window (a new run, a new brake)."""
        self._buffer, self._buffered, self._next_index, self._rate = {}, 0, None, None

    def feed(self, chunk: SampleChunk) -> list[Assessment]:
        """The assessments of every window that ``chunk`` completes, in order."""
        missing = [c for c in self.channels if c not in chunk.channels]
        if missing:
            raise ValueError(
                f"detector {self.name}: no channel {missing[0]!r} in the samples; it reads"
                f" {list(self.channels)}"
            )
        if self._rate is not None and chunk.sample_rate_hz != self._rate:
            self.reset()  # a new run at another rate
        n = self.window_samples(chunk.sample_rate_hz)
        start = chunk.first_sample_index
        offset = 0
        if self._next_index != start:  # first chunk or a gap: wait for an aligned window
            self._buffer, self._buffered = {c: [] for c in self.channels}, 0
            offset = (-start) % n
        self._rate = chunk.sample_rate_hz
        self._next_index = start + len(chunk)
        out = []
        k = offset
        while k < len(chunk):
            take = min(n - self._buffered, len(chunk) - k)
            for c in self.channels:
                self._buffer[c].append(np.asarray(chunk.channels[c][k : k + take]))
            self._buffered += take
            k += take
            if self._buffered == n:
                window = {c: np.concatenate(parts) for c, parts in self._buffer.items()}
                last = start + k - 1
                out.append(self.assess(window, last, chunk.sample_rate_hz))
                self._buffer, self._buffered = {c: [] for c in self.channels}, 0
        return out
