"""The impact baseline (``impact``): each stop judged by the shoes' first impacts.

When the brake is applied the shoes cross their clearance, hit the drum, bounce and settle
within about 60 ms; the backing plate rings with it and is quiet again by 0.1 s. Which shoe
touches first, how hard and how often they bounce is set by the shoes' geometry and their
actuation: a pivot moved out, a shoe tilted, an uneven share of the force, a delay or lag,
a weak return spring, a worn lining all change the sequence, while the rest of the stop
shows little of them (``brake-sim`` README, "What the baselines do not see"). The other
baselines judge fixed 0.1-0.5 s windows in which these few milliseconds are diluted; this
one finds the application in the signals and judges exactly that event, once per stop.

**Application** (causal, from the measured line pressure): after a finite sample below
:data:`RELEASE_BAR` (the brake released; a monitor that starts during a stop waits for the
release), the first finite sample at or above :data:`APPLY_BAR` is the stop's trigger.

**Features** (:func:`event_features`): the rms of each backing-plate acceleration
(:data:`~.features.ACCEL_CHANNELS`, m/s^2) in :data:`N_BINS` bins of :data:`BIN_S`
(rounded to whole samples), the first :data:`PRE_BINS` of them before the trigger, as
``log10(rms + FLOOR)`` (a bin without a finite sample: no evidence, it reads as healthy).
The condition they depend on is the line pressure's rise rate over the first
:data:`RAMP_S` after the trigger (bar/s): a harder application hits harder and sooner.

**Healthy model** (fitted on the healthy training stops): each feature's linear
dependence on the rise rate (least squares), the residuals scaled by their standard
deviation, and the covariance of those scaled residuals, shrunk by Ledoit-Wolf
(``sklearn.covariance``: 64 features from a few dozen stops). A stop's **distance** is the
Mahalanobis distance of its scaled residuals under that covariance.

**Threshold**: the largest distance of a healthy training stop scored by a model that did
not see its unit (the stops grouped by ``unit_id``, or by run where the windows carry no
unit): the brake a monitor judges is one it never saw, so its healthy scatter must be
judged out of unit. Health index = distance / threshold; 1 is the alarm. With N healthy
training stops the largest out-of-unit one is exceeded by a new healthy stop with a
probability of about 1/(N+1) (the rate is stated by the training data, not measured).

**Verdict**: given at the window in which the event's last sample arrives (about 0.1 s
after the trigger) and held (health index, alarm and diagnosis) at every window until the
next stop's verdict replaces it: a brake's defect does not leave between stops. Before
its first stop a brake reads 0, no alarm.

**Diagnosis** on alarm: the defective training class (``kind:location`` of the first
active defect) whose mean scaled residuals lie nearest under the same covariance;
confidence is that class's share of ``exp(-d^2/2)`` over the defective classes. Severity:
the projection of the stop onto that class's direction from the healthy mean, times the
class's least-squares slope of severity on that projection over its training stops (a
severity linear in a small defect; NaN for a class with fewer than 2 training stops).

Everything it computes after fitting is numpy on stored arrays, so a detector loaded from
its saved form (:mod:`.saved`) gives the fitted one's verdicts bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace

import numpy as np
from sklearn.covariance import LedoitWolf

from brake_sim_ros.detection.detector import Assessment, Detector, Diagnosis, TrainingWindow
from brake_sim_ros.detection.features import ACCEL_CHANNELS, PRESSURE_CHANNEL

APPLY_BAR = 2.0  # line pressure that marks an application (its noise is about 0.1 bar)
RELEASE_BAR = 1.0  # below it the brake is released and the next application is armed
BIN_S = 0.0025  # s, one bin of the acceleration's envelope
N_BINS = 32  # bins per event (80 ms at 2.5 ms)
PRE_BINS = 2  # of them before the trigger (the first contact can precede 2 bar)
RAMP_S = 0.1  # s after the trigger over which the pressure's rise rate is measured
RAMP_EDGE_S = 0.01  # s averaged at each end of that interval
FLOOR = 1e-2  # m/s^2 added before the log: below the accelerometers' noise
CHANNELS = (*ACCEL_CHANNELS, PRESSURE_CHANNEL)
N_FEATURES = len(ACCEL_CHANNELS) * N_BINS
MIN_HEALTHY_STOPS = 3


@dataclass(frozen=True)
class EventShape:
    """The event's sample counts at one sample rate."""

    bin: int  # samples per bin
    pre: int  # samples before the trigger
    post: int  # samples from the trigger to the verdict (the trigger's included)

    @classmethod
    def at(cls, sample_rate_hz: float) -> EventShape:
        b = max(1, round(BIN_S * sample_rate_hz))
        after = (N_BINS - PRE_BINS) * b
        return cls(b, PRE_BINS * b, max(after, round(RAMP_S * sample_rate_hz)))


def event_features(
    segment: Mapping[str, np.ndarray], shape: EventShape, sample_rate_hz: float
) -> tuple[np.ndarray, float]:
    """``(features, rise_rate)`` of one event (module docstring): ``segment`` holds each
    channel from ``shape.pre`` samples before the trigger to ``shape.post`` after it
    (NaN where nothing was measured). Features shape (:data:`N_FEATURES`,), NaN for a bin
    without a finite sample; rise rate in bar/s, NaN without pressure at both ends."""
    out = []
    for c in ACCEL_CHANNELS:
        x = np.asarray(segment[c][: N_BINS * shape.bin], dtype=np.float64).reshape(N_BINS, -1)
        finite = np.isfinite(x)
        count = finite.sum(axis=1)
        power = np.where(finite, x * x, 0.0).sum(axis=1)
        rms = np.sqrt(power / np.maximum(count, 1))
        out.append(np.where(count > 0, np.log10(rms + FLOOR), np.nan))
    p = np.asarray(segment[PRESSURE_CHANNEL], dtype=np.float64)[shape.pre :]
    edge = max(1, round(RAMP_EDGE_S * sample_rate_hz))
    ramp = round(RAMP_S * sample_rate_hz)
    first, last = p[:edge], p[max(0, ramp - edge) : ramp]
    if np.isfinite(first).any() and np.isfinite(last).any():
        rate = (np.nanmean(last) - np.nanmean(first)) / (max(ramp - edge, 1) / sample_rate_hz)
    else:
        rate = math.nan
    return np.concatenate(out), float(rate)


def _residuals(model: tuple[np.ndarray, ...], features: np.ndarray, rate: float) -> np.ndarray:
    """A stop's scaled residuals from a healthy model ``(coef, scale, location, ...)``,
    centred on its healthy mean (a bin without samples: 0, no evidence)."""
    coef, scale, location = model[:3]
    z = (features - (coef[0] + coef[1] * rate)) / scale - location
    return np.where(np.isfinite(z), z, 0.0)


def _mahalanobis(z: np.ndarray, precision: np.ndarray) -> float:
    """The Mahalanobis length of residuals ``z`` under ``precision``."""
    return math.sqrt(max(float(z @ precision @ z), 0.0))


class _StopFinder:
    """Finds applications in a stream of windows and returns each event's samples once
    they are all there (module docstring). Consecutive windows only: a gap restarts it."""

    def __init__(self, shape: EventShape) -> None:
        self.shape = shape
        self.buffer: dict[str, np.ndarray] = {}
        self.start = 0  # the run's index of buffer's first sample
        self.end: int | None = None  # one past the last sample seen
        self.scanned = 0  # the run's index from which the pressure is still to scan
        self.armed = False
        self.trigger: int | None = None

    def push(self, window: Mapping[str, np.ndarray], last_sample_index: int) -> list[dict]:
        """The segments (channel -> samples) of the events this window completes."""
        n = len(window[PRESSURE_CHANNEL])
        first = last_sample_index - n + 1
        if self.end != first:  # a new run or a gap: wait for the next release
            self.start = self.scanned = first
            self.buffer = {c: np.zeros(0) for c in CHANNELS}
            self.armed, self.trigger = False, None
        self.buffer = {
            c: np.concatenate([self.buffer[c], np.asarray(window[c], dtype=np.float64)])
            for c in CHANNELS
        }
        self.end = last_sample_index + 1
        done = []
        while True:
            if self.trigger is None and not self._find_trigger():
                break
            assert self.trigger is not None
            stop = self.trigger + self.shape.post
            if stop > self.end:
                break
            lo = self.trigger - self.shape.pre
            pad = max(0, self.start - lo)  # a trigger too near the run's start
            done.append(
                {
                    c: np.concatenate(
                        [np.full(pad, np.nan), v[lo + pad - self.start : stop - self.start]]
                    )
                    for c, v in self.buffer.items()
                }
            )
            self.scanned, self.trigger = self.trigger + 1, None
        keep = self.end - self.shape.pre if self.trigger is None else self.trigger - self.shape.pre
        keep = max(keep, self.start)
        self.buffer = {c: v[keep - self.start :] for c, v in self.buffer.items()}
        self.start = keep
        return done

    def _find_trigger(self) -> bool:
        assert self.end is not None
        p = self.buffer[PRESSURE_CHANNEL][self.scanned - self.start :]
        offset = 0
        if not self.armed:
            below = np.flatnonzero(p < RELEASE_BAR)  # NaN compares False
            if below.size == 0:
                self.scanned = self.end
                return False
            self.armed, offset = True, int(below[0]) + 1
        above = np.flatnonzero(p[offset:] >= APPLY_BAR)
        if above.size == 0:
            self.scanned = self.end
            return False
        self.trigger = self.scanned + offset + int(above[0])
        self.armed = False
        return True


class ImpactDetector(Detector):
    """Judges each stop by its first impacts (module docstring)."""

    def __init__(self, *, window_s: float = 0.1) -> None:
        super().__init__()
        if not (math.isfinite(window_s) and window_s > 0.0):
            raise ValueError(f"window_s={window_s!r}: allowed > 0")
        self.name = "impact"
        self.channels = CHANNELS
        self.window_s = float(window_s)
        # fitted state (module docstring); arrays so that a saved form restores it exactly
        self.sample_rate_hz: float | None = None
        self.coef = np.zeros((2, N_FEATURES))  # feature = coef[0] + coef[1] * rise rate
        self.scale = np.ones(N_FEATURES)  # std of the healthy residuals
        self.location = np.zeros(N_FEATURES)  # healthy mean of the scaled residuals
        self.precision = np.eye(N_FEATURES)  # inverse of their shrunk covariance
        self.rate_mean = 0.0  # bar/s, the healthy stops' mean rise rate (a missing one's)
        self.threshold: float | None = None
        self.healthy_index = np.zeros(0)  # healthy training stops, out of unit
        self.classes: tuple[str, ...] = ()  # defective training classes, sorted
        self.centroids = np.zeros((0, N_FEATURES))
        self.severity_slope = np.zeros(0)  # per class, NaN: no estimate
        self._finder: _StopFinder | None = None
        self._verdict: tuple[float, bool, Diagnosis | None] = (0.0, False, None)

    # -- fitting ------------------------------------------------------------------------
    def _events(
        self, windows: Iterable[TrainingWindow]
    ) -> list[tuple[np.ndarray, float, TrainingWindow]]:
        """(features, rise rate, the window that completed it) of every training stop."""
        out = []
        finder: _StopFinder | None = None
        run = None
        for w in windows:
            if self.sample_rate_hz is None:
                self.sample_rate_hz = w.sample_rate_hz
            elif w.sample_rate_hz != self.sample_rate_hz:
                raise ValueError(
                    f"detector {self.name}: training windows at {w.sample_rate_hz:g} and"
                    f" {self.sample_rate_hz:g} Hz; allowed one sample rate"
                )
            if finder is None or w.run_id != run or w.last_sample_index < 0:
                finder = _StopFinder(EventShape.at(w.sample_rate_hz))
                run = w.run_id
            missing = [c for c in CHANNELS if c not in w.channels]
            if missing:
                raise ValueError(f"detector {self.name}: training windows without {missing[0]!r}")
            last = (
                w.last_sample_index
                if w.last_sample_index >= 0
                else len(w.channels[PRESSURE_CHANNEL]) - 1
            )
            for segment in finder.push(w.channels, last):
                f, rate = event_features(segment, finder.shape, w.sample_rate_hz)
                # the window's truth, not its channels: a stop's window is a view of its
                # whole run, which a fit streamed run by run must not keep
                out.append((f, rate, replace(w, channels={})))
        return out

    @staticmethod
    def _healthy_model(F: np.ndarray, rates: np.ndarray) -> tuple[np.ndarray, ...]:
        """(coef, scale, location, precision) from healthy stops' features and rates."""
        A = np.column_stack([np.ones(rates.size), rates])
        filled = np.where(np.isfinite(F), F, np.nanmean(F, axis=0))
        filled = np.where(np.isfinite(filled), filled, 0.0)
        coef = np.linalg.lstsq(A, filled, rcond=None)[0]
        residual = filled - A @ coef
        scale = np.maximum(residual.std(axis=0), 1e-6)
        lw = LedoitWolf().fit(residual / scale)
        return coef, scale, lw.location_, lw.precision_

    def fit(self, windows: Iterable[TrainingWindow]) -> None:
        """The healthy model, the out-of-unit threshold and the classes (module docstring)."""
        self.sample_rate_hz = None
        events = self._events(windows)
        healthy = [e for e in events if e[2].healthy]
        if len(healthy) < MIN_HEALTHY_STOPS:
            raise ValueError(
                f"detector {self.name}: {len(healthy)} healthy training stops (applications"
                f" of the brake); it needs {MIN_HEALTHY_STOPS} or more"
            )
        F = np.array([e[0] for e in healthy])
        rates = np.array([e[1] for e in healthy])
        self.rate_mean = float(np.nanmean(rates)) if np.isfinite(rates).any() else 0.0
        rates = np.where(np.isfinite(rates), rates, self.rate_mean)
        groups = np.array([e[2].unit_id or e[2].run_id for e in healthy])
        held_out = []
        for g in sorted(set(groups)):
            rest = groups != g
            if rest.sum() < 2:
                continue
            fold = self._healthy_model(F[rest], rates[rest])
            held_out += [
                _mahalanobis(_residuals(fold, f, r), fold[3])
                for f, r in zip(F[~rest], rates[~rest], strict=True)
            ]
        if len(held_out) < 2:
            raise ValueError(
                f"detector {self.name}: healthy training stops of {len(set(groups))} unit(s);"
                " it needs stops of 3 or more units (or runs), each judged by a model of others"
            )
        self.coef, self.scale, self.location, self.precision = self._healthy_model(F, rates)
        if not max(held_out) > 0.0:
            raise ValueError(
                f"detector {self.name}: the healthy training stops do not differ; it needs"
                " their scatter to set a threshold"
            )
        self.threshold = float(max(held_out))
        self.healthy_index = np.array(held_out) / self.threshold
        by_class: dict[str, list[tuple[np.ndarray, float]]] = {}
        for f, r, w in events:
            if not w.healthy:
                severity = w.severities[0] if w.severities else math.nan
                by_class.setdefault(":".join(w.defects[0]), []).append(
                    (self._scaled(f, r), severity)
                )
        self.classes = tuple(sorted(by_class))
        self.centroids = np.array(
            [np.mean([z for z, _ in by_class[c]], axis=0) for c in self.classes]
        ).reshape(len(self.classes), N_FEATURES)
        slopes = []
        for c, centroid in zip(self.classes, self.centroids, strict=True):
            proj = np.array([self._projection(z, centroid) for z, _ in by_class[c]])
            sev = np.array([s for _, s in by_class[c]])
            ok = np.isfinite(proj) & np.isfinite(sev)
            denom = float(proj[ok] @ proj[ok])
            slopes.append(
                float(proj[ok] @ sev[ok]) / denom if ok.sum() >= 2 and denom > 0 else math.nan
            )
        self.severity_slope = np.array(slopes)

    # -- judging ------------------------------------------------------------------------
    def _scaled(self, features: np.ndarray, rate: float) -> np.ndarray:
        """The stop's :func:`_residuals` from the fitted healthy model (a stop without a
        rise rate: the healthy mean rate's)."""
        r = rate if math.isfinite(rate) else self.rate_mean
        return _residuals((self.coef, self.scale, self.location), features, r)

    def _projection(self, z: np.ndarray, centroid: np.ndarray) -> float:
        """z along the class's direction, in units of the class's mean (1: the mean)."""
        norm = float(centroid @ self.precision @ centroid)
        return float(z @ self.precision @ centroid) / norm if norm > 0.0 else math.nan

    def _judge(self, features: np.ndarray, rate: float) -> tuple[float, bool, Diagnosis | None]:
        assert self.threshold is not None
        z = self._scaled(features, rate)
        index = _mahalanobis(z, self.precision) / self.threshold
        alarm = index >= 1.0
        if not (alarm and self.classes):
            return index, alarm, None
        d = self.centroids - z
        d2 = np.einsum("ij,jk,ik->i", d, self.precision, d)
        j = int(np.argmin(d2))
        weights = np.exp(-(d2 - d2[j]) / 2.0)
        kind, location = self.classes[j].split(":", 1)
        severity = self.severity_slope[j] * self._projection(z, self.centroids[j])
        return (
            index,
            alarm,
            Diagnosis(kind, location, float(severity), float(weights[j] / weights.sum())),
        )

    def reset(self) -> None:
        super().reset()
        self._finder, self._verdict = None, (0.0, False, None)

    def assess(
        self, window: Mapping[str, np.ndarray], last_sample_index: int, sample_rate_hz: float
    ) -> Assessment:
        if self.threshold is None or self.sample_rate_hz is None:
            raise RuntimeError(f"detector {self.name} is not fitted: call fit() first")
        if sample_rate_hz != self.sample_rate_hz:
            raise ValueError(
                f"detector {self.name}: samples at {sample_rate_hz:g} Hz; it was fitted at"
                f" {self.sample_rate_hz:g} Hz"
            )
        if self._finder is None:
            self._finder = _StopFinder(EventShape.at(sample_rate_hz))
        for segment in self._finder.push(window, last_sample_index):
            self._verdict = self._judge(
                *event_features(segment, self._finder.shape, sample_rate_hz)
            )
        index, alarm, diagnosis = self._verdict
        return Assessment(
            last_sample_index, last_sample_index / sample_rate_hz, index, alarm, diagnosis
        )
