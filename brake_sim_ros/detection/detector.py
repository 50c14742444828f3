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

:func:`chunk_from_measured` turns one ``MeasuredChunk`` message (live, replayed, or read back
from an MCAP recording) into a :class:`SampleChunk`, the one conversion every reader of
``~/measured`` uses, so offline and live detectors see the same numbers.

A user's detector subclasses :class:`Detector` (``name``, ``channels``, ``assess``;
``fit`` when it learns) and is named on the command line by ``module:Class``.
"""

from __future__ import annotations

import abc
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from brake_sim_ros.detection.user_code import user_code
from brake_sim_ros.errors import BrakeSimError


class RateMismatchError(BrakeSimError, ValueError):
    """Samples at another rate than the detector was fitted at (one line, both rates)."""


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


# The most samples one MeasuredChunk may cover: 2**22, 164 s at 25.6 kHz (the node sends
# 0.1 s), and the most values its channels may spread over (2**25 float64, 256 MiB); a
# larger chunk is a damaged or hostile message, refused before any allocation.
MAX_CHUNK_SAMPLES = 1 << 22
MAX_CHUNK_VALUES = 1 << 25
# the longest window a detector may buffer, samples (82 s at 51.2 kHz): a rate that asks
# for more is refused, never buffered without end (32 MB per channel at the limit)
MAX_WINDOW_SAMPLES = 1 << 22
MAX_WINDOW_S = 60.0  # the longest window a detector may ask for, s


def chunk_from_measured(msg: Any) -> SampleChunk:
    """The :class:`SampleChunk` of one ``brake_sim_msgs/MeasuredChunk`` (or any object with
    its fields): every channel on the simulator's samples, NaN between a decimated
    channel's samples, as a dataset's measured columns read (``measured:<name> [<unit>]``;
    the tone-ring edge times are not channels here, as there).

    Channel ``c`` holds its values at the sample indices in ``[first_sample_index,
    first_sample_index + sample_count)`` that are multiples of ``decimation[c]``
    (MeasuredChunk.msg).

    Raises:
        ValueError: a message whose fields do not fit together (one line: which field,
            what it should be); its values are never echoed.
    """
    first = int(msg.first_sample_index)
    n = int(msg.sample_count)
    rate = float(msg.sample_rate_hz)
    where = f"measured chunk at sample {first}"
    names = list(msg.channel_names)
    decimation = [int(d) for d in msg.decimation]
    counts = [int(c) for c in msg.channel_sample_counts]
    values = np.asarray(msg.values, dtype=np.float64)
    if not (math.isfinite(rate) and rate > 0.0):
        raise ValueError(f"{where}: sample_rate_hz is not a finite rate > 0")
    if n > MAX_CHUNK_SAMPLES:
        raise ValueError(
            f"{where}: sample_count {n}; allowed at most {MAX_CHUNK_SAMPLES} samples a chunk"
        )
    if n * len(names) > MAX_CHUNK_VALUES:
        raise ValueError(
            f"{where}: {len(names)} channels of {n} samples; allowed at most"
            f" {MAX_CHUNK_VALUES} values a chunk"
        )
    if len({len(names), len(msg.units), len(decimation), len(counts)}) != 1:
        raise ValueError(
            f"{where}: {len(names)} channel_names, {len(msg.units)} units,"
            f" {len(decimation)} decimation, {len(counts)} channel_sample_counts; allowed"
            " one of each per channel"
        )
    if len(set(names)) != len(names):
        raise ValueError(f"{where}: a channel name appears twice; allowed distinct names")
    if sum(counts) != values.size:
        raise ValueError(
            f"{where}: {values.size} values, its channel_sample_counts say {sum(counts)}"
        )
    channels: dict[str, np.ndarray] = {}
    start = 0
    for name, step, count in zip(names, decimation, counts, strict=True):
        shown = repr(name[:40])  # a name from the wire, shown short
        if step < 1:
            raise ValueError(f"{where}: channel {shown} has decimation {step}; allowed >= 1")
        offset = (-first) % step  # the first multiple of the decimation in the chunk
        expected = 0 if offset >= n else (n - 1 - offset) // step + 1
        if count != expected:
            raise ValueError(
                f"{where}: channel {shown} has {count} values; {n} samples at decimation"
                f" {step} hold {expected}"
            )
        column = np.full(n, np.nan)
        column[offset::step] = values[start : start + count]
        channels[name] = column
        start += count
    return SampleChunk(first, rate, channels)


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
    """A detector's verdict on the window ending at ``sample_index`` (time ``time_s``).
    ``rul_s``: its forecast of the brake's remaining useful life there, s of operation
    until the first defect reaches its kind's service limit (``brake-sim defects``), >= 0;
    NaN when it gives none (the scorer's ``forecast`` figures compare it with the run's
    ``rul [s]`` label)."""

    sample_index: int
    time_s: float
    health_index: float
    alarm: bool
    diagnosis: Diagnosis | None = None
    rul_s: float = math.nan


@dataclass(frozen=True)
class TrainingWindow:
    """One window for :meth:`Detector.fit`: channel values, shape (n,) each, and the truth
    at its last sample (the active defect kinds with their locations; empty: healthy).
    ``severities`` are those defects' severities there, in each kind's unit, in the order
    of ``defects`` (empty: not known). ``run_id`` and ``last_sample_index`` (the run's
    index of its last sample; -1: not known) let a detector that judges a longer history
    join consecutive windows; ``unit_id`` (empty: not known) names the brake, so that a
    detector can judge its healthy scatter on brakes it did not fit."""

    channels: Mapping[str, np.ndarray]
    sample_rate_hz: float
    defects: tuple[tuple[str, str], ...] = field(default=())
    run_id: str = ""
    last_sample_index: int = -1
    severities: tuple[float, ...] = field(default=())
    unit_id: str = ""

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
    # What fitting saw (``evaluate.fit`` records it; a saved detector keeps it): the
    # sample rate, Hz (None: not recorded), and each channel read with its unit. What a
    # detector learns (a threshold on an RMS) belongs to that rate: feeding samples at
    # another rate is refused, unless the detector declares that it resamples.
    fitted_rate_hz: float | None = None
    fitted_channels: Mapping[str, str] = MappingProxyType({})
    # The brake whose samples it was fitted on ("study" or "service"; None: not recorded):
    # the other brake's springs, stops, hydraulics, tyre and clearance change every signal,
    # so its samples are refused whatever the detector.
    fitted_brake: str | None = None
    resamples: bool = False

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

    # -- the saved form (``brake-sim fit``; the built-ins' is in :mod:`.saved`) -----------
    def saved_state(self) -> Mapping[str, Any] | None:
        """What fitting learned, for a saved file: a mapping of JSON values (finite
        numbers, strings, booleans, null, lists, string-keyed objects) and float64 or
        int64 numpy arrays, restored bit for bit. None (the default): no saved form."""
        return None

    def load_state(self, state: Mapping[str, Any]) -> None:
        """Take back what :meth:`saved_state` gave, on an instance built without
        arguments; raise ValueError (one line) on a state it cannot take."""
        raise NotImplementedError(f"detector {self.name}: no saved form")

    # -- the streaming part -------------------------------------------------------------
    def rate_refusal(self, sample_rate_hz: float) -> str | None:
        """Why samples at ``sample_rate_hz`` (Hz) cannot be judged, in one line naming both
        rates; None when they can (the fitted rate, not recorded, or a resampling
        detector)."""
        fitted = self.fitted_rate_hz
        if self.resamples or fitted is None or sample_rate_hz == fitted:
            return None
        return (
            f"detector {self.name} was fitted at {fitted:g} Hz and the samples are at"
            f" {sample_rate_hz:g} Hz: allowed {fitted:g} Hz (fit it on runs at"
            f" {sample_rate_hz:g} Hz, or stream at {fitted:g} Hz)"
        )

    def brake_refusal(self, brake: str, where: str) -> str | None:
        """Why samples from ``brake`` ("study" or "service"; "": not declared) cannot be
        judged, in one line naming both brakes and ``where`` (the run, the file or the
        stream); None when they can (the fitted brake, or none recorded)."""
        fitted = self.fitted_brake
        if fitted is None or brake == fitted:
            return None
        if not brake:
            return (
                f"detector {self.name} was fitted on the {fitted} brake's samples and the brake"
                f" of {where} is not declared: allowed samples from the {fitted} brake (declare"
                " theirs: brake-sim monitor --brake study|service, or the ROS parameter brake)"
            )
        return (
            f"detector {self.name} was fitted on the {fitted} brake's samples and {where}"
            f" comes from the {brake} brake: allowed the {fitted} brake's (fit it on the"
            f" {brake} brake's runs)"
        )

    def window_samples(self, sample_rate_hz: float) -> int:
        """The window's length at ``sample_rate_hz``, samples: ``window_s`` rounded.

        Raises:
            ValueError: a window under half a sample there (one line: never one sample
                standing in for it).
        """
        n = round(self.window_s * sample_rate_hz)
        if n < 1:
            raise ValueError(
                f"detector {self.name}: window_s {self.window_s:g} s is under one sample at"
                f" {sample_rate_hz:g} Hz; allowed at least 1 / {sample_rate_hz:g} s"
            )
        return n

    def reset(self) -> None:
        """Forget the partial window (a new run, a new brake)."""
        self._buffer, self._buffered, self._next_index, self._rate = {}, 0, None, None

    def feed(self, chunk: SampleChunk) -> list[Assessment]:
        """The assessments of every window that ``chunk`` completes, in order.

        Raises:
            RateMismatchError: samples at another rate than the fitted one.
            ValueError: a channel the detector reads is missing.
        """
        refusal = self.rate_refusal(chunk.sample_rate_hz)
        if refusal is not None:
            raise RateMismatchError(refusal)
        missing = [c for c in self.channels if c not in chunk.channels]
        if missing:
            raise ValueError(
                f"detector {self.name}: no channel {missing[0]!r} in the samples; it reads"
                f" {list(self.channels)}"
            )
        if self._rate is not None and chunk.sample_rate_hz != self._rate:
            self.reset()  # a new run at another rate
        n = self.window_samples(chunk.sample_rate_hz)
        if n > MAX_WINDOW_SAMPLES:
            raise ValueError(
                f"detector {self.name}: a window of {n} samples at {chunk.sample_rate_hz:g} Hz;"
                f" allowed at most {MAX_WINDOW_SAMPLES} (the samples a window may buffer)"
            )
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
                with user_code(self, "assess"):
                    verdict = self.assess(window, last, chunk.sample_rate_hz)
                    if not isinstance(verdict, Assessment):
                        raise TypeError(f"it returned {type(verdict).__name__}, not an Assessment")
                out.append(verdict)
                self._buffer, self._buffered = {c: [] for c in self.channels}, 0
        return out
