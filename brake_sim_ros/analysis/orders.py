"""Order analysis: a signal's spectrum over drum angle (cycles per revolution).

A drum that decelerates sweeps every frequency fixed to its angle (``k f_rot`` for a
defect of order ``k``); resampled on uniform drum angles, the same component is a line at
order ``k``. This is what order tracking with the tone ring does on a vehicle (README,
"Measured signals"); here the exact drum angle of the model is used.
"""

from __future__ import annotations

import math

import numpy as np

SAMPLES_PER_REVOLUTION = 256  # angle resolution of the resampled signal (orders up to 128)
TREND_DEGREE = 3  # polynomial removed before the transform: the slow trend of a stop


def order_spectrum(
    time_s: np.ndarray,
    drum_angle_rad: np.ndarray,
    signal: np.ndarray,
    window_s: tuple[float, float],
) -> tuple[np.ndarray, np.ndarray]:
    """Complex amplitude spectrum of ``signal`` over the drum's orders.

    Args:
        time_s, drum_angle_rad, signal: samples (n,), s, rad (increasing within the
            window: a turning drum), and any unit.
        window_s: the time window analysed, s; a whole number of revolutions from its start
            is used.

    Returns:
        (orders, amplitudes): orders in cycles per revolution (resolution 1 / revolutions);
        complex amplitudes in the signal's unit (a Hann-windowed DFT scaled so that a sine
        of amplitude ``A`` at an order on the grid reads ``|A|``), after removing a cubic
        trend.

    Raises:
        ValueError: the drum turns less than one revolution in the window.
    """
    m = (time_s >= window_s[0]) & (time_s < window_s[1])
    angle = drum_angle_rad[m]
    if angle.size < 2:
        raise ValueError(f"order spectrum: no samples in the window {window_s} s")
    revolutions = math.floor((angle[-1] - angle[0]) / (2.0 * math.pi))
    if revolutions < 1:
        raise ValueError(
            f"order spectrum: the drum turns {(angle[-1] - angle[0]) / (2 * math.pi):.2f}"
            f" revolutions in {window_s} s: allowed at least one"
        )
    n = revolutions * SAMPLES_PER_REVOLUTION
    grid = angle[0] + np.arange(n) * (2.0 * math.pi / SAMPLES_PER_REVOLUTION)
    x = np.interp(grid, angle, signal[m])
    i = np.arange(n, dtype=float)
    x = x - np.polyval(np.polyfit(i, x, TREND_DEGREE), i)
    w = np.hanning(n)
    return np.arange(n // 2 + 1) / revolutions, np.fft.rfft(x * w) * (2.0 / w.sum())


def order_amplitude(
    time_s: np.ndarray,
    drum_angle_rad: np.ndarray,
    signal: np.ndarray,
    order: float,
    window_s: tuple[float, float],
) -> float:
    """Amplitude of ``signal`` at ``order`` (its unit): the largest bin within half an order
    of it (:func:`order_spectrum`)."""
    orders, amplitudes = order_spectrum(time_s, drum_angle_rad, signal, window_s)
    near = np.abs(orders - order) <= 0.5
    return float(np.abs(amplitudes[near]).max())
