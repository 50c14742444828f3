"""The defect catalogue: every kind of brake defect the model knows, as data, and the
ground truth of a brake's condition as a list of active defects.

Each kind has a name, the locations it can sit at, a severity in a physical unit (0 for a
healthy brake, so a label column reads 0 where the defect is absent), the range the model
accepts and a line on what it changes. The ground truth of a brake (``Defects.active``,
:mod:`.defects`) is a list of :class:`ActiveDefect`, one per kind and location in force,
so a consumer (the ``DefectState`` message, Parquet label columns, file metadata, a
scorer) needs no change when a kind is added here.

Time: every defect has an onset and a growth law (:class:`Growth`); its severity at a
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

Pure data and logic, plus the compiled severity law: no files.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.compiled import JIT
from brake_sim_ros.model.layout import SIDES

# how a severity evolves after its onset; the index is the law's id in the compiled model
GROWTH_LAWS: tuple[str, ...] = ("step", "linear", "exponential", "friction_work")
LAW_STEP, LAW_LINEAR, LAW_EXPONENTIAL, LAW_FRICTION_WORK = 0, 1, 2, 3
DRUM_KIND = "drum_out_of_round"
WEAR_KIND = "lining_wear"
FLAT_KIND = "drum_flat"
# Thickness of a new lining, mm: passenger-car drum-brake shoe linings are typically 4-6
# mm thick new (a typical figure, not from TESTBED.md); a wear beyond it is refused.
LINING_THICKNESS_MM = 5.0
# Thickness left at the usual replacement limit, mm: 1.6 mm (1/16 in) above the shoe
# table for bonded linings (a typical workshop figure), so 3.4 mm of wear.
LINING_MINIMUM_MM = 1.6
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


@njit(**JIT)
def severity_series(times, law, onset_s, rate, start, final):
    """:func:`severity_at` at each of ``times`` (s, shape (n,)), in the kind's unit."""
    out = np.empty(times.shape[0])
    for i in range(times.shape[0]):
        out[i] = severity_at(times[i], law, onset_s, rate, start, final)
    return out


def _finite(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


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
        needs = {
            "linear": "rate_per_s",
            "exponential": "doubling_time_s",
            "friction_work": "wear_rate_mm_per_mj",
        }.get(self.law)
        needed_by = {
            "rate_per_s": "linear",
            "doubling_time_s": "exponential",
            "start": "exponential",
            "wear_rate_mm_per_mj": "friction_work",
        }
        for name, law in needed_by.items():
            value = getattr(self, name)
            if law != self.law and value != 0.0:
                raise ParameterError(
                    f"defect {name}={value:g} with growth {self.law!r} is invalid: allowed"
                    f" only with growth {law!r}"
                )
        if needs is not None and not getattr(self, needs) > 0.0:
            raise ParameterError(
                f"defect {needs}={getattr(self, needs):g} with growth {self.law!r} is invalid:"
                " allowed a number > 0"
            )
        if needs == "wear_rate_mm_per_mj" and self.wear_rate_mm_per_mj > MAX_WEAR_RATE_MM_PER_MJ:
            raise ParameterError(
                f"defect wear_rate_mm_per_mj={self.wear_rate_mm_per_mj:g} is invalid: allowed"
                f" > 0 to {MAX_WEAR_RATE_MM_PER_MJ:g} mm/MJ"
            )
        if needs == "doubling_time_s" and self.doubling_time_s > MAX_GROWTH_TIME_S:
            raise ParameterError(
                f"defect doubling_time_s={self.doubling_time_s:g} is invalid: allowed up to"
                f" {MAX_GROWTH_TIME_S:g} s"
            )

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


@dataclass(frozen=True)
class DefectKind:
    """One kind of defect.

    Attributes:
        name: the kind's name in ground truth, label columns and the CLI.
        locations: where it can sit (a shoe: ``left``/``right``; ``drum``).
        unit: the severity's unit.
        minimum, maximum: the severities the model accepts, in ``unit`` (the limit's
            reason is in ``limit``).
        limit: why the range stops there.
        description: what it changes in the brake, and the sign convention.
        scenario_key: the key that sets it in a scenario's ``[defects.<location>]`` and
            the node parameter ``<location>_<key>``.
        healthy_value: what that key reads on a healthy brake (the value set is
            ``healthy_value + severity``).
        service_limit: a size seen in service (shared figures: the study's cases), in
            ``unit``, signed: where a severity sweep ends.
    """

    name: str
    locations: tuple[str, ...]
    unit: str
    minimum: float
    maximum: float
    limit: str
    description: str
    scenario_key: str
    service_limit: float
    healthy_value: float = 0.0

    def check(self, severity: float, where: str = "") -> None:
        """Refuse a severity outside the range, in one line naming the limit."""
        if not self.minimum <= severity <= self.maximum:
            h = self.healthy_value
            raise ParameterError(
                f"defect {where}{self.scenario_key}={h + severity:g} is invalid: allowed"
                f" {h + self.minimum:g} to {h + self.maximum:g} ({self.limit})"
            )


KINDS: tuple[DefectKind, ...] = (
    DefectKind(
        name="pivot_radius_change",
        locations=SIDES,
        unit="%",
        minimum=-20.0,
        maximum=20.0,
        limit="the range the shoe's assembly on its abutments is built and tested for",
        description=(
            "the anchor pin's distance from the drum centre, in % of the nominal radius;"
            " positive moves the pin outward, toward the drum"
        ),
        scenario_key="pivot_radius_change_pct",
        service_limit=3.0,  # the study's cases: +-3 %
    ),
    DefectKind(
        name="initial_angle",
        locations=SIDES,
        unit="deg",
        minimum=-10.0,
        maximum=10.0,
        limit="the range the shoe's assembly on its abutments is built and tested for",
        description=(
            "the shoe's assembled angle about its pivot; negative tilts it toward the"
            " drum centre, away from the drum"
        ),
        scenario_key="initial_angle_deg",
        service_limit=-2.0,  # the study's cases: -2 deg
    ),
    DefectKind(
        name="actuation_share_change",
        locations=SIDES,
        unit="1",
        minimum=-0.5,
        maximum=0.5,
        limit="a shoe's share of the total force lies between 0 and 1",
        description=(
            "the shoe's share of the total actuation force minus the healthy 0.5 (a"
            " scenario sets the share itself: 0.55 is +0.05); the shares sum to 1"
        ),
        scenario_key="actuation_share",
        service_limit=0.05,  # the study's cases: +-10 % of the share (0.55)
        healthy_value=0.5,
    ),
    DefectKind(
        name="friction_change",
        locations=SIDES,
        unit="%",
        minimum=-90.0,
        maximum=50.0,
        limit=(
            "a lining keeps some friction; +50 % of the nominal 0.285 is 0.43, the top of"
            " drum-brake linings; a shoe that would self-lock (mu h >= d) is refused at"
            " assembly"
        ),
        description=(
            "change of the shoe's lining friction coefficient, in % of the nominal one;"
            " negative for fade (hot) or contamination (oil, water)"
        ),
        scenario_key="friction_change_pct",
        service_limit=-50.0,  # fade and contamination can halve mu (TESTBED.md)
    ),
    DefectKind(
        name="actuation_gain_change",
        locations=SIDES,
        unit="%",
        minimum=-90.0,
        maximum=50.0,
        limit="a wheel cylinder that still pushes, up to half again the commanded force",
        description=(
            "change of the force the shoe's wheel cylinder delivers for the commanded one,"
            " in %; negative for low line pressure"
        ),
        scenario_key="actuation_gain_change_pct",
        service_limit=-27.0,  # graded efficiency down to 73 % (UCI hydraulic rig, TESTBED.md)
    ),
    DefectKind(
        name="actuation_delay",
        locations=SIDES,
        unit="ms",
        minimum=0.0,
        maximum=500.0,
        limit="beyond 0.5 s a brake no longer answers within the 0.36 s expected of a car",
        description="dead time between the commanded actuation and the shoe's, in ms",
        scenario_key="actuation_delay_ms",
        service_limit=100.0,  # a whole healthy hydraulic rise (under 0.1 s, TESTBED.md)
    ),
    DefectKind(
        name="actuation_lag",
        locations=SIDES,
        unit="ms",
        minimum=0.0,
        maximum=500.0,
        limit="beyond 0.5 s a brake no longer answers within the 0.36 s expected of a car",
        description=(
            "time constant of a first-order lag of the shoe's actuation (a slow rise), in ms"
        ),
        scenario_key="actuation_lag_ms",
        service_limit=120.0,  # 95 % of a step in 0.36 s, a car's response (TESTBED.md)
    ),
    DefectKind(
        name="actuation_pulsation",
        locations=SIDES,
        unit="%",
        minimum=0.0,
        maximum=100.0,
        limit="a pulsating force still only pushes",
        description=(
            "amplitude of a pulsation of the shoe's actuation force, in % of it, at the"
            " frequency actuation_pulsation_hz (attribute frequency_hz)"
        ),
        scenario_key="actuation_pulsation_pct",
        service_limit=20.0,  # no service figure in TESTBED.md: a clearly felt pulsation
    ),
    DefectKind(
        name="return_spring_weakening",
        locations=SIDES,
        unit="%",
        minimum=0.0,
        maximum=100.0,
        limit="a spring loses at most all of its preload (100 %: broken)",
        description=(
            "preload the shoe's return spring has lost, in %; past 67 % (the stop's margin"
            " over the residual line pressure) the shoe drags on the drum without actuation"
        ),
        scenario_key="return_spring_weakening_pct",
        service_limit=100.0,  # a broken spring
    ),
    DefectKind(
        name=DRUM_KIND,
        locations=("drum",),
        unit="um",
        minimum=0.0,
        maximum=3500.0,
        limit=(
            "the peak runout stays below the gap between the resting shoes and the drum"
            " (the running clearance, 3.5 mm nominal, checked at assembly) and the surface"
            " slope sum k a_k / R0 at most 0.05"
        ),
        description=(
            "drum radius harmonics r(psi) = R0 + sum a_k cos(k psi + phi_k), psi in the"
            " drum's frame; the severity is the peak runout sum a_k, each harmonic's"
            " amplitude and phase are attributes (order_<k>_amplitude_um,"
            " order_<k>_phase_deg)"
        ),
        scenario_key="harmonics",
        service_limit=150.0,  # service runouts 50-150 um (about 50 um a common limit)
    ),
    DefectKind(
        name=WEAR_KIND,
        locations=SIDES,
        unit="mm",
        minimum=0.0,
        maximum=LINING_THICKNESS_MM,
        limit=f"a new lining is {LINING_THICKNESS_MM:g} mm thick (a typical passenger-car figure)",
        description=(
            "lining thickness the shoe has lost, in mm: the lining surface moves in, the gap"
            " to the drum grows by as much (the shoe turns further before it touches);"
            " growth friction_work wears it with the shoe's own friction work"
        ),
        scenario_key="lining_wear_mm",
        # replaced at 1.6 mm left of 5 mm (1/16 in above the table: a typical workshop limit)
        service_limit=LINING_THICKNESS_MM - LINING_MINIMUM_MM,
    ),
    DefectKind(
        name=FLAT_KIND,
        locations=("drum",),
        unit="um",
        minimum=0.0,
        maximum=1000.0,
        limit=(
            "a flat deeper than 1 mm is a broken drum; the flat's slope pi d / (2 w R0) at"
            " most 0.05 (w its half width), as the harmonics'"
        ),
        description=(
            "a local flat or crack edge of the drum: its radius dips by up to the depth over"
            " an angular window (attributes centre_deg, in the drum's frame, and width_deg),"
            " d (1 + cos(pi x / w)) / 2 within x = psi - centre of |x| < w = width / 2; the"
            " severity is the depth"
        ),
        scenario_key="flat_depth_um",
        service_limit=100.0,  # no service figure in TESTBED.md: twice the 50 um runout limit
    ),
)
KIND_BY_NAME: dict[str, DefectKind] = {k.name: k for k in KINDS}


@dataclass(frozen=True)
class ActiveDefect:
    """One defect in force.

    Attributes:
        kind: a name from :data:`KINDS`.
        location: where it sits (one of the kind's locations).
        severity: its size now (or, describing a whole run, its final size), in the
            kind's unit (non-zero).
        unit: the kind's unit.
        onset_s: simulated time it started, s.
        growth: how it evolves after the onset (:data:`GROWTH_LAWS`).
        growth_rate: the law's rate (:attr:`Growth.rate`): linear the kind's unit per
            second, exponential 1/s (``ln 2 / doubling time``), step 0.
        attributes: what else describes it, by name (each name ends in its unit), e.g.
            the amplitude and phase of each harmonic of a drum out of round; a defect
            that changes in time adds ``final_severity_<unit>`` (and an exponential
            ``start_severity_<unit>``; ``%`` spelled ``pct``, none for a ratio).
    """

    kind: str
    location: str
    severity: float
    unit: str
    onset_s: float = 0.0
    growth: str = "step"
    growth_rate: float = 0.0
    attributes: tuple[tuple[str, float], ...] = ()

    @property
    def label(self) -> str:
        """One readable line, e.g. ``left pivot_radius_change +3 %``."""
        unit = "" if self.unit == "1" else f" {self.unit}"
        return f"{self.location} {self.kind} {self.severity:+g}{unit}"

    def as_dict(self) -> dict[str, object]:
        return {
            "kind": self.kind,
            "location": self.location,
            "severity": self.severity,
            "unit": self.unit,
            "onset_s": self.onset_s,
            "growth": self.growth,
            "growth_rate": self.growth_rate,
            "attributes": dict(self.attributes),
        }


def label_column(kind: DefectKind, location: str) -> str:
    """The per-sample label column of a kind at a location: its severity, 0 if absent."""
    return f"defect:{kind.name}:{location} [{kind.unit}]"


def label_columns() -> tuple[str, ...]:
    """Every label column, in catalogue order."""
    return tuple(label_column(k, loc) for k in KINDS for loc in k.locations)
