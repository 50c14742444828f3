"""The pose rules (``ShoeGeometry.pose``): where a moved pin puts the shoe.

``"eye-piston"`` (the heel in an eye on its pin, the tip on the piston's stop) against the
rigid-body facts that define it: the pin moves radially, the body keeps every distance to
it and turns about it, the tip ends on the piston's axis; the compiled placement a growing
pin uses is the static one; a scenario chooses the rule and a wrong name is refused.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from brake_sim_ros.errors import ParameterError, ScenarioError
from brake_sim_ros.model import growth
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import pack
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.growth_law import Growth
from brake_sim_ros.model.parameters import POSES, BrakeParameters, ShoeGeometry
from brake_sim_ros.model.placement import POSE_IDS, place_shoe
from brake_sim_ros.scenarios.loader import parse_scenario
from tests.tip_abutment import TIP_STUDY

EYE = BrakeParameters()  # the study brake's shoe
SHIFTS_PCT = (-2.0, -0.5, 0.5, 3.0, 10.0)


def _left_frame(xy, side):
    return (-xy[0], xy[1]) if side == "right" else xy


def test_every_pose_rule_has_its_packed_id():
    assert set(POSE_IDS) == set(POSES) and len(set(POSE_IDS.values())) == len(POSES)


@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("pct", SHIFTS_PCT)
def test_the_heel_in_an_eye_carries_the_body_with_its_pin_and_turns_it_onto_the_piston(side, pct):
    g = EYE.shoe
    s = place_shoe(EYE, side, ShoeDefect(pivot_radius_change_pct=pct))
    pin = np.array(_left_frame(s.pivot_xy_m, side))
    np.testing.assert_allclose(pin, np.array(g.pivot_xy_m) * (1 + pct / 100), rtol=1e-14)
    tip = np.array(_left_frame(s.tip_xy_m, side))
    assert tip[0] == g.tip_x_m  # on the piston's stop, exactly
    assert tip[1] != g.tip_y_m  # it slid across the piston in the slot
    # a rigid body turned by the reported angle about the moved pin: every body point
    # keeps its distance from the pin, and the tip's direction turned by that angle
    turn = s.abutment_turn_rad
    nominal = {
        "tip": (g.tip_x_m, g.tip_y_m),
        "lining centre": (0.0, 0.0),
        "mass centre": (g.mass_centre_x_m, g.mass_centre_y_m),
    }
    moved = {
        "tip": tuple(tip),
        "lining centre": _left_frame(s.lining_centre_xy_m, side),
        "mass centre": _left_frame(s.mass_centre_xy_m, side),
    }
    for name, point in nominal.items():
        before = np.subtract(point, g.pivot_xy_m)
        after = np.subtract(moved[name], pin)
        assert np.hypot(*after) == pytest.approx(np.hypot(*before), rel=1e-13), name
        angle = math.atan2(*np.flip(after)) - math.atan2(*np.flip(before))
        assert math.remainder(angle - turn, 2 * math.pi) == pytest.approx(0.0, abs=1e-13), name
    mid = s.lining_mid_rad if side == "left" else math.pi - s.lining_mid_rad
    assert mid == pytest.approx(math.radians(0.5 * (g.lining_start_deg + g.lining_end_deg)) + turn)
    # the pin keeps its place in the shoe: its inertia about the pin is the shoe's own
    assert s.inertia_about_pivot_kg_m2 == g.inertia_about_pivot_kg_m2
    assert s.heel_seat_offset_m == 0.0
    # hand calculation, to first order in the shift: the pin moves across the piston's
    # axis by px shift, which the turn takes back at the tip's height above the pin,
    # b = ty - py: turn = px shift / b (an outward pin below the drum's centre, left of
    # it, turns the left shoe clockwise)
    shift = pct / 100.0
    px, py = g.pivot_xy_m
    assert turn == pytest.approx(px * shift / (g.tip_y_m - py), rel=0.5 * abs(shift))


def test_the_study_brake_has_the_eye_and_the_service_brake_the_tip_abutment():
    assert BrakeParameters().shoe.pose == "eye-piston"
    params = BrakeParameters.of_brake("service")
    assert params.shoe.pose == "tip-abutment"
    s = place_shoe(params, "left", ShoeDefect(pivot_radius_change_pct=0.2))
    assert s.tip_xy_m == (params.shoe.tip_x_m, params.shoe.tip_y_m)  # it never moves


@pytest.mark.parametrize("params", [TIP_STUDY, EYE], ids=["tip-abutment", "eye-piston"])
def test_a_growing_pin_is_placed_by_the_same_rule_as_a_pin_set_from_the_start(params):
    """The compiled re-placement (growth.apply) at the final severity writes the static
    pack's shoe block, tip included, and the healthy one at severity 0."""
    grown = Defects(
        left=ShoeDefect(pivot_radius_change_pct=3.0),
        growth=(("pivot_radius_change", "left", Growth(0.0, "linear", rate_per_s=1.0)),),
    )
    p = pack(params, grown)
    healthy = pack(params, Defects())
    static = pack(params, Defects(left=ShoeDefect(pivot_radius_change_pct=3.0)))
    b = slice(L.P_SHOE_BASE, L.P_SHOE_BASE + L.SHOE_STRIDE)
    pw = growth.working_copy(p)
    growth.apply(p, pw, 0.0, np.zeros(L.N_STATE), growth.ALL_ENTRIES)
    np.testing.assert_allclose(pw[b], healthy[b], rtol=1e-14, atol=1e-17)
    growth.apply(p, pw, 10.0, np.zeros(L.N_STATE), growth.ALL_ENTRIES)
    np.testing.assert_allclose(pw[b], static[b], rtol=1e-14, atol=1e-17)
    tip_y = L.P_SHOE_BASE + L.S_TIP_Y
    assert (pw[tip_y] != healthy[tip_y]) == (params.shoe.pose == "eye-piston")


def test_a_scenario_chooses_the_pose_and_a_wrong_name_is_refused_in_one_line():
    text = 'name = "eye"\n[parameters.shoe]\npose = "{}"\n'
    assert parse_scenario(text.format("eye-piston")).setup.params.shoe.pose == "eye-piston"
    with pytest.raises(ScenarioError) as err:
        parse_scenario(text.format("eye-pistn"))
    message = str(err.value)
    assert "\n" not in message and "parameters.shoe.pose" in message and "tip-abutment" in message
    with pytest.raises(ScenarioError, match=r"parameters\.shoe\.pose"):
        parse_scenario('name = "eye"\n[parameters.shoe]\npose = 1.0\n')
    with pytest.raises(ParameterError, match="pose"):
        dataclasses.replace(ShoeGeometry(), pose="eye")
