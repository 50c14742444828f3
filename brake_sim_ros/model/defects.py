"""Defects: deviations of the shoes, the drum and the hydraulic line from the symmetric,
round, healthy brake."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.actuation import shoe_gain
from brake_sim_ros.model.catalogue import (
    DEFAULT_FLAT_WIDTH_DEG,  # noqa: F401 (re-exported: the flat's default width)
    DEFAULT_PULSATION_HZ,  # noqa: F401 (re-exported)
    DRUM_KIND,
    KIND_BY_NAME,
    KINDS,
    LINE,
    LOCATIONS,
    MAX_FLAT_WIDTH_DEG,  # noqa: F401 (re-exported)
    MAX_PULSATION_HZ,  # noqa: F401 (re-exported)
    ActiveDefect,
    DefectKind,
    Growth,
    kinds_at,
    label_column,
)
from brake_sim_ros.model.defect_fields import FieldSet as _FieldSet
from brake_sim_ros.model.defect_fields import present_values, tied_value

# Most harmonics one drum carries: the packed parameter vector has this many slots.
from brake_sim_ros.model.layout import MAX_DRUM_HARMONICS


class ShoeDefect(_FieldSet):
    """Defects of one shoe: a value for each catalogue field a shoe takes (its kinds'
    keys and attributes, :func:`.catalogue.fields_at`; the meaning, unit and range of
    each are the kind's entry, ``brake-sim defects``). The defaults are a healthy shoe,
    e.g. ``ShoeDefect(actuation_lag_ms=80.0)``.

    The physics of the built-in kinds: a pivot moved outward (``pivot_radius_change_pct``)
    keeps the shoe on its piston at the tip, so the shoe turns about its tip and then on
    the pin at its new place (:func:`brake_sim_ros.model.placement.place_shoe`); the
    actuation force is multiplied by ``2 share (1 + gain change/100)``
    (``actuation.shoe_gain``); a friction change scales the lining's coefficient
    ``mu (1 + pct/100)``; delay, lag and pulsation act on the commanded actuation history
    (the scenario's, or the node's live commands, which the stepper keeps as a history,
    ``solvers.fixed_step.CommandHistory``): ``tau F' + F = F_commanded`` for a lag,
    ``F (1 + a sin(2 pi f t))`` for a pulsation; a weak return spring past the stop's
    margin (``actuation.spring_release``: preload 60 N against a residual line force of
    20 N, so past 67 %) lets the residual pressure press the shoe on the drum without
    actuation: drag (on the service brake the spring itself is weakened, preload and rate
    times ``1 - pct/100``: :mod:`brake_sim_ros.model.service`); a worn lining's surface
    moves in by the wear, so the running clearance grows on the study brake (no adjuster);
    on the service brake its self-adjuster has taken the wear present at the start up in
    whole steps, and takes a wear that grows up at each application
    (:mod:`brake_sim_ros.model.ratchet`), but for what a seized adjuster failed to take up
    (``adjuster_seized_mm``, nothing within the run: :mod:`brake_sim_ros.model.adjuster`).
    """

    @classmethod
    def from_severities(cls, severities: dict[str, float]) -> ShoeDefect:
        """The shoe carrying these catalogue severities (absent kinds healthy; a present
        kind's attributes at their :attr:`DefectField.present_default`): the inverse of
        :meth:`severities`."""
        values: dict[str, float] = {}
        for kind in kinds_at(cls._LOCATION):
            severity = severities.get(kind.name, 0.0)
            if severity:
                values.update(present_values(kind, severity))
        return cls(**values)

    @property
    def actuation_gain(self) -> float:
        """Multiplier on this shoe's actuation force, ``2 share (1 + gain change/100)``."""
        return float(shoe_gain.py_func(self.actuation_share, self.actuation_gain_change_pct))

    def _shaping(self, effects: tuple[str, ...]) -> bool:
        return any(self.severity_of(k) for k in kinds_at(self._LOCATION) if k.actuation in effects)

    @property
    def actuation_shaped(self) -> bool:
        """The shoe's commanded actuation history is reshaped (delayed, lagged or
        pulsating: a kind whose ``actuation`` is ``history``)."""
        return self._shaping(("history",))

    @property
    def force_shaped(self) -> bool:
        """The force that reaches the shoe takes the kernel's shaped path: a reshaped
        history or a weak return spring (any kind with an ``actuation`` effect)."""
        return self._shaping(("history", "release"))


# Largest order of a drum-radius harmonic (cycles per revolution): the service range of
# drum waviness reaches 20-50 per revolution (``TESTBED.md``).
MAX_DRUM_ORDER = 50
# Service figures, for the documentation of the range (``TESTBED.md``): drum runout of
# 50-150 um in service, about 50 um a common service limit, judder from 10-20 um.
SERVICE_RUNOUT_UM = 150.0


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


class DrumDefect(_FieldSet):
    """Out-of-roundness and waviness of the drum. The default is a round drum.

    The drum's radius at the angle ``psi`` measured in the drum's own frame (the polar
    angle in the backing plate of a point on the drum's surface minus the drum angle
    ``drum_angle_rad``, counter-clockwise) is

        r(psi) = R0 + sum_k a_k cos(k psi + phi_k)

    with ``R0`` the nominal drum radius. As the drum turns at ``f_rot`` revolutions per
    second, a harmonic of order ``k`` passes a shoe ``k f_rot`` times a second.

    Limits (each refused with a one-line error): orders 1 to :data:`MAX_DRUM_ORDER`, each at
    most once, at most :data:`MAX_DRUM_HARMONICS` harmonics; finite amplitudes >= 0 and
    phases; the surface slope ``sum_k k a_k / R0`` at most :data:`.contact.MAX_DRUM_SLOPE`; and the
    peak runout ``sum_k a_k`` below the gap between each resting shoe and the round drum
    (the running clearance: 3.63 mm on the study brake, 0.3 mm on the service brake;
    checked where the brake is assembled, :func:`brake_sim_ros.model.assembly.pack`): a
    drum out of round by more would touch the retracted shoes every revolution, a
    permanent contact. Service drums run out by
    50-150 um, about 50 um is a common service limit, and judder starts from 10-20 um
    (``TESTBED.md``); order 2 (ovality) dominates.

    A local flat (or the edge of a crack) lowers the radius in a short window: by
    ``d (1 + cos(pi x / w)) / 2`` for ``|x| < w``, ``x = psi - c`` (wrapped to [-pi, pi)),
    ``c`` the flat's centre and ``w`` half its width (:func:`brake_sim_ros.model.contact.
    drum_radius`); its slope is continuous and at most ``pi d / (2 w)``, refused at assembly
    above :data:`.contact.MAX_DRUM_SLOPE` of ``R0``. A flat only lowers the surface: it never
    touches a retracted shoe. Once per revolution it passes each shoe.

    Built as ``DrumDefect(harmonics, **fields)``: the radius harmonics (in any order;
    empty for a round drum) and the catalogue's drum fields (:func:`.catalogue.fields_at`
    ``("drum")``): the flat's depth ``d`` (``flat_depth_um``, um; 0: none), its centre
    ``c`` in the drum's frame (``flat_centre_deg``) and whole width ``2 w``
    (``flat_width_deg``, deg).
    """

    _LOCATION = "drum"
    _WHAT = "drum"

    def __init__(self, harmonics: tuple[DrumHarmonic, ...] = (), **values: float) -> None:
        if not isinstance(harmonics, tuple) or not all(
            isinstance(h, DrumHarmonic) for h in harmonics
        ):
            raise ParameterError(
                f"drum harmonics={harmonics!r} is invalid: allowed a tuple of DrumHarmonic"
            )
        if len(harmonics) > MAX_DRUM_HARMONICS:
            raise ParameterError(
                f"drum harmonics: {len(harmonics)} given: allowed at most {MAX_DRUM_HARMONICS}"
            )
        orders = [h.order for h in harmonics]
        if len(set(orders)) != len(orders):
            raise ParameterError(f"drum harmonic orders {orders}: allowed each order at most once")
        object.__setattr__(self, "harmonics", harmonics)
        super().__init__(**values)

    def _extra(self) -> dict[str, object]:
        return {"harmonics": self.harmonics}

    def severity_of(self, kind: DefectKind) -> float:
        """The severity of ``kind`` on the drum: the harmonics' peak runout for a drum out
        of round (a table), else its key's value."""
        if kind.name == DRUM_KIND:
            return self.peak_runout_um
        return super().severity_of(kind)

    def attributes_of(self, kind: DefectKind) -> tuple[tuple[str, float], ...]:
        """``kind``'s attributes (a drum out of round: each harmonic's, :meth:`attributes`)."""
        if kind.name == DRUM_KIND:
            return self.attributes()
        return super().attributes_of(kind)

    @classmethod
    def from_orders(cls, *orders: tuple[int, float, float]) -> DrumDefect:
        """A drum from ``(order, amplitude_um, phase_deg)`` triples."""
        return cls(tuple(DrumHarmonic(k, a, ph) for k, a, ph in orders))

    def flat_slope(self, drum_radius_m: float) -> float:
        """Largest surface slope of the flat ``|dr/dpsi| / R0``: ``pi d / (2 w R0)``, rad."""
        half = math.radians(0.5 * self.flat_width_deg)
        return math.pi * self.flat_depth_um * 1e-6 / (2.0 * half * drum_radius_m)

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


class LineDefect(_FieldSet):
    """Defects of the service brake's hydraulic circuit (catalogue location ``line``,
    :mod:`.line_kinds`): the catalogue's line fields (:func:`.catalogue.fields_at`
    ``("line")``), e.g. ``LineDefect(air_in_line_ml=1.0)``, ``LineDefect(line_leak_pct=20.0)``.
    The default is a sound, bled line. The study brake has no circuit and refuses any
    (:func:`.catalogue.refuse_without_circuit`)."""

    _LOCATION = LINE
    _WHAT = "line"


def _attribute(name: str, unit: str) -> str:
    """An attribute name ending in ``unit`` (``%`` as ``pct``; none for a ratio)."""
    suffix = {"%": "pct", "1": ""}.get(unit, unit)
    return f"{name}_{suffix}" if suffix else name


@dataclass(frozen=True)
class Defects:
    """Defects of both shoes, of the drum and of the hydraulic line (``line``: the service
    brake's circuit), in any combination, and when each appears.

    The shoe, drum and line fields hold each defect's final severity; ``growth`` holds, for
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
    line: LineDefect = field(default_factory=LineDefect)

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
            entry_kind = KIND_BY_NAME[kind]
            key = (kind, loc)
            tied = (kind, "right" if loc == "left" else "left")
            if key in seen or (entry_kind.tied and tied in seen):
                raise ParameterError(
                    f"defect growth of {kind} at {loc} given twice: allowed one entry per"
                    " defect"
                    + (
                        f" (the other shoe's {entry_kind.scenario_key} mirrors it)"
                        if entry_kind.tied
                        else ""
                    )
                )
            seen.add(key)
            where = f"{loc} {entry_kind.scenario_key} "
            if growth.law not in entry_kind.laws:
                takes = [k.scenario_key for k in KINDS if growth.law in k.laws]
                raise ParameterError(
                    f"defect {where}growth {growth.law!r} is invalid: allowed only for"
                    f" {', '.join(takes)} (the laws {list(entry_kind.laws)} for this key)"
                )
            if growth.is_static:
                continue
            if entry_kind.initial_condition:
                raise ParameterError(
                    f"defect {where}onset {growth.onset_s:g} s, growth {growth.law!r} is"
                    " invalid: allowed only a step at 0 s (an initial condition of the run:"
                    " it acts through the state at t = 0)"
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
        return all(getattr(self, loc).is_healthy for loc in LOCATIONS)

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
            if k == kind and KIND_BY_NAME[kind].tied and loc != location:
                return dataclasses.replace(growth, start=-growth.start)
        return Growth()

    def _by_location(self) -> dict[str, dict[str, float]]:
        return {loc: getattr(self, loc).severities() for loc in LOCATIONS}

    def _attributes(self, kind: str, location: str, fraction: float) -> tuple:
        """Attributes of a defect in force: a drum's harmonics (amplitudes at ``fraction``
        of the final ones); a defect that changes in time adds its final severity (and an
        exponential its start)."""
        entry = KIND_BY_NAME[kind]
        attributes = []
        for name, value in getattr(self, location).attributes_of(entry):
            scaled = value * fraction if kind == DRUM_KIND and "amplitude" in name else value
            attributes.append((name, scaled))
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
        entry = KIND_BY_NAME[kind]
        if location == "drum":
            return cls(drum=DrumDefect(**present_values(entry, severity)))
        if location == LINE:
            return cls(line=LineDefect(**present_values(entry, severity)))
        shoes = {side: ShoeDefect() for side in ("left", "right")}
        shoes[location] = ShoeDefect.from_severities({kind: severity})
        if entry.tied:  # the other shoe mirrors it (the shares sum to 1)
            other = "right" if location == "left" else "left"
            shoes[other] = ShoeDefect(**tied_value(entry, shoes[location]))
        return cls(**shoes)

    def labels(self) -> list[str]:
        """One readable line per defect in force (:attr:`.catalogue.ActiveDefect.label`)."""
        return [d.label for d in self.active()]
