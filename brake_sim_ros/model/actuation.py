"""Actuation force histories: piecewise-linear in time, one per shoe."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from brake_sim_ros.errors import ParameterError

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
