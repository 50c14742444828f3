"""Defects: deviations of the shoes and the drum from the symmetric, round brake."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.catalogue import (
    DRUM_KIND,
    KIND_BY_NAME,
    KINDS,
    ActiveDefect,
    label_column,
)

# Most harmonics one drum carries: the packed parameter vector has this many slots.
from brake_sim_ros.model.layout import MAX_DRUM_HARMONICS


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
    """

    pivot_radius_change_pct: float = 0.0
    initial_angle_deg: float = 0.0
    actuation_share: float = 0.5

    def __post_init__(self) -> None:
        for name in ("pivot_radius_change_pct", "initial_angle_deg", "actuation_share"):
            value = getattr(self, name)
            if not isinstance(value, int | float) or not math.isfinite(value):
                raise ParameterError(f"defect {name}={value!r} is invalid: allowed a finite number")
        for kind, severity in self.severities().items():
            KIND_BY_NAME[kind].check(severity)

    def severities(self) -> dict[str, float]:
        """The severity of each catalogue kind a shoe can carry (0: absent), in the kind's
        unit (:mod:`.catalogue`)."""
        return {
            "pivot_radius_change": float(self.pivot_radius_change_pct),
            "initial_angle": float(self.initial_angle_deg),
            "actuation_share_change": float(self.actuation_share) - 0.5,
        }

    @classmethod
    def from_severities(cls, severities: dict[str, float]) -> ShoeDefect:
        """The shoe carrying these catalogue severities (absent kinds healthy): the
        inverse of :meth:`severities`."""
        return cls(
            pivot_radius_change_pct=severities.get("pivot_radius_change", 0.0),
            initial_angle_deg=severities.get("initial_angle", 0.0),
            actuation_share=0.5 + severities.get("actuation_share_change", 0.0),
        )

    @property
    def is_healthy(self) -> bool:
        return not any(self.severities().values())

    @property
    def actuation_gain(self) -> float:
        """Multiplier on this shoe's actuation force, ``2 * actuation_share``."""
        return 2.0 * self.actuation_share


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

    Attributes:
        harmonics: the radius harmonics, in any order; empty for a round drum.
    """

    harmonics: tuple[DrumHarmonic, ...] = ()

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

    @classmethod
    def from_orders(cls, *orders: tuple[int, float, float]) -> DrumDefect:
        """A drum from ``(order, amplitude_um, phase_deg)`` triples."""
        return cls(tuple(DrumHarmonic(k, a, ph) for k, a, ph in orders))

    @property
    def is_healthy(self) -> bool:
        """Round: no harmonic of non-zero amplitude."""
        return all(h.amplitude_um == 0.0 for h in self.harmonics)

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


@dataclass(frozen=True)
class Defects:
    """Defects of both shoes and of the drum, in any combination."""

    left: ShoeDefect = field(default_factory=ShoeDefect)
    right: ShoeDefect = field(default_factory=ShoeDefect)
    drum: DrumDefect = field(default_factory=DrumDefect)

    def __post_init__(self) -> None:
        total = self.left.actuation_share + self.right.actuation_share
        if abs(total - 1.0) > 1e-9:
            raise ParameterError(
                f"defect actuation shares left={self.left.actuation_share} +"
                f" right={self.right.actuation_share} = {total}: allowed a sum of exactly 1"
                " (the total actuation force is kept)"
            )

    @property
    def is_healthy(self) -> bool:
        return self.left.is_healthy and self.right.is_healthy and self.drum.is_healthy

    @property
    def kinds(self) -> tuple[str, ...]:
        """Catalogue kinds of the defects present, in catalogue order."""
        return tuple(dict.fromkeys(d.kind for d in self.active()))

    def _by_location(self) -> dict[str, dict[str, float]]:
        return {
            "left": self.left.severities(),
            "right": self.right.severities(),
            "drum": {DRUM_KIND: self.drum.peak_runout_um},
        }

    def active(self) -> tuple[ActiveDefect, ...]:
        """The ground truth: every defect in force, in catalogue order (kind, then
        location); each a step at the start of the run. A drum out of round carries each
        harmonic's amplitude and phase as attributes."""
        at = self._by_location()
        return tuple(
            ActiveDefect(
                kind.name,
                loc,
                at[loc][kind.name],
                kind.unit,
                attributes=self.drum.attributes() if kind.name == DRUM_KIND else (),
            )
            for kind in KINDS
            for loc in kind.locations
            if at[loc][kind.name] != 0.0
        )

    def severities(self) -> dict[str, float]:
        """The per-sample label columns (:func:`.catalogue.label_columns`) and their value:
        each kind's severity at each location, 0 where absent."""
        at = self._by_location()
        return {label_column(k, loc): at[loc][k.name] for k in KINDS for loc in k.locations}

    @classmethod
    def single(cls, kind: str, location: str, severity: float) -> Defects:
        """A brake with one catalogue defect of ``severity`` at ``location`` (the other
        shoe's actuation share follows a share change: the shares sum to 1; a drum out of
        round is an ovality, order 2 at phase 0, of that peak runout)."""
        if location not in KIND_BY_NAME[kind].locations:
            raise ParameterError(
                f"defect {kind} at {location!r} is invalid: allowed at"
                f" {list(KIND_BY_NAME[kind].locations)}"
            )
        if kind == DRUM_KIND:
            return cls(drum=DrumDefect.from_orders((2, severity, 0.0)))
        shoes = {side: ShoeDefect() for side in ("left", "right")}
        shoes[location] = ShoeDefect.from_severities({kind: severity})
        if kind == "actuation_share_change":
            other = "right" if location == "left" else "left"
            shoes[other] = ShoeDefect(actuation_share=1.0 - shoes[location].actuation_share)
        return cls(**shoes)

    def labels(self) -> list[str]:
        """One readable line per defect in force (:attr:`.catalogue.ActiveDefect.label`)."""
        return [d.label for d in self.active()]
