"""Defects: deviations of the shoes and the drum from the symmetric, round brake."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.actuation import shoe_gain
from brake_sim_ros.model.catalogue import (
    DRUM_KIND,
    FLAT_KIND,
    KIND_BY_NAME,
    KINDS,
    WEAR_KIND,
    ActiveDefect,
    Growth,
    label_column,
)

# Most harmonics one drum carries: the packed parameter vector has this many slots.
from brake_sim_ros.model.layout import MAX_DRUM_HARMONICS

# Highest pulsation frequency of an actuation, Hz: a hydraulic line's pressure pulsation
# (a pump, ABS modulation) stays far below the contact's kHz dynamics.
MAX_PULSATION_HZ = 1000.0
# The frequency Defects.single gives a pulsation (a severity sweep), Hz: about the ABS
# modulation rate of a wheel (10-20 Hz).
DEFAULT_PULSATION_HZ = 15.0


def _finite(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


@dataclass(frozen=True)
class ShoeDefect:
    """Defects of one shoe. The defaults are a healthy shoe.

    Attributes:
        pivot_radius_change_pct: change of the pivot's distance from the drum centre, in
            percent of the nominal radius. Positive moves the pin radially outward, closer
            to the drum. The shoe stays on its piston at the tip: the pin carries the heel
            across the tip-pin line, so the shoe turns about its tip (outward for a pin
            moved outward, inward for one moved inward), and the shoe then turns on the pin
            at its new place (see :func:`brake_sim_ros.model.assembly.place_shoe`).
        initial_angle_deg: the shoe's starting angle about its pivot, degrees. Negative
            tilts the shoe toward the drum centre, away from the drum.
        actuation_share: this shoe's share of the total actuation force (0.5 healthy).
            The shoe's actuation force is multiplied by ``2 * actuation_share``.
        friction_change_pct: change of this shoe's lining friction coefficient, percent of
            the nominal one (fade when hot, contamination by oil or water: negative; both
            can halve it, ``TESTBED.md``). The shoe's coefficient is ``mu (1 + pct/100)``.
        actuation_gain_change_pct: change of the force the shoe's wheel cylinder delivers
            for the commanded one, percent (low line pressure: negative); the shoe's
            force is multiplied by ``2 share (1 + pct/100)`` (``actuation.shoe_gain``).
        actuation_delay_ms: dead time of the shoe's actuation, ms: it follows the
            commanded history this late.
        actuation_lag_ms: time constant of a first-order lag of the shoe's actuation, ms
            (a slow rise: ``tau F' + F = F_commanded``).
        actuation_pulsation_pct: amplitude of a pulsation of the shoe's actuation force,
            percent of it (``F (1 + a sin(2 pi f t))``), at ``actuation_pulsation_hz``.
        actuation_pulsation_hz: the pulsation's frequency, Hz (> 0 with a pulsation).
        return_spring_weakening_pct: preload the shoe's return spring has lost, percent
            (100: broken). Past the stop's margin (``actuation.spring_release``: preload
            60 N against a residual line force of 20 N, so past 67 %) the residual pressure
            presses the shoe on the drum without actuation: drag.
        lining_wear_mm: lining thickness lost, mm (0 to 5, the thickness of a new lining,
            catalogue.LINING_THICKNESS_MM). The lining's
            surface, an arc about the shoe's lining centre, moves in by as much: the running
            clearance grows by the wear and the shoe turns further before it touches (an
            adjuster that takes up wear is not modelled: a brake between adjustments). The
            contact length of the model's line contact is the lining's width along the drum
            axis, which wear does not change.

    Delay, lag and pulsation act on the commanded actuation history: the scenario's, or
    the node's live actuation commands (``~/actuation``), which the stepper keeps as a
    history for a delayed or lagging shoe (``solvers.fixed_step.CommandHistory``).
    """

    pivot_radius_change_pct: float = 0.0
    initial_angle_deg: float = 0.0
    actuation_share: float = 0.5
    friction_change_pct: float = 0.0
    actuation_gain_change_pct: float = 0.0
    actuation_delay_ms: float = 0.0
    actuation_lag_ms: float = 0.0
    actuation_pulsation_pct: float = 0.0
    actuation_pulsation_hz: float = 0.0
    return_spring_weakening_pct: float = 0.0
    lining_wear_mm: float = 0.0

    def __post_init__(self) -> None:
        for name in (
            "pivot_radius_change_pct",
            "initial_angle_deg",
            "actuation_share",
            "friction_change_pct",
            "actuation_gain_change_pct",
            "actuation_delay_ms",
            "actuation_lag_ms",
            "actuation_pulsation_pct",
            "actuation_pulsation_hz",
            "return_spring_weakening_pct",
            "lining_wear_mm",
        ):
            value = getattr(self, name)
            if not isinstance(value, int | float) or not math.isfinite(value):
                raise ParameterError(f"defect {name}={value!r} is invalid: allowed a finite number")
        for kind, severity in self.severities().items():
            KIND_BY_NAME[kind].check(severity)
        hz = self.actuation_pulsation_hz
        if not 0.0 <= hz <= MAX_PULSATION_HZ or (self.actuation_pulsation_pct and hz == 0.0):
            raise ParameterError(
                f"defect actuation_pulsation_hz={hz:g} is invalid: allowed > 0 to"
                f" {MAX_PULSATION_HZ:g} Hz with a pulsation (0 without one)"
            )

    def severities(self) -> dict[str, float]:
        """The severity of each catalogue kind a shoe can carry (0: absent), in the kind's
        unit (:mod:`.catalogue`)."""
        return {
            "pivot_radius_change": float(self.pivot_radius_change_pct),
            "initial_angle": float(self.initial_angle_deg),
            "actuation_share_change": float(self.actuation_share) - 0.5,
            "friction_change": float(self.friction_change_pct),
            "actuation_gain_change": float(self.actuation_gain_change_pct),
            "actuation_delay": float(self.actuation_delay_ms),
            "actuation_lag": float(self.actuation_lag_ms),
            "actuation_pulsation": float(self.actuation_pulsation_pct),
            "return_spring_weakening": float(self.return_spring_weakening_pct),
            WEAR_KIND: float(self.lining_wear_mm),
        }

    @classmethod
    def from_severities(cls, severities: dict[str, float]) -> ShoeDefect:
        """The shoe carrying these catalogue severities (absent kinds healthy): the
        inverse of :meth:`severities`."""
        return cls(
            pivot_radius_change_pct=severities.get("pivot_radius_change", 0.0),
            initial_angle_deg=severities.get("initial_angle", 0.0),
            actuation_share=0.5 + severities.get("actuation_share_change", 0.0),
            friction_change_pct=severities.get("friction_change", 0.0),
            actuation_gain_change_pct=severities.get("actuation_gain_change", 0.0),
            actuation_delay_ms=severities.get("actuation_delay", 0.0),
            actuation_lag_ms=severities.get("actuation_lag", 0.0),
            actuation_pulsation_pct=severities.get("actuation_pulsation", 0.0),
            return_spring_weakening_pct=severities.get("return_spring_weakening", 0.0),
            lining_wear_mm=severities.get(WEAR_KIND, 0.0),
            actuation_pulsation_hz=(
                DEFAULT_PULSATION_HZ if severities.get("actuation_pulsation") else 0.0
            ),
        )

    @property
    def is_healthy(self) -> bool:
        return not any(self.severities().values())

    @property
    def actuation_gain(self) -> float:
        """Multiplier on this shoe's actuation force, ``2 share (1 + gain change/100)``."""
        return float(shoe_gain.py_func(self.actuation_share, self.actuation_gain_change_pct))

    @property
    def actuation_shaped(self) -> bool:
        """The shoe's actuation is delayed, lagged or pulsating."""
        return bool(
            self.actuation_delay_ms or self.actuation_lag_ms or self.actuation_pulsation_pct
        )


# Largest order of a drum-radius harmonic (cycles per revolution): the service range of
# drum waviness reaches 20-50 per revolution (``TESTBED.md``).
MAX_DRUM_ORDER = 50
# Largest surface slope of the drum, ``sum_k k a_k / R0`` (rad): the contact geometry tilts
# the normal by the local slope at one contact point, a small-slope model; 0.05 (a tilt of
# 2.9 deg) is far above service runouts (150 um of order 2 on a 180 mm drum: 0.0017).
MAX_DRUM_SLOPE = 0.05
# Service figures, for the documentation of the range (``TESTBED.md``): drum runout of
# 50-150 um in service, about 50 um a common service limit, judder from 10-20 um.
SERVICE_RUNOUT_UM = 150.0
# The width a flat gets when a scenario names none (and in a severity sweep), deg: about
# 16 mm of arc on a 180 mm drum, a short window as a crack's edge or a local flat is.
DEFAULT_FLAT_WIDTH_DEG = 5.0
# Widest flat, deg: a wider dip is a low lobe, a harmonic (drum_out_of_round).
MAX_FLAT_WIDTH_DEG = 90.0


@dataclass(frozen=True)
class DrumHarmonic:
    """One harmonic of the drum's radius.

    Attributes:
        order: cycles per revolution ``k``, an integer 1 to :data:`MAX_DRUM_ORDER`
            (1: an eccentric drum, 2: ovality, 3: a trilobe).
        amplitude_um: ``a_k``, micrometres (>= 0): the radius deviates by up to this much.
        phase_deg: ``phi_k``, degrees: the harmonic is ``a_k cos(k psi + phi_k)`` with
            ``psi`` the angle in the drum's own frame (below).
    """

    order: int
    amplitude_um: float
    phase_deg: float = 0.0

    def __post_init__(self) -> None:
        if isinstance(self.order, bool) or not isinstance(self.order, int):
            raise ParameterError(
                f"drum harmonic order={self.order!r} is invalid: allowed an integer 1 to"
                f" {MAX_DRUM_ORDER}"
            )
        if not 1 <= self.order <= MAX_DRUM_ORDER:
            raise ParameterError(
                f"drum harmonic order={self.order} is invalid: allowed an integer 1 to"
                f" {MAX_DRUM_ORDER}"
            )
        for name in ("amplitude_um", "phase_deg"):
            value = getattr(self, name)
            if (
                isinstance(value, bool)
                or not isinstance(value, int | float)
                or not math.isfinite(value)
            ):
                raise ParameterError(
                    f"drum harmonic {name}={value!r} is invalid: allowed a finite number"
                )
        if self.amplitude_um < 0.0:
            raise ParameterError(
                f"drum harmonic amplitude_um={self.amplitude_um} is invalid: allowed >= 0 um"
                " (a negative amplitude is a phase of 180 deg)"
            )


@dataclass(frozen=True)
class DrumDefect:
    """Out-of-roundness and waviness of the drum. The default is a round drum.

    The drum's radius at the angle ``psi`` measured in the drum's own frame (the polar
    angle in the backing plate of a point on the drum's surface minus the drum angle
    ``drum_angle_rad``, counter-clockwise) is

        r(psi) = R0 + sum_k a_k cos(k psi + phi_k)

    with ``R0`` the nominal drum radius. As the drum turns at ``f_rot`` revolutions per
    second, a harmonic of order ``k`` passes a shoe ``k f_rot`` times a second.

    Limits (each refused with a one-line error): orders 1 to :data:`MAX_DRUM_ORDER`, each at
    most once, at most :data:`MAX_DRUM_HARMONICS` harmonics; finite amplitudes >= 0 and
    phases; the surface slope ``sum_k k a_k / R0`` at most :data:`MAX_DRUM_SLOPE`; and the
    peak runout ``sum_k a_k`` below the gap between each resting shoe and the round drum
    (the running clearance, 3.5 mm nominal; checked where the brake is assembled,
    :func:`brake_sim_ros.model.assembly.pack`): a drum out of round by more would touch the
    retracted shoes every revolution, a permanent contact. Service drums run out by
    50-150 um, about 50 um is a common service limit, and judder starts from 10-20 um
    (``TESTBED.md``); order 2 (ovality) dominates.

    A local flat (or the edge of a crack) lowers the radius in a short window: by
    ``d (1 + cos(pi x / w)) / 2`` for ``|x| < w``, ``x = psi - c`` (wrapped to [-pi, pi)),
    ``c`` the flat's centre and ``w`` half its width (:func:`brake_sim_ros.model.contact.
    drum_radius`); its slope is continuous and at most ``pi d / (2 w)``, refused at assembly
    above :data:`MAX_DRUM_SLOPE` of ``R0``. A flat only lowers the surface: it never
    touches a retracted shoe. Once per revolution it passes each shoe.

    Attributes:
        harmonics: the radius harmonics, in any order; empty for a round drum.
        flat_depth_um: the flat's depth ``d``, um (0: none; the catalogue's ``drum_flat``).
        flat_centre_deg: its centre ``c`` in the drum's frame, deg.
        flat_width_deg: its whole width ``2 w``, deg (> 0 to 90).
    """

    harmonics: tuple[DrumHarmonic, ...] = ()
    flat_depth_um: float = 0.0
    flat_centre_deg: float = 0.0
    flat_width_deg: float = DEFAULT_FLAT_WIDTH_DEG

    def __post_init__(self) -> None:
        if not isinstance(self.harmonics, tuple) or not all(
            isinstance(h, DrumHarmonic) for h in self.harmonics
        ):
            raise ParameterError(
                f"drum harmonics={self.harmonics!r} is invalid: allowed a tuple of DrumHarmonic"
            )
        if len(self.harmonics) > MAX_DRUM_HARMONICS:
            raise ParameterError(
                f"drum harmonics: {len(self.harmonics)} given: allowed at most {MAX_DRUM_HARMONICS}"
            )
        orders = [h.order for h in self.harmonics]
        if len(set(orders)) != len(orders):
            raise ParameterError(f"drum harmonic orders {orders}: allowed each order at most once")
        for name in ("flat_depth_um", "flat_centre_deg", "flat_width_deg"):
            value = getattr(self, name)
            if not _finite(value):
                raise ParameterError(f"drum {name}={value!r} is invalid: allowed a finite number")
        KIND_BY_NAME[FLAT_KIND].check(self.flat_depth_um)
        if not 0.0 < self.flat_width_deg <= MAX_FLAT_WIDTH_DEG:
            raise ParameterError(
                f"drum flat_width_deg={self.flat_width_deg:g} is invalid: allowed > 0 to"
                f" {MAX_FLAT_WIDTH_DEG:g} deg (a wider dip is a harmonic, drum_out_of_round)"
            )
        if not -360.0 <= self.flat_centre_deg <= 360.0:
            raise ParameterError(
                f"drum flat_centre_deg={self.flat_centre_deg:g} is invalid: allowed -360 to 360 deg"
            )

    @classmethod
    def from_orders(cls, *orders: tuple[int, float, float]) -> DrumDefect:
        """A drum from ``(order, amplitude_um, phase_deg)`` triples."""
        return cls(tuple(DrumHarmonic(k, a, ph) for k, a, ph in orders))

    @property
    def is_healthy(self) -> bool:
        """Round: no harmonic of non-zero amplitude, no flat."""
        return all(h.amplitude_um == 0.0 for h in self.harmonics) and not self.flat_depth_um

    def flat_slope(self, drum_radius_m: float) -> float:
        """Largest surface slope of the flat ``|dr/dpsi| / R0``: ``pi d / (2 w R0)``, rad."""
        half = math.radians(0.5 * self.flat_width_deg)
        return math.pi * self.flat_depth_um * 1e-6 / (2.0 * half * drum_radius_m)

    def flat_attributes(self) -> tuple[tuple[str, float], ...]:
        """The flat's centre and width (deg), by name, for the ground truth."""
        return (
            ("centre_deg", float(self.flat_centre_deg)),
            ("width_deg", float(self.flat_width_deg)),
        )

    @property
    def peak_runout_um(self) -> float:
        """``sum_k a_k``, um: the largest the radius can deviate from ``R0`` for any phases."""
        return float(sum(h.amplitude_um for h in self.harmonics))

    def slope(self, drum_radius_m: float) -> float:
        """Bound on the surface slope ``|dr/dpsi| / R0``: ``sum_k k a_k / R0``, rad."""
        return float(sum(h.order * h.amplitude_um for h in self.harmonics)) * 1e-6 / drum_radius_m

    def attributes(self) -> tuple[tuple[str, float], ...]:
        """Each harmonic's amplitude (um) and phase (deg), by name, for the ground truth."""
        out: list[tuple[str, float]] = []
        for h in sorted(self.harmonics, key=lambda h: h.order):
            if h.amplitude_um:
                out += [
                    (f"order_{h.order}_amplitude_um", float(h.amplitude_um)),
                    (f"order_{h.order}_phase_deg", float(h.phase_deg)),
                ]
        return tuple(out)


# Kinds that act only through the state at t = 0 (the shoe's starting angle): they can
# only be present from the start, a step at 0 s.
INITIAL_CONDITION_KINDS = frozenset({"initial_angle"})
# Kinds whose two shoes are tied (the shares sum to 1): a growth on one shoe moves the
# other's severity by the opposite amount, so only one shoe states it.
TIED_KINDS = frozenset({"actuation_share_change"})


def _attribute(name: str, unit: str) -> str:
    """An attribute name ending in ``unit`` (``%`` as ``pct``; none for a ratio)."""
    suffix = {"%": "pct", "1": ""}.get(unit, unit)
    return f"{name}_{suffix}" if suffix else name


@dataclass(frozen=True)
class Defects:
    """Defects of both shoes and of the drum, in any combination, and when each appears.

    The shoe and drum fields hold each defect's final severity; ``growth`` holds, for
    defects that do not simply exist from the start, their onset and growth law
    (:class:`~brake_sim_ros.model.catalogue.Growth`) as ``(kind, location, growth)``
    entries. A defect without an entry is a step at 0 s (present from the start); an
    entry that is a step at 0 s is dropped, so both spell the same brake. Refused, in one
    line: an entry for an absent defect or an unknown kind or location, two entries for
    one defect, growth of a starting angle (an initial condition), entries on both shoes
    for a tied kind (the actuation shares: the other shoe mirrors the one stated), and
    an exponential start that cannot grow to the final severity.
    """

    left: ShoeDefect = field(default_factory=ShoeDefect)
    right: ShoeDefect = field(default_factory=ShoeDefect)
    drum: DrumDefect = field(default_factory=DrumDefect)
    growth: tuple[tuple[str, str, Growth], ...] = ()

    def __post_init__(self) -> None:
        total = self.left.actuation_share + self.right.actuation_share
        if abs(total - 1.0) > 1e-9:
            raise ParameterError(
                f"defect actuation shares left={self.left.actuation_share} +"
                f" right={self.right.actuation_share} = {total}: allowed a sum of exactly 1"
                " (the total actuation force is kept)"
            )
        if not isinstance(self.growth, tuple):
            raise ParameterError(
                f"defect growth {self.growth!r} is invalid: allowed a tuple of (kind,"
                " location, Growth)"
            )
        at = self._by_location()
        seen: set[tuple[str, str]] = set()
        kept = []
        for entry in self.growth:
            if not (isinstance(entry, tuple) and len(entry) == 3 and isinstance(entry[2], Growth)):
                raise ParameterError(
                    f"defect growth entry {entry!r} is invalid: allowed (kind, location, Growth)"
                )
            kind, loc, growth = entry
            if kind not in KIND_BY_NAME or loc not in KIND_BY_NAME[kind].locations:
                raise ParameterError(
                    f"defect growth of {kind!r} at {loc!r} is invalid: allowed a catalogue kind"
                    " at one of its locations (brake-sim defects)"
                )
            key = (kind, loc)
            tied = (kind, "right" if loc == "left" else "left")
            if key in seen or (kind in TIED_KINDS and tied in seen):
                raise ParameterError(
                    f"defect growth of {kind} at {loc} given twice: allowed one entry per"
                    " defect"
                    + (" (the other shoe's share mirrors it)" if kind in TIED_KINDS else "")
                )
            seen.add(key)
            where = f"{loc} {KIND_BY_NAME[kind].scenario_key} "
            if growth.law == "friction_work" and kind != WEAR_KIND:
                raise ParameterError(
                    f"defect {where}growth 'friction_work' is invalid: allowed only for"
                    f" {KIND_BY_NAME[WEAR_KIND].scenario_key} (a lining wears with its friction"
                    " work)"
                )
            if growth.is_static:
                continue
            if kind in INITIAL_CONDITION_KINDS:
                raise ParameterError(
                    f"defect {where}onset {growth.onset_s:g} s, growth {growth.law!r} is"
                    " invalid: allowed only a step at 0 s (the starting angle is an initial"
                    " condition of the run)"
                )
            final = at[loc][kind]
            if final == 0.0:
                raise ParameterError(
                    f"defect {where}has an onset and growth but no final severity: allowed"
                    " only for a defect that is present (give its value)"
                )
            growth.check(final, where, KIND_BY_NAME[kind].healthy_value)
            kept.append(entry)
        object.__setattr__(self, "growth", tuple(kept))

    @property
    def is_healthy(self) -> bool:
        return self.left.is_healthy and self.right.is_healthy and self.drum.is_healthy

    @property
    def is_static(self) -> bool:
        """Every defect is present from the start (a step at 0 s): nothing changes in time."""
        return not self.growth

    @property
    def kinds(self) -> tuple[str, ...]:
        """Catalogue kinds of the defects present, in catalogue order."""
        return tuple(dict.fromkeys(d.kind for d in self.active()))

    @property
    def wearing_with_work(self) -> tuple[str, ...]:
        """Shoes whose lining wears with their friction work (growth ``friction_work``):
        their wear is the compiled model's state (layout ``N_STATE_WEAR``)."""
        return tuple(loc for kind, loc, g in self.growth if not g.follows_time)

    @property
    def growing_kinds(self) -> tuple[str, ...]:
        """Catalogue kinds of the defects that change during the run, in catalogue order."""
        names = {kind for kind, _loc, _g in self.growth}
        return tuple(k.name for k in KINDS if k.name in names)

    def growth_of(self, kind: str, location: str) -> Growth:
        """Onset and law of the defect ``kind`` at ``location`` (a step at 0 s if none is
        stated; a tied kind's other shoe mirrors the stated one's start)."""
        for k, loc, growth in self.growth:
            if k == kind and loc == location:
                return growth
            if k == kind and kind in TIED_KINDS and loc != location:
                return dataclasses.replace(growth, start=-growth.start)
        return Growth()

    def _by_location(self) -> dict[str, dict[str, float]]:
        return {
            "left": self.left.severities(),
            "right": self.right.severities(),
            "drum": {
                DRUM_KIND: self.drum.peak_runout_um,
                FLAT_KIND: float(self.drum.flat_depth_um),
            },
        }

    def _attributes(self, kind: str, location: str, fraction: float) -> tuple:
        """Attributes of a defect in force: a drum's harmonics (amplitudes at ``fraction``
        of the final ones); a defect that changes in time adds its final severity (and an
        exponential its start)."""
        attributes = []
        if kind == DRUM_KIND:
            for name, value in self.drum.attributes():
                attributes.append((name, value * fraction if "amplitude" in name else value))
        if kind == FLAT_KIND:
            attributes.extend(self.drum.flat_attributes())
        if kind == "actuation_pulsation":
            shoe = getattr(self, location)
            attributes.append(("frequency_hz", float(shoe.actuation_pulsation_hz)))
        growth = self.growth_of(kind, location)
        if not growth.is_static:
            unit = KIND_BY_NAME[kind].unit
            attributes.append(
                (_attribute("final_severity", unit), self._by_location()[location][kind])
            )
            if growth.law == "exponential":
                attributes.append((_attribute("start_severity", unit), growth.start))
        return tuple(attributes)

    def _worn(
        self, location: str, final: float, wear_m: dict[str, np.ndarray] | None, time_s: object
    ) -> np.ndarray:
        """A friction-work wear at ``location`` (mm) from the model's recorded wear
        ``wear_m[location]`` (m, the ``*_lining_wear_m`` columns), the final wear where the
        model holds it there."""
        if wear_m is None or location not in wear_m:
            raise ValueError(
                f"the {location} lining's wear at {time_s} s follows its friction work: it is"
                " read from the model's recorded wear (pass wear_m, the *_lining_wear_m columns)"
            )
        worn = np.asarray(wear_m[location], dtype=np.float64)
        return np.where(worn >= final * 1e-3, final, worn * 1e3)

    def active(
        self, time_s: float | None = None, wear_m: dict[str, float] | None = None
    ) -> tuple[ActiveDefect, ...]:
        """The ground truth: every defect in force, in catalogue order (kind, then
        location), each with its onset and growth law (:mod:`.catalogue`).

        Args:
            time_s: simulated time, s: each severity is the one at that time and a defect
                before its onset is not listed. None: the final severities of every
                defect the run has (the description of the run, e.g. a file's metadata).
            wear_m: with ``time_s``, the lining wear the model recorded at that time, m, by
                shoe (its ``*_lining_wear_m`` columns): the severity of a wear that grows
                with friction work (required for one).
        """
        at = self._by_location()
        out = []
        for kind in KINDS:
            for loc in kind.locations:
                final = at[loc][kind.name]
                if final == 0.0:
                    continue
                growth = self.growth_of(kind.name, loc)
                if time_s is None:
                    now = final
                elif growth.follows_time:
                    now = growth.severity(time_s, final)
                else:
                    now = float(self._worn(loc, final, wear_m, time_s))
                if now == 0.0:
                    continue
                out.append(
                    ActiveDefect(
                        kind.name,
                        loc,
                        now,
                        kind.unit,
                        onset_s=float(growth.onset_s),
                        growth=growth.law,
                        growth_rate=growth.rate,
                        attributes=self._attributes(kind.name, loc, now / final),
                    )
                )
        return tuple(out)

    def severities(
        self, time_s: float | None = None, wear_m: dict[str, float] | None = None
    ) -> dict[str, float]:
        """The per-sample label columns (:func:`.catalogue.label_columns`) and their value:
        each kind's severity at each location at ``time_s`` (s; None: the final ones), 0
        where absent; ``wear_m`` as for :meth:`active`."""
        at = self._by_location()
        out = {}
        for k in KINDS:
            for loc in k.locations:
                final = at[loc][k.name]
                if time_s is not None and final != 0.0:
                    growth = self.growth_of(k.name, loc)
                    if growth.follows_time:
                        final = growth.severity(time_s, final)
                    else:
                        final = float(self._worn(loc, final, wear_m, time_s))
                out[label_column(k, loc)] = final
        return out

    def label_series(
        self, times_s: np.ndarray, wear_m: dict[str, np.ndarray] | None = None
    ) -> dict[str, np.ndarray]:
        """The label columns at each of ``times_s`` (s, shape (n,)): each kind's severity at
        each location (:func:`.catalogue.severity_at`), 0 where absent. A lining wear that
        grows with friction work is the model's own, read from ``wear_m`` (m, by shoe,
        each shape (n,): the samples' ``*_lining_wear_m`` columns; required for one)."""
        times = np.asarray(times_s, dtype=np.float64)
        at = self._by_location()
        out = {}
        for k in KINDS:
            for loc in k.locations:
                final = at[loc][k.name]
                growth = self.growth_of(k.name, loc)
                if final == 0.0:
                    out[label_column(k, loc)] = np.zeros(times.shape[0])
                elif growth.follows_time:
                    out[label_column(k, loc)] = growth.series(times, final)
                else:
                    out[label_column(k, loc)] = self._worn(loc, final, wear_m, "the samples'")
        return out

    def change_times(self) -> tuple[float, ...]:
        """Simulated times (s) at which a defect appears or stops changing, ascending."""
        at = self._by_location()
        times = set()
        for kind, loc, growth in self.growth:
            times.add(growth.onset_s)
            times.add(growth.reached_s(at[loc][kind]))
        return tuple(sorted(times))

    @classmethod
    def single(cls, kind: str, location: str, severity: float) -> Defects:
        """A brake with one catalogue defect of ``severity`` at ``location`` (the other
        shoe's actuation share follows a share change: the shares sum to 1; a drum out of
        round is an ovality, order 2 at phase 0, of that peak runout; a drum flat is
        :data:`DEFAULT_FLAT_WIDTH_DEG` wide, centred at 0 deg)."""
        if location not in KIND_BY_NAME[kind].locations:
            raise ParameterError(
                f"defect {kind} at {location!r} is invalid: allowed at"
                f" {list(KIND_BY_NAME[kind].locations)}"
            )
        if kind == DRUM_KIND:
            return cls(drum=DrumDefect.from_orders((2, severity, 0.0)))
        if kind == FLAT_KIND:
            return cls(drum=DrumDefect(flat_depth_um=severity))
        shoes = {side: ShoeDefect() for side in ("left", "right")}
        shoes[location] = ShoeDefect.from_severities({kind: severity})
        if kind == "actuation_share_change":
            other = "right" if location == "left" else "left"
            shoes[other] = ShoeDefect(actuation_share=1.0 - shoes[location].actuation_share)
        return cls(**shoes)

    def labels(self) -> list[str]:
        """One readable line per defect in force (:attr:`.catalogue.ActiveDefect.label`)."""
        return [d.label for d in self.active()]
