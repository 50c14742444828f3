"""Features of one window of measured channels: the one feature function every baseline
uses (the threshold on a statistic, the order analysis, the learned classifier).

From the measured channels of the default sensor set (``brake-sim`` README, "Measured
signals"), per window (:func:`window_features`, names :func:`feature_names`):

* per accelerometer channel (:data:`ACCEL_CHANNELS`, m/s^2): ``rms`` (m/s^2),
  ``kurtosis`` (1), ``crest`` (1), the rms in each band of :data:`BANDS_HZ` (m/s^2, from
  the Hann-windowed spectrum; 0 for a band above the Nyquist frequency), and the
  amplitude at each drum order of :data:`ORDERS` (m/s^2, :func:`order_amplitudes`);
* from the tone ring (:data:`PULSE_CHANNEL`): the amplitude of the drum's angle
  fluctuation at each order (rad, :func:`angle_fluctuation_orders`), the drum's mean speed
  (rad/s), its deceleration (rad/s^2) and the revolutions in the window;
* from the line pressure (:data:`PRESSURE_CHANNEL`, bar): mean and standard deviation,
  and the drum's deceleration per bar of it (rad/s^2/bar, over at least
  :data:`MIN_PRESSURE_BAR`): the brake's effectiveness, which a friction change moves and
  the actuation force does not.

**Drum angle from the tone ring.** The pulse channel is 1 while a tooth is under the
sensor: each 0 -> 1 step is one tooth pitch (``2 pi / teeth``) of the drum. The edge lies
between the two samples; it is placed half a sample before the first 1, and a cubic in
time (the trend :mod:`brake_sim_ros.analysis.orders` removes too) fitted through the
cumulative pitch over the window's edges gives the drum angle at every sample. The
spectrum over orders is then :func:`brake_sim_ros.analysis.orders.order_spectrum` on that
angle: a once-per-revolution reference from what a vehicle measures, not from the model's
state. The teeth count is the default set's (:data:`TONE_RING_TEETH`); orders scale with a
wrong count. Fewer than :data:`MIN_REVOLUTIONS` revolutions in a window (a stopped or
slow drum) give order amplitudes of 0 and a speed from the edges there are.

Windows are arrays of one window per channel (NaN samples, a dropout, are dropped from the
statistics; a channel missing from the window gives NaN features for it).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import numpy as np

from brake_sim_ros.analysis.orders import TREND_DEGREE, order_spectrum
from brake_sim_ros.sensing.sensors import DEFAULT_TONE_RING_TEETH

ACCEL_CHANNELS = ("backing_plate_accel_x", "backing_plate_accel_y")
PULSE_CHANNEL = "wheel_speed"
PRESSURE_CHANNEL = "line_pressure"
CHANNELS = (*ACCEL_CHANNELS, PULSE_CHANNEL, PRESSURE_CHANNEL)
TONE_RING_TEETH = DEFAULT_TONE_RING_TEETH
# Bands of the acceleration spectrum, Hz: below the structure's modes (the drum's orders
# and the actuation), the lower part of the drum-brake noise band (TESTBED: 0.85-4.6 kHz)
# with the first structural modes (1.2-1.45 kHz), and its upper part with the second.
BANDS_HZ: tuple[tuple[float, float], ...] = (
    (5.0, 200.0),
    (200.0, 850.0),
    (850.0, 2000.0),
    (2000.0, 4600.0),
)
ORDERS: tuple[int, ...] = tuple(range(1, 21))  # the drum's out-of-round orders (TESTBED: 1-20)
MIN_REVOLUTIONS = 2  # an order spectrum needs this many whole revolutions in the window
# below this line pressure the brake is not applied: the deceleration per bar is taken
# over this much, so that the noise of an idle line does not make it explode
MIN_PRESSURE_BAR = 1.0


def rms(x: np.ndarray) -> float:
    """Root mean square, the channel's unit (NaN samples ignored; NaN without a sample)."""
    if not np.isfinite(x).any():  # a dropout throughout: nothing to judge, no warning
        return math.nan
    return float(np.sqrt(np.nanmean(np.square(x))))


def kurtosis(x: np.ndarray) -> float:
    """Kurtosis (3 for Gaussian noise; impacts raise it), NaN samples ignored; NaN without
    a sample."""
    if not np.isfinite(x).any():
        return math.nan
    centred = x - np.nanmean(x)
    var = np.nanmean(centred**2)
    return float(np.nanmean(centred**4) / (var * var)) if var > 0.0 else 0.0


def crest_factor(x: np.ndarray) -> float:
    """Peak over RMS (about 3-4 for Gaussian noise), NaN samples ignored; NaN without a
    sample."""
    r = rms(x)
    if math.isnan(r):
        return math.nan
    return float(np.nanmax(np.abs(x)) / r) if r > 0.0 else 0.0


STATISTICS: dict[str, Callable[[np.ndarray], float]] = {
    "rms": rms,
    "kurtosis": kurtosis,
    "crest": crest_factor,
}


def band_rms(x: np.ndarray, sample_rate_hz: float) -> np.ndarray:
    """Rms in each band of :data:`BANDS_HZ` (the signal's unit), shape (bands,): from the
    Hann-windowed spectrum of the mean-removed window (NaN samples set to the mean),
    scaled so that the bands of a white signal add up to its rms; 0 above Nyquist."""
    x = np.asarray(x, dtype=np.float64)
    finite = np.isfinite(x)
    out = np.zeros(len(BANDS_HZ))
    if finite.sum() < 2:
        return out
    x = np.where(finite, x - x[finite].mean(), 0.0)
    w = np.hanning(x.size)
    power = np.abs(np.fft.rfft(x * w)) ** 2 * (2.0 / np.sum(w * w) / x.size)
    freqs = np.fft.rfftfreq(x.size, 1.0 / sample_rate_hz)
    for b, (low, high) in enumerate(BANDS_HZ):
        m = (freqs >= low) & (freqs < high)
        out[b] = math.sqrt(float(power[m].sum())) if m.any() else 0.0
    return out


def tooth_edges(pulse: np.ndarray, sample_rate_hz: float) -> np.ndarray:
    """Times of the tone ring's rising edges within the window, s from its first sample:
    half a sample before each sample that reads 1 after one that reads 0."""
    p = np.asarray(pulse, dtype=np.float64)
    rising = np.flatnonzero((p[1:] > 0.5) & (p[:-1] < 0.5)) + 1
    return (rising - 0.5) / sample_rate_hz


def pulse_transitions(pulse: np.ndarray, sample_rate_hz: float) -> np.ndarray:
    """Times of every change of the pulse (rising and falling edges: half a tooth pitch
    apart), s from the window's first sample, half a sample before the changed sample."""
    p = np.asarray(pulse, dtype=np.float64) > 0.5
    changed = np.flatnonzero(p[1:] != p[:-1]) + 1
    return (changed - 0.5) / sample_rate_hz


def drum_angle(
    pulse: np.ndarray, sample_rate_hz: float, teeth: int = TONE_RING_TEETH
) -> tuple[np.ndarray | None, float, float]:
    """The drum angle at each sample of the window from the tone ring (module docstring).

    Returns:
        (angle, speed, deceleration): angle in rad from the first edge, shape (n,), or None
        when the window holds fewer than 4 edges or the fitted angle does not increase;
        mean speed over the window, rad/s (0 below 2 edges); deceleration, rad/s^2
        (positive when slowing; 0 below 4 edges).
    """
    edges = tooth_edges(pulse, sample_rate_hz)
    pitch = 2.0 * math.pi / teeth
    if edges.size < 2:
        return None, 0.0, 0.0
    speed = float((edges.size - 1) * pitch / (edges[-1] - edges[0]))
    if edges.size < 4:
        return None, speed, 0.0
    t = np.arange(len(pulse)) / sample_rate_hz
    scale = max(float(t[-1]), 1.0 / sample_rate_hz)
    coeffs = np.polyfit(edges / scale, np.arange(edges.size) * pitch, 3)
    angle = np.polyval(coeffs, t / scale)
    # d2(angle)/dt2 at the window's middle
    accel = float(np.polyval(np.polyder(coeffs, 2), 0.5)) / scale**2
    if not np.all(np.diff(angle) > 0.0):
        return None, speed, -accel
    return angle, speed, -accel


def order_amplitudes(
    signal: np.ndarray, angle: np.ndarray | None, sample_rate_hz: float
) -> np.ndarray:
    """Amplitude at each order of :data:`ORDERS` (the signal's unit), shape (orders,), on
    the drum angle (:func:`drum_angle`): the bin at the order of
    :func:`~brake_sim_ros.analysis.orders.order_spectrum`. Zeros without an angle or below
    :data:`MIN_REVOLUTIONS` revolutions."""
    out = np.zeros(len(ORDERS))
    if angle is None or angle[-1] - angle[0] < MIN_REVOLUTIONS * 2.0 * math.pi:
        return out
    x = np.asarray(signal, dtype=np.float64)
    finite = np.isfinite(x)
    if finite.sum() < 2:
        return out
    t = np.arange(x.size) / sample_rate_hz
    orders, amplitudes = order_spectrum(
        t[finite], angle[finite], x[finite], (0.0, float(t[-1]) + 1.0)
    )
    bins = np.rint(np.asarray(ORDERS) / orders[1]).astype(np.int64)  # orders[1]: resolution
    out[:] = np.abs(amplitudes[np.clip(bins, 0, orders.size - 1)])
    return out


def angle_fluctuation_orders(
    pulse: np.ndarray, sample_rate_hz: float, teeth: int = TONE_RING_TEETH
) -> np.ndarray:
    """Amplitude of the drum's angle fluctuation at each order of :data:`ORDERS`, rad,
    shape (orders,), from the tone ring alone.

    The pulse's edges, rising and falling, are half a tooth pitch apart in angle, so their
    times over whole revolutions are a signal sampled on the angle: their departure from a
    cubic in the edge count (the stop's smooth deceleration), times the mean speed, is the
    angle by which the drum leads or lags a smooth stop (a torque that varies with the
    drum's angle, as an out-of-round drum's, makes it). Its Hann-windowed DFT is read at
    each order (orders at or above the teeth read 0). The edge times are quantised to the
    sample period (up to ``speed / (2 sample rate)`` rad per edge: at 5120 Hz and 100 rad/s
    about 0.01 rad per edge, 3e-4 rad at an order over 0.5 s). Zeros below
    :data:`MIN_REVOLUTIONS` revolutions of edges.
    """
    out = np.zeros(len(ORDERS))
    edges = pulse_transitions(pulse, sample_rate_hz)
    per_revolution = 2 * teeth
    revolutions = (edges.size - 1) // per_revolution
    if revolutions < MIN_REVOLUTIONS:
        return out
    n = revolutions * per_revolution
    e = edges[: n + 1]
    i = np.arange(n + 1, dtype=np.float64)
    speed = 2.0 * math.pi * revolutions / float(e[-1] - e[0])
    lag = (e - np.polyval(np.polyfit(i, e, TREND_DEGREE), i))[:n] * speed  # rad, lags +
    w = np.hanning(n)
    spectrum = np.abs(np.fft.rfft(lag * w)) * (2.0 / w.sum())
    for j, k in enumerate(ORDERS):
        if k < teeth:
            out[j] = spectrum[k * revolutions]
    return out


def feature_names() -> tuple[str, ...]:
    """The names of :func:`window_features`'s values, in order."""
    names: list[str] = []
    for c in ACCEL_CHANNELS:
        names += [f"{c}:{s}" for s in STATISTICS]
        names += [f"{c}:band_{low:g}_{high:g}_hz" for low, high in BANDS_HZ]
        names += [f"{c}:order_{k}" for k in ORDERS]
    names += [f"{PULSE_CHANNEL}:angle_order_{k}" for k in ORDERS]
    names += ["drum_speed_rad_s", "drum_deceleration_rad_s2", "revolutions"]
    names += ["line_pressure_mean_bar", "line_pressure_std_bar", "deceleration_per_bar"]
    return tuple(names)


def window_features(window: Mapping[str, np.ndarray], sample_rate_hz: float) -> np.ndarray:
    """The features of one window (module docstring), shape (len(feature_names()),);
    NaN for a channel the window lacks or that is all NaN."""
    out: list[float] = []
    pulse = window.get(PULSE_CHANNEL)
    if pulse is not None:
        angle, speed, decel = drum_angle(pulse, sample_rate_hz)
    else:
        angle, speed, decel = None, math.nan, math.nan
    for c in ACCEL_CHANNELS:
        x = window.get(c)
        if x is None or not np.isfinite(x).any():
            out += [math.nan] * (len(STATISTICS) + len(BANDS_HZ) + len(ORDERS))
            continue
        out += [f(x) for f in STATISTICS.values()]
        out += band_rms(x, sample_rate_hz).tolist()
        out += order_amplitudes(x, angle, sample_rate_hz).tolist()
    if pulse is not None:
        out += angle_fluctuation_orders(pulse, sample_rate_hz).tolist()
    else:
        out += [math.nan] * len(ORDERS)
    revolutions = 0.0 if angle is None else float((angle[-1] - angle[0]) / (2.0 * math.pi))
    out += [speed, decel, revolutions if pulse is not None else math.nan]
    p = window.get(PRESSURE_CHANNEL)
    if p is None or not np.isfinite(p).any():
        out += [math.nan, math.nan, math.nan]
    else:
        mean = float(np.nanmean(p))
        out += [mean, float(np.nanstd(p)), decel / max(mean, MIN_PRESSURE_BAR)]
    return np.asarray(out, dtype=np.float64)
