"""Pure geometry of the brake drawing: drum, shoes, linings, pivots, contact points, forces.

Everything is in the ``brake_backing_plate`` frame (origin at the drum centre, x right,
y up, metres) and computed from the core's parameters and defects with
:func:`brake_sim_ros.model.placement.place_shoe`, so the drawing is the geometry the
physics uses. No Rerun here: :mod:`.scene` turns a :class:`Frame` into entities.

The shoe outline (web and lining thickness) is illustrative: the model's shoe is a rigid
body known by its pivot, lining arc and tip; the lining's friction surface, the pivot,
the tip and the contact points are drawn where the model has them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from brake_sim_ros.model.defects import Defects
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.placement import place_shoe

LINING_THICKNESS_M = 0.008  # drawn thickness of the lining (illustrative)
TABLE_THICKNESS_M = 0.004  # drawn thickness of the shoe table under the lining (illustrative)
FORCE_SCALE_M_PER_N = 2e-5  # arrow length per newton: 5 kN draws 0.1 m
_ARC_POINTS = 32
_DRUM_POINTS = 181


def _rotate(points: np.ndarray, centre: np.ndarray, angle_rad: float) -> np.ndarray:
    """Points (n, 2) turned by ``angle_rad`` (counter-clockwise) about ``centre`` (2,)."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    rel = points - centre
    return np.column_stack((c * rel[:, 0] - s * rel[:, 1], s * rel[:, 0] + c * rel[:, 1])) + centre


@dataclass(frozen=True)
class ShoeShape:
    """One shoe at its symmetric rest angle (defects applied), points in m, shape (n, 2).

    Attributes:
        sign: +1 left (outward = counter-clockwise), -1 right (outward = clockwise).
        pivot: pivot pin centre (2,).
        tip: actuated tip (2,).
        actuation_dir: unit vector of the actuation force on the tip (2,).
        lining: closed outline of the lining; its outer arc is the friction surface.
        table: closed outline of the shoe (table under the lining, web to pivot and tip).
    """

    sign: float
    pivot: np.ndarray
    tip: np.ndarray
    actuation_dir: np.ndarray
    lining: np.ndarray
    table: np.ndarray


@dataclass(frozen=True)
class Frame:
    """The drawing at one instant, all in m in frame ``brake_backing_plate``.

    Attributes:
        drum: drum circle (n, 2) and its angle marker (2, 2) (a radial tick).
        linings / tables: per side, closed outlines (n, 2).
        pivots / tips: (2, 2), rows left and right.
        actuation_arrows: origins and vectors (2, 2) each, force x FORCE_SCALE_M_PER_N.
    """

    drum: np.ndarray
    drum_marker: np.ndarray
    linings: tuple[np.ndarray, np.ndarray]
    tables: tuple[np.ndarray, np.ndarray]
    pivots: np.ndarray
    tips: np.ndarray
    actuation_origins: np.ndarray
    actuation_vectors: np.ndarray


class BrakeDrawing:
    """The brake's 2-D drawing for given parameters and defects.

    Args:
        params: parameters in force (drum radius, shoe geometry).
        defects: defects in force (a pivot-radius change turns the shoe about its tip:
            :func:`brake_sim_ros.model.placement.place_shoe`).
    """

    def __init__(self, params: BrakeParameters, defects: Defects) -> None:
        self.drum_radius_m = params.shoe.drum_radius_m
        angles = np.linspace(0.0, 2.0 * math.pi, _DRUM_POINTS)
        self._drum = self.drum_radius_m * np.column_stack((np.cos(angles), np.sin(angles)))
        self.shoes = tuple(self._shoe_shape(params, side, getattr(defects, side)) for side in SIDES)

    @staticmethod
    def _shoe_shape(params: BrakeParameters, side: str, defect) -> ShoeShape:
        s = place_shoe(params, side, defect)
        pivot = np.asarray(s.pivot_xy_m)
        centre = np.asarray(s.lining_centre_xy_m)
        a = np.linspace(
            s.lining_mid_rad - s.lining_half_rad, s.lining_mid_rad + s.lining_half_rad, _ARC_POINTS
        )
        unit = np.column_stack((np.cos(a), np.sin(a)))
        if np.hypot(*(unit[0] - pivot)) > np.hypot(*(unit[-1] - pivot)):
            unit = unit[::-1]  # heel (end next to the pivot) first
        r = s.lining_radius_m
        outer = centre + r * unit
        inner = centre + (r - LINING_THICKNESS_M) * unit
        under = centre + (r - LINING_THICKNESS_M - TABLE_THICKNESS_M) * unit
        tip = np.asarray(s.tip_xy_m)
        lining = np.vstack((outer, inner[::-1], outer[:1]))
        table = np.vstack((pivot, inner, tip, under[-1:], under[::-1], pivot))
        return ShoeShape(
            sign=s.sign,
            pivot=pivot,
            tip=tip,
            actuation_dir=np.asarray(s.actuation_dir, dtype=float),
            lining=lining,
            table=table,
        )

    def frame(
        self,
        *,
        shoe_angles_rad: tuple[float, float],
        drum_angle_rad: float,
        actuation_n: tuple[float, float],
    ) -> Frame:
        """The drawing for shoe angles (left, right; positive outward, from the symmetric
        rest position, as in BrakeState), the drum angle (CCW) and the actuation forces (N)."""
        linings, tables, tips = [], [], []
        for shoe, angle in zip(self.shoes, shoe_angles_rad, strict=True):
            turn = shoe.sign * angle  # left outward = CCW, right outward = CW
            linings.append(_rotate(shoe.lining, shoe.pivot, turn))
            tables.append(_rotate(shoe.table, shoe.pivot, turn))
            tips.append(_rotate(shoe.tip[None, :], shoe.pivot, turn)[0])
        c, s = math.cos(drum_angle_rad), math.sin(drum_angle_rad)
        marker = self.drum_radius_m * np.array([[0.85 * c, 0.85 * s], [c, s]])
        tips_arr = np.array(tips)
        vectors = np.array(
            [shoe.actuation_dir * f for shoe, f in zip(self.shoes, actuation_n, strict=True)]
        )
        return Frame(
            drum=self._drum,
            drum_marker=marker,
            linings=(linings[0], linings[1]),
            tables=(tables[0], tables[1]),
            pivots=np.array([shoe.pivot for shoe in self.shoes]),
            tips=tips_arr,
            actuation_origins=tips_arr,
            actuation_vectors=FORCE_SCALE_M_PER_N * vectors,
        )


def contact_force_vectors(
    point_xy_m: tuple[float, float], normal_n: float, friction_n: float
) -> tuple[np.ndarray, np.ndarray]:
    """Arrows (m, scaled by FORCE_SCALE_M_PER_N) of the drum's force on a lining at a
    contact point on the drum surface: normal toward the drum centre, friction along the
    counter-clockwise tangent when positive (BrakeState's signs)."""
    p = np.asarray(point_xy_m, dtype=float)
    r = float(np.hypot(*p))
    if r == 0.0:
        zero = np.zeros(2)
        return zero, zero
    inward = -p / r
    ccw = np.array([-p[1], p[0]]) / r
    return FORCE_SCALE_M_PER_N * normal_n * inward, FORCE_SCALE_M_PER_N * friction_n * ccw
