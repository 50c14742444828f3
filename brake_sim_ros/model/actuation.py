"""Actuation force histories: piecewise-linear in time, one per shoe; and what an
actuation defect makes of them at the shoe (compiled: gain, delay, first-order lag,
pulsation)."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.compiled import JIT


@njit(inline="always", **JIT)
def pwl(t, ts, fs):
    """Piecewise-linear interpolation, held constant outside the knots."""
    n = ts.shape[0]
    if t <= ts[0]:
        return fs[0]
    if t >= ts[n - 1]:
        return fs[n - 1]
    lo = 0
    hi = n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if ts[mid] <= t:
            lo = mid
        else:
            hi = mid
    w = (t - ts[lo]) / (ts[hi] - ts[lo])
    return fs[lo] + w * (fs[hi] - fs[lo])


@njit(**JIT)
def shoe_gain(share, change_pct):
    """Multiplier on a shoe's commanded force: ``2 share (1 + change_pct / 100)`` (its
    share of the total, and a pressure loss, negative, or gain at its wheel cylinder)."""
    return 2.0 * share * (1.0 + change_pct / 100.0)


# The return spring (the model had none: its healthy brake is calibrated on the net force
# that moves a shoe off its stop). A drum brake's lines hold a residual pressure (a check
# valve keeps 0.5-1 bar to seal the cups): about RESIDUAL_FORCE_N on a 19 mm wheel
# cylinder; the return spring's preload, RETURN_SPRING_PRELOAD_N at the tip, holds the shoe
# on its stop against it with the margin between the two. The healthy model's actuation is
# the net force once the shoe has left the stop (cylinder minus spring), 0 on the stop.
RESIDUAL_FORCE_N = 20.0
RETURN_SPRING_PRELOAD_N = 60.0


@njit(inline="always", **JIT)
def spring_release(force, released, margin):
    """Actuation force at the tip (N) when the return spring has lost ``released`` N of its
    preload, for the healthy model's net force ``force`` (N): off its stop (``force > 0``)
    the shoe gets the lost preload on top; on its stop only what exceeds the stop's margin
    (``margin``: preload minus residual force, N) pushes it, so a spring weakened past
    the margin (or broken) presses the shoe on the drum without actuation: drag."""
    if force > 0.0:
        return force + released
    return released - margin if released > margin else 0.0


@njit(**JIT)
def shaped(t, ts, fs, delay_s, lag_s, amplitude, frequency_hz):
    """The force a shoe's wheel cylinder delivers at ``t`` (s) for the commanded
    piecewise-linear history (knots ``ts`` s, ``fs`` N), before the gain.

    The history is delayed by ``delay_s``, then passed through a first-order lag of time
    constant ``lag_s`` (``tau y' + y = u``, at rest on the first knot's force), then
    modulated by ``1 + amplitude sin(2 pi frequency_hz t)`` (``amplitude`` in [0, 1], so
    the force stays >= 0). The lag of a piecewise-linear input is exact: each change of
    slope ``db`` at a knot ``t_i`` adds ``-tau db (1 - exp(-(t - t_i) / tau))``.
    """
    td = t - delay_s
    u = pwl(td, ts, fs)
    if lag_s > 0.0:
        n = ts.shape[0]
        before = 0.0
        lagging = 0.0
        for i in range(n):
            if ts[i] >= td:
                break
            after = (fs[i + 1] - fs[i]) / (ts[i + 1] - ts[i]) if i + 1 < n else 0.0
            lagging += (after - before) * (1.0 - math.exp(-(td - ts[i]) / lag_s))
            before = after
        u -= lag_s * lagging
    if amplitude > 0.0:
        u *= 1.0 + amplitude * math.sin(2.0 * math.pi * frequency_hz * t)
    return u


MAX_ACTUATION_FORCE_N = 50_000.0


@dataclass(frozen=True)
class ForceProfile:
    """Piecewise-linear force history, held constant before the first and after the last knot.

    Attributes:
        times_s: knot times, s, strictly increasing.
        forces_n: force at each knot, N, >= 0 (a shoe is pushed, never pulled).
    """

    times_s: tuple[float, ...]
    forces_n: tuple[float, ...]

    def __post_init__(self) -> None:
        t, f = self.times_s, self.forces_n
        if len(t) == 0 or len(t) != len(f):
            raise ParameterError(
                f"force profile has {len(t)} times and {len(f)} forces: allowed equal, non-zero"
                " lengths"
            )
        for i, (ti, fi) in enumerate(zip(t, f, strict=True)):
            if not (math.isfinite(ti) and math.isfinite(fi)):
                raise ParameterError(f"force profile knot {i} ({ti}, {fi}): allowed finite values")
            if not 0.0 <= fi <= MAX_ACTUATION_FORCE_N:
                raise ParameterError(
                    f"force profile knot {i} force {fi} N: allowed 0 to {MAX_ACTUATION_FORCE_N} N"
                )
        if any(b <= a for a, b in itertools.pairwise(t)):
            raise ParameterError(f"force profile times {t}: allowed strictly increasing times")

    def __call__(self, time_s: float | np.ndarray) -> np.ndarray:
        return np.interp(time_s, self.times_s, self.forces_n)

    @property
    def peak_n(self) -> float:
        return max(self.forces_n)

    def scaled(self, factor: float) -> ForceProfile:
        return ForceProfile(self.times_s, tuple(f * factor for f in self.forces_n))

    @classmethod
    def constant(cls, force_n: float) -> ForceProfile:
        return cls((0.0,), (float(force_n),))

    @classmethod
    def ramp(cls, peak_n: float, start_s: float = 0.2, full_s: float = 0.7) -> ForceProfile:
        """The published history: zero until ``start_s``, linear to ``peak_n`` at ``full_s``."""
        if not full_s > start_s >= 0.0:
            raise ParameterError(
                f"ramp start {start_s} s, full {full_s} s: allowed 0 <= start < full"
            )
        return cls((0.0, start_s, full_s), (0.0, 0.0, float(peak_n)))


# Peak actuation force of the published braking event, N per shoe. Calibrated, with the
# friction coefficient, for the 6.6 s stop; a typical wheel-cylinder force for a car.
NOMINAL_PEAK_ACTUATION_N = 1300.0


@dataclass(frozen=True)
class Actuation:
    """Commanded actuation force of each shoe (before any actuation-share defect)."""

    left: ForceProfile
    right: ForceProfile

    @classmethod
    def published_ramp(cls, peak_n: float = NOMINAL_PEAK_ACTUATION_N) -> Actuation:
        ramp = ForceProfile.ramp(peak_n)
        return cls(ramp, ramp)

    def as_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(left times, left forces, right times, right forces) as float64 arrays."""
        return (
            np.asarray(self.left.times_s, float),
            np.asarray(self.left.forces_n, float),
            np.asarray(self.right.times_s, float),
            np.asarray(self.right.forces_n, float),
        )
