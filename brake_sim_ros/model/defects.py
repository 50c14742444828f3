"""Defects: deviations of one or both shoes from the symmetric brake."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.catalogue import KIND_BY_NAME, KINDS, ActiveDefect, label_column


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
        return (
            self.pivot_radius_change_pct == 0.0
            and self.initial_angle_deg == 0.0
            and self.actuation_share == 0.5
        )

    @property
    def actuation_gain(self) -> float:
        """Multiplier on this shoe's actuation force, ``2 * actuation_share``."""
        return 2.0 * self.actuation_share


@dataclass(frozen=True)
class Defects:
    """Defects of both shoes, in any combination."""

    left: ShoeDefect = field(default_factory=ShoeDefect)
    right: ShoeDefect = field(default_factory=ShoeDefect)

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
        return self.left.is_healthy and self.right.is_healthy

    def active(self) -> tuple[ActiveDefect, ...]:
        """The ground truth: every defect in force, in catalogue order (kind, then
        location); each a step at the start of the run."""
        shoes = {"left": self.left.severities(), "right": self.right.severities()}
        return tuple(
            ActiveDefect(kind.name, loc, shoes[loc][kind.name], kind.unit)
            for kind in KINDS
            for loc in kind.locations
            if shoes[loc][kind.name] != 0.0
        )

    def severities(self) -> dict[str, float]:
        """The per-sample label columns (:func:`.catalogue.label_columns`) and their value:
        each kind's severity at each location, 0 where absent."""
        shoes = {"left": self.left.severities(), "right": self.right.severities()}
        return {
            label_column(kind, loc): shoes[loc][kind.name]
            for kind in KINDS
            for loc in kind.locations
        }

    @classmethod
    def single(cls, kind: str, location: str, severity: float) -> Defects:
        """A brake with one catalogue defect of ``severity`` at ``location`` (the other
        shoe's actuation share follows a share change: the shares sum to 1)."""
        if location not in ("left", "right") or location not in KIND_BY_NAME[kind].locations:
            raise ParameterError(
                f"defect {kind} at {location!r} is invalid: allowed at"
                f" {list(KIND_BY_NAME[kind].locations)}"
            )
        shoes = {side: ShoeDefect() for side in ("left", "right")}
        shoes[location] = ShoeDefect.from_severities({kind: severity})
        if kind == "actuation_share_change":
            other = "right" if location == "left" else "left"
            shoes[other] = ShoeDefect(actuation_share=1.0 - shoes[location].actuation_share)
        return cls(**shoes)

    def labels(self) -> list[str]:
        """One readable line per defect in force (:attr:`.catalogue.ActiveDefect.label`)."""
        return [d.label for d in self.active()]
