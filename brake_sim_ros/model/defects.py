"""Defects: deviations of one or both shoes from the symmetric brake."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from brake_sim_ros.errors import ParameterError


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
        if not -20.0 <= self.pivot_radius_change_pct <= 20.0:
            raise ParameterError(
                f"defect pivot_radius_change_pct={self.pivot_radius_change_pct} is invalid:"
                " allowed -20 to +20 %"
            )
        if not -10.0 <= self.initial_angle_deg <= 10.0:
            raise ParameterError(
                f"defect initial_angle_deg={self.initial_angle_deg} is invalid: allowed -10 to"
                " +10 deg"
            )
        if not 0.0 <= self.actuation_share <= 1.0:
            raise ParameterError(
                f"defect actuation_share={self.actuation_share} is invalid: allowed 0 to 1"
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

    def labels(self, side: str) -> list[str]:
        out = []
        if self.pivot_radius_change_pct:
            out.append(f"{side} pivot radius {self.pivot_radius_change_pct:+.1f} %")
        if self.initial_angle_deg:
            out.append(f"{side} initial angle {self.initial_angle_deg:+.2f} deg")
        if self.actuation_share != 0.5:
            out.append(f"{side} actuation share {self.actuation_share:.3f}")
        return out


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

    def labels(self) -> list[str]:
        return self.left.labels("left") + self.right.labels("right")
