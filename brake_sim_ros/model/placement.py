"""A shoe's place in the assembled brake: where it sits between its two abutments (the
pin at its heel, the piston at its tip) with its defects applied, in the backing-plate
frame. Read by the packing of the pin's and the lining's defects (:mod:`.packing`), the
drawing and the geometry study.

Pure logic: no files.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

from brake_sim_ros.model import growth
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.parameters import BrakeParameters

# the packed id of each pose rule (parameters.POSES)
POSE_IDS: dict[str, int] = {"tip-abutment": L.POSE_TIP_ABUTMENT, "eye-piston": L.POSE_EYE_PISTON}


class ShoePose(Protocol):
    """What a shoe's placement reads of its defects (a :class:`.defects.ShoeDefect`; that
    module imports the catalogue, which names the packing that places a shoe)."""

    pivot_radius_change_pct: float
    lining_wear_mm: float


@dataclass(frozen=True)
class ShoePlacement:
    """One shoe's assembled geometry at its symmetric rest angle (defects applied), in the
    backing-plate frame (m, rad).

    Attributes:
        sign: +1 left shoe (outward = counter-clockwise), -1 right shoe (mirror image).
        pivot_xy_m: the pin, the axis the shoe turns about in service.
        lining_centre_xy_m, lining_radius_m, lining_mid_rad, lining_half_rad: the lining
            arc (centre, radius, polar angle of its middle seen from the centre, half span).
        tip_xy_m: where the piston pushes; it stays on the piston's axis whatever the pin
            does (and at its place across it with the tip abutment).
        actuation_dir: unit direction of the piston's push (fixed in the backing plate).
        mass_centre_xy_m: the shoe's mass centre.
        inertia_about_pivot_kg_m2: moment of inertia about the pin (parallel-axis theorem
            from the nominal value, for the pin's place in the shoe's heel seat).
        abutment_turn_rad: angle the shoe body turned to follow the pin (about its tip
            abutment, or about the moved pin with the heel in an eye), rad, in the shoe's
            own sense (counter-clockwise for the left shoe, clockwise for the right one, as
            its angle).
        heel_seat_offset_m: part of the pin's displacement along the tip-pin line, taken
            up in the heel seat (positive: the pin moved away from the tip), m; 0 with the
            heel in an eye.
    """

    sign: float
    pivot_xy_m: tuple[float, float]
    lining_centre_xy_m: tuple[float, float]
    lining_radius_m: float
    lining_mid_rad: float
    lining_half_rad: float
    tip_xy_m: tuple[float, float]
    actuation_dir: tuple[float, float]
    mass_centre_xy_m: tuple[float, float]
    inertia_about_pivot_kg_m2: float
    abutment_turn_rad: float
    heel_seat_offset_m: float


def place_shoe(params: BrakeParameters, side: str, defect: ShoePose) -> ShoePlacement:
    """Assemble a shoe between its two abutments: the pin at the heel, the piston at the tip.

    The nominal geometry (:class:`ShoeGeometry`, left shoe) has the lining concentric with
    the drum at rest. A pivot-radius defect moves the pin radially, ``delta = pct/100 * P``.
    A rigid shoe in the plane is held at rest by three contacts; which three is its pose
    rule (``ShoeGeometry.pose``), and the rule decides where a moved pin puts the shoe.

    ``"tip-abutment"``:

    * the tip rests on the wheel-cylinder piston, retracted against its stop: the piston
      holds it along its axis, the slot in its end across it. The tip stays where it is,
      whatever the pin does;
    * the heel rests in its seat on the pin. The seat is open along the shoe's tip-pin
      line, as a heel on an anchor: it holds the heel across that line and lets it slide
      along it. (A seat closed both ways would over-constrain a rigid shoe held at its tip:
      a pin displaced along the line would have to stretch the shoe.)

    So the part of ``delta`` across the tip-pin line carries the heel with the pin: the
    shoe body turns about the tip ``T`` by the exact angle between ``P - T`` and ``P' - T``;
    lining, mass centre and heel follow, the tip stays on the piston. The part along the
    line is taken up in the seat: it does not move the body, but the shoe then turns on the
    pin at its new place ``P'`` (its moment arms and its inertia about the pin follow).
    To first order a radial pin shift thus closes the running clearance at the first
    contact by ``pct/100 * D * a / L`` (``D`` the distance of the tip-pin line from the drum
    centre, ``a`` the tip's distance from the contact normal, ``L`` the tip-pin distance):
    opposite shifts move the lining by equal amounts in opposite directions.

    ``"eye-piston"``:

    * the heel sits in a closed eye on the pin (two contacts): the body goes with its pin;
    * the tip rests on the piston held on its stop, which holds it along the piston's axis
      only (the tip slides across it in the slot). The body turns about the moved pin
      ``P'`` until the tip is back on the stop (``x = T_x``, exactly).

    The lining moves by about ``delta`` with the pin, which may exceed the running
    clearance: the arc then first touches at one of its ends (see the validation report's
    note on case 1). The inertia about the pin does not change (the pin stays at its place
    in the shoe).

    A worn lining's arc has the radius of the new one less the wear (its surface moves in).

    The right shoe is the mirror image of the left one about the y axis, defect included.
    """
    g = params.shoe
    # the compiled model re-places a shoe whose pin moves during a run with the same
    # function (model/growth.py); here its Python source runs, so the assembled geometry
    # keeps CPython's math to the last bit
    px, py = g.pivot_xy_m
    qx, qy, cx, cy, mid, mx, my, inertia, tx, ty, turn, seat = growth.shoe_placement.py_func(
        defect.pivot_radius_change_pct / 100.0,
        -1.0 if side == "right" else 1.0,
        POSE_IDS[g.pose],
        px,
        py,
        g.tip_x_m,
        g.tip_y_m,
        g.mass_centre_x_m,
        g.mass_centre_y_m,
        g.inertia_about_pivot_kg_m2,
        g.mass_kg,
        lining_mid_rad(params),
    )
    m = -1.0 if side == "right" else 1.0
    return ShoePlacement(
        sign=m,
        pivot_xy_m=(qx, qy),
        lining_centre_xy_m=(cx, cy),
        lining_radius_m=worn_lining_radius(params, defect.lining_wear_mm),
        lining_mid_rad=mid,
        lining_half_rad=math.radians(0.5 * (g.lining_end_deg - g.lining_start_deg)),
        tip_xy_m=(tx, ty),
        actuation_dir=(-m, 0.0),
        mass_centre_xy_m=(mx, my),
        inertia_about_pivot_kg_m2=inertia,
        abutment_turn_rad=turn,
        heel_seat_offset_m=seat,
    )


def lining_mid_rad(params: BrakeParameters) -> float:
    """Polar angle of the nominal left shoe's lining middle, rad."""
    g = params.shoe
    return math.radians(0.5 * (g.lining_start_deg + g.lining_end_deg))


def worn_lining_radius(params: BrakeParameters, wear_mm: float) -> float:
    """Radius of a lining worn by ``wear_mm`` (mm), m: the new lining's (the drum's less the
    running clearance) less the wear; its surface moves in."""
    g = params.shoe
    return g.drum_radius_m - g.running_clearance_m - wear_mm * 1e-3
