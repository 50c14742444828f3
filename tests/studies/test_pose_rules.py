"""The pose-rule study's placements against hand geometry: the model's rule is the one the
model packs, a shoe carried by its pin brings its lining's heel end within the hand gap of
the drum, a shoe held by its pin and its piston has its tip back on the piston, and the
study names the shape of a response as it is."""

from __future__ import annotations

import math

import pytest

from brake_sim_ros.model.defects import ShoeDefect
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.placement import place_shoe
from brake_sim_ros.studies import pose_rules as pr
from tests.tip_abutment import TIP_STUDY


def test_the_tip_abutment_rule_is_the_models_placement():
    params = TIP_STUDY
    for pct in (-3.0, 3.0):
        study = pr.tip_abutment(params, pct)
        model = place_shoe(params, "left", ShoeDefect(pivot_radius_change_pct=pct))
        assert study.pivot == model.pivot_xy_m
        assert study.lining_centre == model.lining_centre_xy_m
        assert study.inertia_kg_m2 == model.inertia_about_pivot_kg_m2


def test_the_eye_piston_rule_solved_numerically_is_the_models_closed_form():
    """The study solves the turn that puts the tip back on the piston's stop by root
    finding; the model (the study brake's pose) in closed form: the same shoe."""
    params = BrakeParameters()
    g = params.shoe
    for pct in (-3.0, -0.5, 3.0):
        # the study's general rule (an eye, and a stop bearing on one body point) with the
        # piston's stop: the tip held along -x
        study = pr.held_by_stop(params, pct, (g.tip_x_m, g.tip_y_m), (-1.0, 0.0))
        model = place_shoe(params, "left", ShoeDefect(pivot_radius_change_pct=pct))
        for a, b in (
            (study.pivot, model.pivot_xy_m),
            (study.lining_centre, model.lining_centre_xy_m),
            (study.mass_centre, model.mass_centre_xy_m),
            (study.tip, model.tip_xy_m),
        ):
            assert a == pytest.approx(b, abs=1e-14)
        assert study.lining_mid_rad == pytest.approx(model.lining_mid_rad, abs=1e-14)
        assert study.inertia_kg_m2 == pytest.approx(model.inertia_about_pivot_kg_m2, rel=1e-13)


def test_a_shoe_carried_by_its_pin_nearly_touches_at_its_heel_end():
    """3 % of a 148 mm pin radius is 4.44 mm, more than the 3.5 mm clearance: moved with
    its pin, the lining keeps clear of the drum only by its heel end (at 195 deg, 50 deg
    short of the pin), whose gap is the drum radius less the distance of the moved end."""
    params = TIP_STUDY
    g = params.shoe
    pct = 3.0
    p = pr.packed(params, pr.carried(params, pct), pivot_radius_change_pct=pct)
    px, py = g.pivot_xy_m
    end = math.radians(g.lining_end_deg)
    r = g.drum_radius_m - g.running_clearance_m
    x = r * math.cos(end) + pct / 100.0 * px
    y = r * math.sin(end) + pct / 100.0 * py
    hand_gap_mm = 1e3 * (g.drum_radius_m - math.hypot(x, y))
    geo = pr.geometry(p)
    assert geo.rest_gap_mm == pytest.approx(hand_gap_mm, abs=1e-6)
    assert 0.0 < geo.rest_gap_mm < 0.2 * 1e3 * g.running_clearance_m
    # the first contact is that end, and the shoe turns through a quarter of its gap
    assert geo.contact_deg == pytest.approx(g.lining_end_deg, abs=1.5)
    base = pr.geometry(pr.packed(params, pr.carried(params, 0.0)))
    assert geo.gap_angle_rad / base.gap_angle_rad < 0.3


def test_a_shoe_held_by_its_pin_and_piston_has_its_tip_on_the_piston():
    params = BrakeParameters()
    g = params.shoe
    for pct in (-2.0, 3.0):
        pose = pr.eye_piston(params, pct)
        assert pose.tip[0] == pytest.approx(g.tip_x_m, abs=1e-12)
        px, py = g.pivot_xy_m
        assert pose.pivot == pytest.approx((px * (1 + pct / 100), py * (1 + pct / 100)))
        # to first order: the turn r about the moved pin Q that takes the tip's x back,
        # r = px s / (ty - qy), and the tip's vertical shift py s + r (tx - qx)
        s = pct / 100
        qx, qy = px * (1 + s), py * (1 + s)
        turn = px * s / (g.tip_y_m - qy)
        hand_y = g.tip_y_m + py * s + turn * (g.tip_x_m - qx)
        assert pose.tip[1] == pytest.approx(hand_y, abs=2e-5)  # second order: r^2 x 0.3 m


def test_the_shape_of_a_response():
    pcts = [-2.0, -1.0, 0.0, 1.0, 2.0]
    assert pr.shape([3.0, 2.0, 1.0, 0.0, -1.0], pcts) == "monotone, asymmetry 0.00"
    assert pr.shape([1.0, 0.5, 0.0, 0.5, 1.0], pcts) == "both ends the same way, asymmetry 1.00"
    assert pr.shape([0.0, 2.0, 1.0, 3.0, 4.0], pcts).startswith("not monotone")


def test_a_pin_held_shoe_reaches_case_1_in_the_calibrations_space():
    """Under ``eye-piston`` the study brake's geometry puts case 1's three figures, the
    symmetric first impact and case 5 inside their published bands (the validation's
    bands, band units <= 1), assembled clear of the drum and short of self-locking at
    both ends of the sweep; the inward pin softens the first impact as well (an even
    response: the first contact at the lining's toe end)."""
    from brake_sim_ros.studies.pose_rule_sample import grid_point

    params = BrakeParameters()
    point = grid_point(params, "eye-piston", 0.0, (0.0, 0.0, 0.0))
    assert not point.admissible
    assert set(point.misses) == {"sym.Fe", "5.peak", "5.T", "1.peak", "1.T", "1.Fe"}
    assert all(abs(m) <= 1.0 for m in point.misses.values()), point.misses
    assert point.case2_peak_pct < 0.0
    # the tip abutment with the same geometry leaves case 1 outside
    model = grid_point(params, "tip-abutment", 0.0, (0.0, 0.0, 0.0))
    assert any(abs(model.misses[k]) > 1.0 for k in ("1.peak", "1.T", "1.Fe"))


def test_a_rule_places_the_right_shoe_as_the_models_mirror_image():
    """The validation of another pose places each shoe whose pin moved: with the model's
    own rule the packed vector is the model's, for a pin moved on either shoe."""
    import numpy as np

    from brake_sim_ros.errors import ParameterError
    from brake_sim_ros.model.assembly import pack
    from brake_sim_ros.model.defects import Defects
    from brake_sim_ros.studies.pose_rule_validation import packed_by_rule

    params = TIP_STUDY
    for side, pct in (("left", 3.0), ("right", -3.0), ("right", 2.0)):
        defects = Defects(**{side: ShoeDefect(pivot_radius_change_pct=pct)})
        model = pack(params, defects)
        study = packed_by_rule(params, defects, pr.tip_abutment)
        assert np.array_equal(study, model, equal_nan=True)  # bit for bit
    # another rule moves that shoe's tip; one that would put the lining in the drum at rest
    # is refused in one line
    defects = Defects(right=ShoeDefect(pivot_radius_change_pct=3.0))
    moved = packed_by_rule(params, defects, pr.eye_piston)
    assert moved[pr.L.P_SHOE_BASE + pr.L.SHOE_STRIDE + pr.L.S_TIP_Y] != params.shoe.tip_y_m
    with pytest.raises(ParameterError, match=r"right pivot radius change -3 % .* inside the drum"):
        packed_by_rule(
            params, Defects(right=ShoeDefect(pivot_radius_change_pct=-3.0)), pr.eye_piston
        )
