"""A weak or broken return spring (model/actuation.py spring_release): drag without
actuation once the residual line pressure wins over what is left of the preload."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from brake_sim_ros.model import layout as L
from brake_sim_ros.model.actuation import RESIDUAL_FORCE_N, RETURN_SPRING_PRELOAD_N
from brake_sim_ros.model.assembly import contact_arms, pack
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.stream.build import stepper_for

MU = 0.285
IDLE = 'name = "idle"\nduration_s = 1.5\n[actuation]\npeak_force_n = 0.0\n'
BRAKING = 'name = "braking"\nduration_s = 1.0\n'


def _run(text: str, left: ShoeDefect):
    sc = parse_scenario(text)
    sc = sc.with_defects(Defects(left=left))
    return stepper_for(sc).run(sc.duration_s)


def test_a_broken_spring_drags_the_shoe_on_the_drum_without_actuation():
    """Broken: the residual force (20 N) presses the leading shoe on the drum; its moment
    balance ``Fn (d - mu h) = F q`` gives the friction force ``mu F q / (d - mu h)``
    (arms at first contact); a healthy brake with no actuation has no friction at all."""
    healthy = _run(IDLE, ShoeDefect())
    broken = _run(IDLE, ShoeDefect(return_spring_weakening_pct=100.0))
    assert np.all(healthy["left_friction_force_n"] == 0.0)
    assert np.all(healthy["drum_speed_rad_s"] == healthy["drum_speed_rad_s"][0])
    p = pack(parse_scenario(IDLE).setup.params, Defects())
    arms = contact_arms(p, L.P_SHOE_BASE, 0.0)
    d, h, q = arms.normal_arm_m, arms.friction_arm_m, arms.actuation_arm_m
    expected = MU * RESIDUAL_FORCE_N * q / (d - MU * h)
    w = broken.time_s > 1.0
    assert broken["left_friction_force_n"][w].mean() == pytest.approx(expected, rel=0.03)
    assert np.all(broken["right_friction_force_n"] == 0.0)
    assert broken["drum_speed_rad_s"][-1] < broken["drum_speed_rad_s"][0]  # it drags
    assert np.all(broken["left_actuation_force_n"] == RESIDUAL_FORCE_N)


def test_a_weak_spring_holds_the_shoe_off_but_lets_it_go_earlier():
    """50 % (30 N lost, below the stop's 40 N margin): no drag at rest; under the ramp the
    shoe gets the lost preload on top of the force, so it meets the drum sooner."""
    weak = ShoeDefect(return_spring_weakening_pct=50.0)
    assert np.all(_run(IDLE, weak)["left_friction_force_n"] == 0.0)
    healthy, run = _run(BRAKING, ShoeDefect()), _run(BRAKING, weak)
    released = 0.5 * RETURN_SPRING_PRELOAD_N
    on = healthy["left_actuation_force_n"] > 0.0
    assert np.allclose(
        run["left_actuation_force_n"][on], healthy["left_actuation_force_n"][on] + released
    )
    first = [
        float(r.time_s[np.flatnonzero(r["left_normal_force_n"] > 0)[0]]) for r in (healthy, run)
    ]
    assert first[1] < first[0] - 0.002


def test_the_spring_is_refused_where_the_history_is_taken_as_commanded():
    from brake_sim_ros.errors import ParameterError
    from brake_sim_ros.solvers.reference import run_reference

    setup = (
        parse_scenario(IDLE)
        .with_defects(Defects(left=ShoeDefect(return_spring_weakening_pct=100.0)))
        .setup
    )
    with pytest.raises(ParameterError, match="weak return spring"):
        run_reference(dataclasses.replace(setup), 0.1)
