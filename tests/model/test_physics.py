"""Physics checks that can fail: closed forms, conservation, symmetry, determinism, convergence."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from brake_sim_ros.analysis.energy import energy_balance
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.actuation import Actuation, ForceProfile
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.parameters import BrakeParameters, ContactParameters, ShoeGeometry
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.solvers.reference import run_reference
from brake_sim_ros.stream.build import stepper_for


def test_hertz_line_contact_stiffness_closed_form():
    c = ContactParameters(
        drum_youngs_modulus_pa=100e9,
        drum_poisson_ratio=0.3,
        shoe_youngs_modulus_pa=2e9,
        shoe_poisson_ratio=0.2,
    )
    e_eq = 1.0 / ((1 - 0.09) / 100e9 + (1 - 0.04) / 2e9)
    params = BrakeParameters(contact=c, shoe=ShoeGeometry(lining_width_m=0.05))
    assert params.contact_stiffness_n_per_m == pytest.approx(math.pi / 4 * e_eq * 0.05, rel=1e-12)


def test_torsional_mode_matches_closed_form_with_shoes_held_off():
    params = BrakeParameters()
    setup = BrakeSetup(
        params=params, actuation=Actuation(ForceProfile.constant(0.0), ForceProfile.constant(0.0))
    )
    dt = 1e-5
    stepper = FixedStepStepper(setup, dt)
    y = stepper.state
    y[L.Y_FLYWHEEL_ANGLE] = 0.01  # initial twist of the wheel-tyre coupling
    stepper.set_state(y)
    # zeta is about 0.29: after 5 periods the twist is 1e-6 of its start, still far above
    # the rounding of the angles (about 1e-14 rad)
    block = stepper.run(0.15)
    twist = block["flywheel_angle_rad"] - block["drum_angle_rad"]
    t = block.time_s
    up = np.flatnonzero((twist[:-1] < 0) & (twist[1:] >= 0))
    t_up = t[up] - twist[up] * dt / (twist[up + 1] - twist[up])
    measured = 1.0 / np.mean(np.diff(t_up))
    d = params.driveline
    i_red = (
        d.flywheel_inertia_kg_m2
        * d.drum_inertia_kg_m2
        / (d.flywheel_inertia_kg_m2 + d.drum_inertia_kg_m2)
    )
    wn = math.sqrt(d.coupling_stiffness_n_m_per_rad / i_red)
    zeta = d.coupling_damping_n_m_s_per_rad / (
        2 * math.sqrt(d.coupling_stiffness_n_m_per_rad * i_red)
    )
    expected = wn * math.sqrt(1 - zeta**2) / (2 * math.pi)
    assert measured == pytest.approx(expected, rel=1e-4)
    assert np.all(block["left_normal_force_n"] == 0) and np.all(block["right_normal_force_n"] == 0)


def test_energy_balance_over_a_whole_event(symmetric_rk4):
    # initial kinetic energy + actuator work = friction work + damper and contact losses
    # + energy absorbed when the brake locks + what remains (kinetic and elastic)
    books = energy_balance(symmetric_rk4.samples, BrakeParameters())
    assert symmetric_rk4.stop_time_s is not None
    assert abs(books.residual_j) < 1e-6 * books.turnover_j


def test_contact_never_pulls_and_leading_shoe_carries_more(symmetric_rk4):
    b = symmetric_rk4.samples
    assert b["left_normal_force_n"].min() >= 0.0 and b["right_normal_force_n"].min() >= 0.0
    turning = (b.time_s > 1.0) & (b.time_s < symmetric_rk4.stop_time_s - 0.05)
    assert np.all(
        b.pivot_force_magnitude("left")[turning] > b.pivot_force_magnitude("right")[turning]
    )


def _mirror_run(defects: Defects, speed: float):
    params = BrakeParameters().with_overrides({"driveline": {"initial_speed_rad_s": speed}})
    stepper = FixedStepStepper(BrakeSetup(params=params, defects=defects), 4e-5)
    return stepper.run(1.0)


def test_mirrored_brake_gives_mirrored_results():
    """Swapping the shoes' defects and reversing the drum mirrors every signal about y."""
    a = _mirror_run(
        Defects(left=ShoeDefect(pivot_radius_change_pct=2.0, initial_angle_deg=-1.0)), 103.5
    )
    b = _mirror_run(
        Defects(right=ShoeDefect(pivot_radius_change_pct=2.0, initial_angle_deg=-1.0)), -103.5
    )
    for left, right in (("left", "right"), ("right", "left")):
        np.testing.assert_allclose(
            b[f"{right}_angle_rad"], a[f"{left}_angle_rad"], rtol=1e-6, atol=1e-12
        )
        np.testing.assert_allclose(
            b[f"{right}_normal_force_n"], a[f"{left}_normal_force_n"], rtol=1e-6, atol=1e-6
        )
        np.testing.assert_allclose(
            b[f"{right}_pivot_fx_n"], -a[f"{left}_pivot_fx_n"], rtol=1e-6, atol=1e-6
        )
        np.testing.assert_allclose(
            b[f"{right}_pivot_fy_n"], a[f"{left}_pivot_fy_n"], rtol=1e-6, atol=1e-6
        )
    np.testing.assert_allclose(b["drum_speed_rad_s"], -a["drum_speed_rad_s"], rtol=1e-9)


def test_friction_direction_decides_which_shoe_leads():
    """Same geometry, reversed rotation: the right shoe becomes the leading one."""
    b = _mirror_run(Defects(), -103.5)
    late = b.time_s > 0.8
    assert np.all(b.pivot_force_magnitude("right")[late] > b.pivot_force_magnitude("left")[late])


@pytest.mark.parametrize("name", ["case5_left_tilted", "case2_left_pivot_in"])  # 1, 5 substeps
def test_same_scenario_twice_gives_identical_arrays(name):
    s = load_scenario(name)
    runs = [stepper_for(s).run(1.0).data for _ in range(2)]
    assert np.array_equal(runs[0], runs[1])


def test_chunked_stepping_equals_one_call():
    s = load_scenario("symmetric")
    whole = stepper_for(s).advance(20_000).data
    chunked = stepper_for(s)
    parts = [chunked.advance(n).data for n in (1, 999, 7000, 12_000)]
    assert np.array_equal(whole, np.concatenate(parts))


def test_fixed_step_converges_to_reference():
    """State error against the reference shrinks as the step shrinks.

    The Kelvin-Voigt force jumps at contact onset, so the error of a fixed step depends on
    where an onset falls inside a step and is not monotonic in dt; the finest step must
    still beat every coarse one by a wide margin. In free flight under the linear ramp the
    shoe angle is a cubic in time, which RK4 integrates exactly.
    """
    s = load_scenario("symmetric")
    times = np.array([0.215, 0.26, 0.3, 1.0])  # free flight, impacting, impacting, contact
    ref = run_reference(s.setup, 1.0, sample_times=times, rtol=1e-11).samples.data
    cols = [L.COL[n] for n in ("left_angle_rad", "right_angle_rad", "drum_speed_rad_s")]
    errors = {}
    for dt in (4e-5, 2e-5, 1e-5, 2.5e-6):
        block = FixedStepStepper(s.setup, dt).run(1.0 + dt).data
        rows = block[np.round(times / dt).astype(int)]
        errors[dt] = np.abs(rows[:, cols] - ref[:, cols]) / np.abs(ref[:, cols]).max(axis=0)
    worst_coarse = max(errors[dt][1:].max() for dt in (4e-5, 2e-5, 1e-5))
    assert errors[2.5e-6][1:].max() < worst_coarse / 4
    assert max(errors[dt][0].max() for dt in errors) < 1e-8


@pytest.mark.slow
def test_first_impact_and_stop_of_default_step_match_reference(symmetric_rk4, symmetric_reference):
    fixed, ref = symmetric_rk4.metrics, symmetric_reference.metrics
    for side in ("left", "right"):
        assert fixed.shoe(side).first_impact_peak_n == pytest.approx(
            ref.shoe(side).first_impact_peak_n, rel=0.01
        )
        assert fixed.shoe(side).period_s == pytest.approx(ref.shoe(side).period_s, rel=0.01)
    assert fixed.stop_time_s == pytest.approx(ref.stop_time_s, rel=0.001)


def test_reference_locates_both_shoes_contacts(symmetric_reference):
    m = symmetric_reference.metrics
    assert m.left.n_impacts >= 5 and m.right.n_impacts >= 5
    b = symmetric_reference.samples
    # the lining never sinks into the drum further than the static load explains
    assert b["left_indentation_m"].max() < 2e-3 and b["right_indentation_m"].max() < 2e-3


def test_rigid_coupling_removes_the_torsional_mode():
    s = load_scenario("symmetric")
    setup = dataclasses.replace(
        s.setup, options=dataclasses.replace(s.setup.options, rigid_coupling=True)
    )
    b = stepper_for(s, setup=setup).run(1.0)
    np.testing.assert_array_equal(b["flywheel_speed_rad_s"], b["drum_speed_rad_s"])
