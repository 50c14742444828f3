"""Growth laws: when a defect starts and how its severity evolves, the one definition
that the compiled model, the scenario loader, the labels and the ground truth all use.

Every defect has an onset and a growth law (:class:`Growth`); its severity at a
simulated time is :func:`severity_at`, the one definition that the compiled model
(:mod:`.growth`, each physics step), the label columns and the ground-truth messages all
evaluate. The scenario gives the final severity (the kind's key) and the law:

* ``step``: 0 before the onset, the final severity from it on (the default, onset 0 s:
  a defect present from the start);
* ``linear``: from 0 at the onset, ``rate_per_s`` (the kind's unit per second, > 0) toward
  the final severity, held there once reached: ``s(t) = sign(s_f) min(r (t - t_0), |s_f|)``;
* ``exponential``: from ``start`` (same sign as the final severity, smaller) at the onset,
  doubling every ``doubling_time_s``, held at the final severity once reached:
  ``s(t) = start 2^((t - t_0) / T_d)`` until ``|s| >= |s_f|``;
* ``friction_work`` (lining wear only): Archard-like, the wear grows with the shoe's own
  friction work from the onset, ``ds/dt = k_w P_f`` (``P_f`` the shoe's friction power,
  ``k_w`` = ``wear_rate_mm_per_mj``, mm per MJ), held at the final severity once reached.
  It depends on the motion, not on time alone: the compiled model integrates it with the
  state (layout ``Y_*_WEAR``) and records it (``*_lining_wear_m`` columns), and the labels
  and ground truth read it from there (:meth:`.defects.Defects.label_series`).

The parameters each law takes (:data:`LAW_PARAMETERS`) are written here once: the
checks of :class:`Growth` and the keys a scenario's defect table takes are read from them.

Pure logic plus the compiled severity law: no files.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.compiled import JIT, JIT_ALLOCATING

# how a severity evolves after its onset; the index is the law's id in the compiled model
GROWTH_LAWS: tuple[str, ...] = ("step", "linear", "exponential", "friction_work")
LAW_STEP, LAW_LINEAR, LAW_EXPONENTIAL, LAW_FRICTION_WORK = 0, 1, 2, 3
# Default wear per friction work, mm/MJ: a volumetric specific wear of about 0.3 cm^3/MJ
# (organic friction materials in dynamometer wear tests run about 0.1-0.5 cm^3/MJ: an
# order of magnitude, not a measured figure for this lining) spread over the lining's
# rubbing area, 80 deg of arc at 176.5 mm times 45 mm wide = 111 cm^2: 0.027 mm/MJ. A stop
# from 100 km/h puts about 55 kJ into the leading shoe: 1.5 um of wear.
DEFAULT_WEAR_RATE_MM_PER_MJ = 0.027
# Largest wear rate a scenario may state, mm/MJ: an accelerated wear test that wears a
# lining through in one stop is within it.
MAX_WEAR_RATE_MM_PER_MJ = 1000.0
# Longest onset and doubling time a scenario may state, s: a day of simulated braking
MAX_GROWTH_TIME_S = 86_400.0


@njit(**JIT)
def severity_at(t, law, onset_s, rate, start, final):
    """Severity at simulated time ``t`` (s) of a defect of final severity ``final``.

    Args:
        t: simulated time, s.
        law: the law's id (``LAW_*``, the index in :data:`GROWTH_LAWS`).
        onset_s: the onset, s: 0 before it.
        rate: linear: the rate, the kind's unit per second (> 0); exponential: the relative
            rate ``ln 2 / doubling time``, 1/s; step, friction work: unused.
        start: exponential: the severity at the onset (same sign as ``final``); else unused.
        final: the final severity, in the kind's unit.

    Returns:
        The severity, in the kind's unit; ``final`` once it is reached (never beyond). A
        friction-work law does not follow time: 0 before the onset, ``final`` after it (the
        bound; its value is the compiled model's, :mod:`.growth`).
    """
    if t < onset_s:
        return 0.0
    if law == LAW_LINEAR:
        grown = rate * (t - onset_s)
        if grown >= abs(final):
            return final
        return grown if final > 0.0 else -grown
    if law == LAW_EXPONENTIAL:
        grown = start * math.exp(rate * (t - onset_s))
        if abs(grown) >= abs(final):
            return final
        return grown
    return final


@njit(**JIT_ALLOCATING)
def severity_series(times, law, onset_s, rate, start, final):
    """:func:`severity_at` at each of ``times`` (s, shape (n,)), in the kind's unit."""
    out = np.empty(times.shape[0])
    for i in range(times.shape[0]):
        out[i] = severity_at(times[i], law, onset_s, rate, start, final)
    return out


def _finite(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


@dataclass(frozen=True)
class LawParameter:
    """A number one growth law takes (0, unused, with every other law).

    Attributes:
        name: the key, in a scenario's defect table and on :class:`Growth`.
        law: the law that takes it (one of :data:`GROWTH_LAWS`).
        what: what it is, with its unit, for messages and help.
        high: the largest value allowed (the smallest is > 0), or None for a severity
            (``start``: same sign as the final severity, checked by :meth:`Growth.check`).
        default: the value when a scenario does not state it, or None: required.
    """

    name: str
    law: str
    what: str
    high: float | None
    default: float | None = None

    def check(self, law: str, value: float) -> None:
        """Refuse ``value`` (this parameter of a :class:`Growth` of ``law``), one line."""
        if law != self.law:
            if value != 0.0:
                raise ParameterError(
                    f"defect {self.name}={value:g} with growth {law!r} is invalid: allowed"
                    f" only with growth {self.law!r}"
                )
            return
        if self.high is None:
            return
        if not value > 0.0:
            raise ParameterError(
                f"defect {self.name}={value:g} with growth {law!r} is invalid: allowed a number > 0"
            )
        if value > self.high:
            raise ParameterError(
                f"defect {self.name}={value:g} is invalid: allowed > 0 to {self.high:g}"
                f" ({self.what})"
            )


LAW_PARAMETERS: tuple[LawParameter, ...] = (
    LawParameter("rate_per_s", "linear", "the kind's unit per second", math.inf),
    LawParameter("doubling_time_s", "exponential", "s", MAX_GROWTH_TIME_S),
    LawParameter("start", "exponential", "a value of the key at the onset", None),
    LawParameter(
        "wear_rate_mm_per_mj",
        "friction_work",
        "mm of wear per MJ of the shoe's friction work",
        MAX_WEAR_RATE_MM_PER_MJ,
        DEFAULT_WEAR_RATE_MM_PER_MJ,
    ),
)
# every key of a scenario's growth statement, beside the final value
GROWTH_KEYS: tuple[str, ...] = ("onset_s", "growth", *(p.name for p in LAW_PARAMETERS))


@dataclass(frozen=True)
class Growth:
    """When a defect starts and how its severity grows (see the module doc for the laws).

    Attributes:
        onset_s: simulated time it starts, s (>= 0).
        law: one of :data:`GROWTH_LAWS`.
        rate_per_s: linear only: the kind's unit per second toward the final severity (> 0).
        doubling_time_s: exponential only: the time the severity takes to double, s (> 0).
        start: exponential only: the severity at the onset, in the kind's unit (same sign
            as the final severity, smaller in size).
        wear_rate_mm_per_mj: friction work only: ``k_w``, mm of lining wear per MJ of the
            shoe's friction work (> 0; scenarios default to
            :data:`DEFAULT_WEAR_RATE_MM_PER_MJ`).
    """

    onset_s: float = 0.0
    law: str = "step"
    rate_per_s: float = 0.0
    doubling_time_s: float = 0.0
    start: float = 0.0
    wear_rate_mm_per_mj: float = 0.0

    def __post_init__(self) -> None:
        if self.law not in GROWTH_LAWS:
            raise ParameterError(
                f"defect growth {self.law!r} is invalid: allowed one of {list(GROWTH_LAWS)}"
            )
        for name in ("onset_s", "rate_per_s", "doubling_time_s", "start", "wear_rate_mm_per_mj"):
            if not _finite(getattr(self, name)):
                raise ParameterError(
                    f"defect {name}={getattr(self, name)!r} is invalid: allowed a finite number"
                )
        if not 0.0 <= self.onset_s <= MAX_GROWTH_TIME_S:
            raise ParameterError(
                f"defect onset_s={self.onset_s:g} is invalid: allowed 0 to"
                f" {MAX_GROWTH_TIME_S:g} s (simulated time since the start of the run)"
            )
        for param in LAW_PARAMETERS:
            param.check(self.law, getattr(self, param.name))

    @property
    def is_static(self) -> bool:
        """A step at the start of the run: the defect is simply present."""
        return self.law == "step" and self.onset_s == 0.0

    @property
    def law_id(self) -> int:
        return GROWTH_LAWS.index(self.law)

    @property
    def follows_time(self) -> bool:
        """The severity is a function of time alone (every law but friction work)."""
        return self.law != "friction_work"

    @property
    def rate(self) -> float:
        """The law's rate as :func:`severity_at` takes it (and the ground truth's
        ``growth_rate``): linear unit/s, exponential 1/s (``ln 2 / doubling time``), friction
        work mm/MJ (``k_w``), step 0."""
        if self.law == "linear":
            return float(self.rate_per_s)
        if self.law == "exponential":
            return math.log(2.0) / self.doubling_time_s
        if self.law == "friction_work":
            return float(self.wear_rate_mm_per_mj)
        return 0.0

    def check(self, final: float, where: str = "", healthy: float = 0.0) -> None:
        """Refuse a law that cannot reach ``final`` (the final severity, kind's unit;
        ``healthy``: the healthy value of the key the message names)."""
        if self.law == "exponential" and not (
            self.start * final > 0.0 and abs(self.start) < abs(final)
        ):
            raise ParameterError(
                f"defect {where}start={healthy + self.start:g} is invalid: allowed a value"
                f" between the healthy {healthy:g} and the final {healthy + final:g}"
                " (exponential growth starts there at the onset)"
            )

    def severity(self, t: float, final: float) -> float:
        """Severity at simulated time ``t`` (s) toward ``final`` (:func:`severity_at`)."""
        return float(severity_at(float(t), self.law_id, self.onset_s, self.rate, self.start, final))

    def series(self, times_s: np.ndarray, final: float) -> np.ndarray:
        """Severity at each of ``times_s`` (s) toward ``final`` (:func:`severity_series`)."""
        times = np.ascontiguousarray(times_s, dtype=np.float64)
        return severity_series(times, self.law_id, self.onset_s, self.rate, self.start, final)

    def reached_s(self, final: float) -> float:
        """Simulated time the severity reaches ``final``, s (friction work: not known
        beforehand, ``inf``)."""
        if self.law == "friction_work":
            return math.inf
        if self.law == "linear":
            return self.onset_s + abs(final) / self.rate_per_s
        if self.law == "exponential":
            return self.onset_s + self.doubling_time_s * math.log2(abs(final / self.start))
        return self.onset_s
