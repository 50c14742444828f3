"""Assembled shoe pose under the tip abutment and the response to the pivot location
(issue 10, item 1), on the study brake's old layout with that pose (:data:`TIP_STUDY`;
the service brake's shoe; the heel in an eye: tests/model/test_pose.py).

Pose invariants of :func:`place_shoe` (the tip stays on the piston, the heel follows the
pin across the tip-pin line, the shoe is rigid, the right shoe mirrors the left), and the
physics that can fail: opposite small pivot shifts must move the first impact in opposite
directions, by equal amounts to first order, and larger shifts further the same way.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from brake_sim_ros.analysis.impacts import shoe_metrics
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import contact_arms, indentation_at, pack
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.placement import place_shoe
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.solvers.stability import step_limit
from tests.tip_abutment import TIP_STUDY

PARAMS = TIP_STUDY
SIDES = ("left", "right")
SHIFTS_PCT = (-20.0, -3.0, -0.5, 0.5, 3.0, 20.0)
BASE = {"left": L.P_SHOE_BASE, "right": L.P_SHOE_BASE + L.SHOE_STRIDE}


def _turned(point, centre, angle):
    c, s = math.cos(angle), math.sin(angle)
    dx, dy = point[0] - centre[0], point[1] - centre[1]
    return (centre[0] + c * dx - s * dy, centre[1] + s * dx + c * dy)


def _left_frame(xy, side):
    """A right-shoe point seen in the left shoe's (mirrored) frame."""
    return (-xy[0], xy[1]) if side == "right" else xy


# --- pose ----------------------------------------------------------------------------------
def test_healthy_shoe_is_the_nominal_geometry():
    g = PARAMS.shoe
    s = place_shoe(PARAMS, "left", ShoeDefect())
    assert s.pivot_xy_m == pytest.approx(g.pivot_xy_m, abs=1e-15)
    assert s.lining_centre_xy_m == pytest.approx((0.0, 0.0), abs=1e-15)
    assert s.tip_xy_m == (g.tip_x_m, g.tip_y_m)
    assert s.mass_centre_xy_m == pytest.approx((g.mass_centre_x_m, g.mass_centre_y_m), abs=1e-15)
    assert s.inertia_about_pivot_kg_m2 == pytest.approx(g.inertia_about_pivot_kg_m2, rel=1e-14)
    assert s.abutment_turn_rad == 0.0 and s.heel_seat_offset_m == 0.0


@pytest.mark.parametrize("side", SIDES)
@pytest.mark.parametrize("pct", SHIFTS_PCT)
def test_tip_stays_on_the_piston_and_the_pin_moves_radially(side, pct):
    g = PARAMS.shoe
    s = place_shoe(PARAMS, side, ShoeDefect(pivot_radius_change_pct=pct))
    assert _left_frame(s.tip_xy_m, side) == (g.tip_x_m, g.tip_y_m)
    px, py = g.pivot_xy_m
    assert _left_frame(s.pivot_xy_m, side) == pytest.approx(
        (px * (1 + pct / 100), py * (1 + pct / 100)), rel=1e-14
    )
    assert s.actuation_dir == ((-1.0, 0.0) if side == "left" else (1.0, 0.0))


@pytest.mark.parametrize("side", SIDES)
@pytest.mark.parametrize("pct", SHIFTS_PCT)
def test_body_turns_rigidly_about_the_tip_and_the_heel_follows_the_pin(side, pct):
    """Lining centre and mass centre are the nominal ones turned about the tip by the
    reported angle; the heel (the body point that was on the pin) lies on the tip-pin line
    at its old distance from the tip, so the pin's move across that line is the heel's and
    the rest, along it, is the reported seat offset."""
    g = PARAMS.shoe
    s = place_shoe(PARAMS, side, ShoeDefect(pivot_radius_change_pct=pct))
    tip = (g.tip_x_m, g.tip_y_m)
    turn = s.abutment_turn_rad
    assert _left_frame(s.lining_centre_xy_m, side) == pytest.approx(
        _turned((0.0, 0.0), tip, turn), abs=1e-15
    )
    assert _left_frame(s.mass_centre_xy_m, side) == pytest.approx(
        _turned((g.mass_centre_x_m, g.mass_centre_y_m), tip, turn), abs=1e-15
    )
    nominal_mid = math.radians(0.5 * (g.lining_start_deg + g.lining_end_deg))
    mid = s.lining_mid_rad if side == "left" else math.pi - s.lining_mid_rad
    assert mid == pytest.approx(nominal_mid + turn, abs=1e-15)
    heel = np.array(_turned(g.pivot_xy_m, tip, turn)) - tip
    pin = np.array(_left_frame(s.pivot_xy_m, side)) - tip
    assert abs(heel[0] * pin[1] - heel[1] * pin[0]) <= 1e-15  # on the tip-pin line
    assert np.hypot(*heel) == pytest.approx(math.dist(g.pivot_xy_m, tip), rel=1e-14)
    assert np.hypot(*pin) - np.hypot(*heel) == pytest.approx(s.heel_seat_offset_m, abs=1e-15)
    assert math.copysign(1, turn) == -math.copysign(1, pct)  # outward pin: heel outward


@pytest.mark.parametrize("pct", SHIFTS_PCT)
def test_inertia_about_the_new_pin_by_the_parallel_axis_theorem(pct):
    g = PARAMS.shoe
    s = place_shoe(PARAMS, "left", ShoeDefect(pivot_radius_change_pct=pct))
    own = (
        g.inertia_about_pivot_kg_m2
        - g.mass_kg * math.dist((g.mass_centre_x_m, g.mass_centre_y_m), g.pivot_xy_m) ** 2
    )
    moved = s.inertia_about_pivot_kg_m2 - g.mass_kg * (
        math.dist(s.mass_centre_xy_m, s.pivot_xy_m) ** 2
    )
    assert moved == pytest.approx(own, rel=1e-12)


@pytest.mark.parametrize(
    "defect",
    [
        ShoeDefect(pivot_radius_change_pct=3.0),
        ShoeDefect(pivot_radius_change_pct=-3.0, initial_angle_deg=-1.0),
        ShoeDefect(initial_angle_deg=-2.0, actuation_share=0.5),
    ],
)
def test_mirrored_shoes_stay_mirror_images(defect):
    left, right = (place_shoe(PARAMS, side, defect) for side in SIDES)
    mirror = lambda xy: (-xy[0], xy[1])  # noqa: E731
    assert right.sign == -left.sign
    for name in ("pivot_xy_m", "lining_centre_xy_m", "tip_xy_m", "mass_centre_xy_m"):
        assert getattr(right, name) == pytest.approx(mirror(getattr(left, name)), abs=1e-15)
    assert right.lining_mid_rad == pytest.approx(math.pi - left.lining_mid_rad, abs=1e-15)
    assert right.actuation_dir == mirror(left.actuation_dir)
    for name in ("inertia_about_pivot_kg_m2", "abutment_turn_rad", "heel_seat_offset_m"):
        assert getattr(right, name) == getattr(left, name)
    # and the kernel sees the same shoe: the same gap at the same angle on either side
    p = pack(PARAMS, Defects(left=defect, right=defect))
    for theta in (0.0, 0.01, 0.03):
        assert indentation_at(p, BASE["left"], theta) == pytest.approx(
            indentation_at(p, BASE["right"], theta), abs=1e-15
        )


# --- response ------------------------------------------------------------------------------
def _onset_angle(side: str, pct: float) -> float:
    defects = Defects(**{side: ShoeDefect(pivot_radius_change_pct=pct)})
    arms = contact_arms(pack(PARAMS, defects), BASE[side], 0.0)
    assert arms is not None
    return arms.onset_angle_rad


@pytest.mark.parametrize("side", SIDES)
def test_angular_gap_closes_with_an_outward_pin_and_opens_with_an_inward_one(side):
    """The shoe's travel to first contact: monotone in the pin shift, and antisymmetric for
    small opposite shifts (second-order remainder below 2 % of the first-order change)."""
    gaps = [_onset_angle(side, pct) for pct in (-3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0)]
    assert all(np.diff(gaps) < 0), gaps
    zero, up, down = _onset_angle(side, 0.0), _onset_angle(side, 0.5), _onset_angle(side, -0.5)
    assert abs((up - zero) + (down - zero)) <= 0.02 * abs(up - down)


def _first_impact(side: str, pct: float) -> np.ndarray:
    """(actuation at first impact N, first-impact peak |F_pivot| N, impact period s)."""
    setup = BrakeSetup(
        params=PARAMS, defects=Defects(**{side: ShoeDefect(pivot_radius_change_pct=pct)})
    )
    block = FixedStepStepper(setup, 2e-5).run(0.34)
    m = shoe_metrics(block, side, stop_time_s=None)
    return np.array([m.first_impact_actuation_n, m.first_impact_peak_n, m.period_s])


@pytest.mark.parametrize("side", SIDES)
def test_first_impact_is_antisymmetric_in_small_opposite_pivot_shifts(side):
    """+-0.5 %: each figure moves in opposite directions, by amounts equal to first order:
    |d(+x) + d(-x)| (the even, second-order part) within 10 % of |d(+x) - d(-x)|."""
    base = _first_impact(side, 0.0)
    up = _first_impact(side, 0.5) - base
    down = _first_impact(side, -0.5) - base
    names = ("actuation at first impact", "first-impact peak", "impact period")
    for name, u, d in zip(names, up, down, strict=True):
        assert u * d < 0, (name, u, d)
        assert abs(u + d) <= 0.10 * abs(u - d), (name, u, d)
    # an outward pin brings the shoe to the drum sooner, slower and softer
    assert up[0] < 0 and up[1] < 0 and up[2] < 0


@pytest.mark.parametrize("side", SIDES)
def test_first_impact_is_monotone_over_the_studys_pivot_range(side):
    figures = np.array([_first_impact(side, pct) for pct in (-3.0, -1.5, 0.0, 1.5, 3.0)])
    for column in figures.T:
        assert all(np.diff(column) < 0), figures


def test_inward_pin_leaves_the_leading_shoe_as_stiff_as_the_healthy_one():
    """Case 2 (leading pin 3 % inward) used to touch at the lining's toe, near self-locking,
    with a step limit seven times below the symmetric brake's. With the shoe held at its tip
    the first contact stays mid-lining and the limit within 15 % of the symmetric one."""
    healthy = step_limit(BrakeSetup(params=PARAMS), 1300.0).max_step_s
    inward = Defects(left=ShoeDefect(pivot_radius_change_pct=-3.0))
    case2 = step_limit(BrakeSetup(params=PARAMS, defects=inward), 1300.0).max_step_s
    assert case2 >= 0.85 * healthy, (case2, healthy)
