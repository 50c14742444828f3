"""Friction change per shoe (fade, contamination): the shoe's lining coefficient, in the
compiled model, against the shoe's moment balance and the energy of the stop."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from brake_sim_ros.errors import ParameterError, ScenarioError
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import contact_arms, pack
from brake_sim_ros.model.catalogue import Growth
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.scenarios.loader import load_scenario, parse_scenario
from brake_sim_ros.stream.build import stepper_for

MU = 0.285  # the calibrated coefficient (model/parameters.py FrictionParameters)


def _run(defects: Defects, duration_s: float):
    sc = dataclasses.replace(
        load_scenario("symmetric").with_defects(defects), duration_s=duration_s
    )
    stepper = stepper_for(sc)
    return stepper, stepper.run(duration_s)


@pytest.fixture(scope="module")
def healthy():
    return _run(Defects(), 9.0)


@pytest.fixture(scope="module")
def faded():
    return _run(Defects(left=ShoeDefect(friction_change_pct=-50.0)), 12.0)


def test_the_packed_lining_coefficient_is_the_nominal_one_changed_by_the_percentage():
    sc = load_scenario("symmetric")
    p = pack(sc.setup.params, Defects(right=ShoeDefect(friction_change_pct=-30.0)))
    assert p[L.P_FRICTION_COEFFICIENT] == MU
    assert p[L.P_SHOE_BASE + L.S_FRICTION_COEFFICIENT] == MU
    assert p[L.P_SHOE_BASE + L.SHOE_STRIDE + L.S_FRICTION_COEFFICIENT] == pytest.approx(0.7 * MU)


def test_a_faded_leading_lining_brakes_less_by_its_moment_balance(healthy, faded):
    """In the contact regime the leading shoe balances ``Fn (d - mu h) = Fe q``, so its
    friction force is ``mu Fe q / (d - mu h)``: halving mu scales it by
    ``0.5 (d - mu h) / (d - 0.5 mu h)`` (arms at first contact, from the geometry). The
    trailing shoe, untouched, keeps its force while the drum turns."""
    sc = load_scenario("symmetric")
    p = pack(sc.setup.params, Defects())
    arms = contact_arms(p, L.P_SHOE_BASE, 0.0)
    d, h = arms.normal_arm_m, arms.friction_arm_m
    expected = 0.5 * (d - MU * h) / (d - 0.5 * MU * h)
    window = lambda run: (run.time_s > 1.0) & (run.time_s < 4.0)  # noqa: E731
    for_left = [run["left_friction_force_n"][window(run)].mean() for run in (healthy[1], faded[1])]
    assert for_left[1] / for_left[0] == pytest.approx(expected, rel=0.02)
    right = [run["right_friction_force_n"][window(run)].mean() for run in (healthy[1], faded[1])]
    assert right[1] == pytest.approx(right[0], rel=0.005)


def test_lower_friction_lowers_the_braking_torque_and_lengthens_the_stop(healthy, faded):
    """The rotor's energy is the same; the torque on the drum falls, so the stop takes
    longer, in proportion (the torques' ratio over the contact regime, within the
    impacting regime's share of the stop)."""
    (h_stepper, h_run), (f_stepper, f_run) = healthy, faded
    torque = []
    for run in (h_run, f_run):
        w = (run.time_s > 1.0) & (run.time_s < 4.0)
        radius = np.hypot(run["left_contact_x_m"], run["left_contact_y_m"])[w].mean()
        torque.append(
            ((run["left_friction_force_n"] + run["right_friction_force_n"])[w]).mean() * radius
        )
    assert torque[1] < 0.85 * torque[0]
    stop_h, stop_f = h_stepper.stop_time_s, f_stepper.stop_time_s
    assert stop_h is not None and stop_f is not None
    # after the 0.7 s ramp the deceleration is the torque over the inertia: the time to
    # stop from there scales with the inverse torque
    assert (stop_f - 0.7) / (stop_h - 0.7) == pytest.approx(torque[0] / torque[1], rel=0.05)


def test_a_fading_lining_changes_its_coefficient_as_it_fades():
    """Linear fade to -40 % over 1-3 s: while the lining slides with saturated friction,
    Ff / Fn is the coefficient at that instant, ``mu (1 - 0.2 (t - 1))``."""
    d = Defects(
        left=ShoeDefect(friction_change_pct=-40.0),
        growth=(("friction_change", "left", Growth(1.0, "linear", rate_per_s=20.0)),),
    )
    _, run = _run(d, 3.5)
    t = run.time_s
    fn = run["left_normal_force_n"]
    sliding = (fn > 50.0) & (np.abs(run["left_sliding_speed_m_s"]) > 1.0)
    ratio = run["left_friction_force_n"][sliding] / fn[sliding]
    expected = MU * (1.0 - np.clip(20.0 * (t[sliding] - 1.0), 0.0, 40.0) / 100.0)
    assert np.allclose(ratio, expected, rtol=1e-9)
    assert ratio.min() == pytest.approx(0.6 * MU, rel=1e-9)


def test_a_friction_change_beyond_its_range_is_refused_in_one_line():
    with pytest.raises(ParameterError, match=r"friction_change_pct=-95 is invalid: allowed -90"):
        ShoeDefect(friction_change_pct=-95.0)
    with pytest.raises(
        ScenarioError, match=r"friction_change_pct=60 is invalid: allowed -90 to 50"
    ):
        parse_scenario('name = "x"\n[defects.right]\nfriction_change_pct = 60.0\n')
