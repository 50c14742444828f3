"""Transducers: the analog signal path of a sensor channel (noise, resonance, bandwidth,
anti-alias filter, range, ADC), as data, and the preset classes the sensor kinds offer
(:mod:`.sensor_kinds`; the figures: :mod:`.sensors`).

Pure: numpy and scipy only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from brake_sim_ros.errors import ParameterError

STANDARD_GRAVITY_M_S2 = 9.80665


def bad(channel: str, what: str, value: object, allowed: str) -> ParameterError:
    """The one-line refusal of a channel's setting."""
    return ParameterError(f"sensor {channel!r}: {what} = {value!r} is invalid: allowed {allowed}")


@dataclass(frozen=True)
class Transducer:
    """The signal path of an analog channel, in the channel's unit (m/s^2, N, bar).

    Attributes:
        name: the preset class it came from (informative).
        noise_density_per_sqrt_hz: input-referred white noise, channel unit / sqrt(Hz).
        bandwidth_hz: 3 dB frequency of a 2nd-order Butterworth low-pass, Hz (None: none).
        resonance_hz: mounted resonance, Hz (None: none).
        resonance_damping_ratio: its damping ratio (dimensionless).
        range_min, range_max: the output saturates outside, channel unit (+-inf: never).
        adc_bits: quantisation over the range (None: none; needs a finite range).
        antialias_fraction: the DAQ's anti-alias filter, a 4th-order Butterworth low-pass
            at this fraction of the channel's output rate (None: none).
    """

    name: str = "ideal"
    noise_density_per_sqrt_hz: float = 0.0
    bandwidth_hz: float | None = None
    resonance_hz: float | None = None
    resonance_damping_ratio: float = 0.05
    range_min: float = -math.inf
    range_max: float = math.inf
    adc_bits: int | None = None
    antialias_fraction: float | None = None

    def check(self, channel: str) -> None:
        if not (
            math.isfinite(self.noise_density_per_sqrt_hz) and self.noise_density_per_sqrt_hz >= 0
        ):
            raise bad(channel, "noise density", self.noise_density_per_sqrt_hz, "a number >= 0")
        for what in ("bandwidth_hz", "resonance_hz"):
            value = getattr(self, what)
            if value is not None and not (math.isfinite(value) and value > 0):
                raise bad(channel, what, value, "a frequency > 0 Hz, or none")
        if self.antialias_fraction is not None and not 0.0 < self.antialias_fraction < 0.5:
            raise bad(
                channel, "antialias_fraction", self.antialias_fraction, "> 0 and < 0.5, or none"
            )
        if not 0.0 < self.resonance_damping_ratio < 1.0:
            raise bad(
                channel, "resonance_damping_ratio", self.resonance_damping_ratio, "> 0 and < 1"
            )
        if not self.range_min < self.range_max or math.isnan(self.range_min):
            raise bad(channel, "range", (self.range_min, self.range_max), "min < max")
        if self.adc_bits is not None:
            if not 1 <= self.adc_bits <= 32:
                raise bad(channel, "adc_bits", self.adc_bits, "1 to 32 bits, or none")
            if not (math.isfinite(self.range_min) and math.isfinite(self.range_max)):
                raise bad(channel, "adc_bits", self.adc_bits, "none with an unbounded range")

    @property
    def adc_step(self) -> float:
        """The quantisation step, channel unit (0: no ADC)."""
        if self.adc_bits is None:
            return 0.0
        return (self.range_max - self.range_min) / 2.0**self.adc_bits

    def continuous(
        self, rate_hz: float, resonance_factor: float = 1.0
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
        """``(A, B, C, D)`` of resonance, low-pass and anti-alias filter (for an output
        rate ``rate_hz``), single input and output; None when the path has none.
        ``resonance_factor`` scales the resonance frequency (a loose mount). The
        resonance's states are physical (``[z, z']``, ``z'' = wr^2 (u - z) - 2 zeta wr z'``),
        so a loose mount can change its frequency with the state kept."""
        # scipy.signal costs about 1.5 s of CPU to import (it parses its docstrings): only
        # a process that builds a filtered channel pays it, not every process that loads
        # a scenario (the loader reaches this module through the fleet's sensor scatter)
        from scipy import signal

        stages = []
        if self.resonance_hz is not None:
            wr = 2.0 * math.pi * self.resonance_hz * resonance_factor
            zr = self.resonance_damping_ratio
            stages.append(
                (
                    np.array([[0.0, 1.0], [-(wr**2), -2.0 * zr * wr]]),
                    np.array([[0.0], [wr**2]]),
                    np.array([[1.0, 0.0]]),
                    np.zeros((1, 1)),
                )
            )
        if self.bandwidth_hz is not None:
            num, den = signal.butter(2, 2.0 * math.pi * self.bandwidth_hz, analog=True)
            stages.append(signal.tf2ss(num, den))
        if self.antialias_fraction is not None:
            cutoff = 2.0 * math.pi * self.antialias_fraction * rate_hz
            stages.append(signal.zpk2ss(*signal.butter(4, cutoff, analog=True, output="zpk")))
        if not stages:
            return None
        a, b, c, d = (np.atleast_2d(np.asarray(m, dtype=float)) for m in stages[0])
        for a2, b2, c2, d2 in stages[1:]:  # series: stage 2 driven by stage 1's output
            a2, b2, c2, d2 = (np.atleast_2d(np.asarray(m, dtype=float)) for m in (a2, b2, c2, d2))
            n1, n2 = a.shape[0], a2.shape[0]
            big = np.zeros((n1 + n2, n1 + n2))
            big[:n1, :n1] = a
            big[n1:, :n1] = b2 @ c
            big[n1:, n1:] = a2
            a, b, c, d = (
                big,
                np.vstack([b, b2 @ d]),
                np.hstack([d2 @ c, c2]),
                d2 @ d,
            )
        return a, b, c, d


def accel(
    name: str,
    noise_ug: float,
    bw: float | None,
    res: float | None,
    fs_g: float,
    bits: int,
    antialias: float | None,
) -> Transducer:
    return Transducer(
        name=name,
        noise_density_per_sqrt_hz=noise_ug * 1e-6 * STANDARD_GRAVITY_M_S2,
        bandwidth_hz=bw,
        resonance_hz=res,
        range_min=-fs_g * STANDARD_GRAVITY_M_S2,
        range_max=fs_g * STANDARD_GRAVITY_M_S2,
        adc_bits=bits,
        antialias_fraction=antialias,
    )


IDEAL = Transducer()
