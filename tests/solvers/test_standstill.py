"""Stick and slip at standstill (model/standstill.py): invariants through impacts, lock,
rocking and release, in every level that models the drum."""

from __future__ import annotations

import math

import numpy as np
import pytest

from brake_sim_ros.analysis.energy import energy_balance
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.actuation import Actuation, ForceProfile
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.solvers.contact_regime import run_contact_regime
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.solvers.reference import run_reference
from brake_sim_ros.solvers.stability import step_limit

DT = 4e-5
ENERGY_REL = 1e-6
# 20 kN per shoe ramped in 50 ms: the drum locks within a fraction of a second while the
# vehicle (flywheel) still moves.
PANIC = Actuation(ForceProfile.ramp(20_000.0, 0.01, 0.06), ForceProfile.ramp(20_000.0, 0.01, 0.06))
# the published ramp, held, then released from 7.0 s to 7.1 s
RELEASE = ForceProfile((0.0, 0.2, 0.7, 7.0, 7.1), (0.0, 0.0, 1300.0, 1300.0, 0.0))


def _coupling_torque(block, params: BrakeParameters) -> np.ndarray:
    d = params.driveline
    twist = block["flywheel_angle_rad"] - block["drum_angle_rad"]
    slip = block["flywheel_speed_rad_s"] - block["drum_speed_rad_s"]
    return d.coupling_stiffness_n_m_per_rad * twist + d.coupling_damping_n_m_s_per_rad * slip


def _flywheel_residual(block, params: BrakeParameters) -> np.ndarray:
    """Residual of I_f w_f' = -T_c between consecutive samples (trapezoidal rule), N m."""
    torque = _coupling_torque(block, params)
    w = block["flywheel_speed_rad_s"]
    dt = np.diff(block.time_s)
    lhs = params.driveline.flywheel_inertia_kg_m2 * np.diff(w) / dt
    return lhs + 0.5 * (torque[1:] + torque[:-1])


@pytest.fixture(scope="module")
def published():
    stepper = FixedStepStepper(BrakeSetup(), DT)
    return stepper, stepper.run(7.5)


@pytest.fixture(scope="module")
def panic():
    setup = BrakeSetup(actuation=PANIC)
    dt = min(DT, step_limit(setup, 20_000.0).max_step_s)
    stepper = FixedStepStepper(setup, dt)
    return setup, stepper, stepper.run(1.5)


def test_flywheel_obeys_its_equation_at_every_sample_of_the_published_stop(published):
    """Through impacts, the stop and the rocking after it: within 1 % of the peak coupling
    torque at every sample (the old lock zeroed the flywheel: a residual of I_f w_f / dt)."""
    stepper, block = published
    assert stepper.stop_time_s is not None and block.time_s[-1] > stepper.stop_time_s + 0.5
    peak = np.abs(_coupling_torque(block, BrakeParameters())).max()
    assert np.abs(_flywheel_residual(block, BrakeParameters())).max() < 0.01 * peak


def test_flywheel_obeys_its_equation_through_a_panic_stop(panic):
    setup, stepper, block = panic
    assert stepper.wheel_lock_time_s is not None and stepper.wheel_lock_time_s < 0.5
    peak = np.abs(_coupling_torque(block, setup.params)).max()
    assert np.abs(_flywheel_residual(block, setup.params)).max() < 0.01 * peak


def test_panic_stop_takes_at_least_the_momentum_bound(panic):
    """The wheel locks at once, the vehicle does not: its stop takes at least
    (I_f + I_d) w0 / max(brake torque), and the books close through the stick-slip."""
    setup, stepper, block = panic
    d = setup.params.driveline
    fn = block["left_normal_force_n"] + block["right_normal_force_n"]
    torque = setup.params.friction.coefficient * setup.params.shoe.drum_radius_m * fn.max()
    bound = (d.flywheel_inertia_kg_m2 + d.drum_inertia_kg_m2) * d.initial_speed_rad_s / torque
    assert stepper.stop_time_s is not None
    assert stepper.wheel_lock_time_s <= stepper.stop_time_s
    assert stepper.stop_time_s >= bound
    books = energy_balance(block, setup.params)
    assert abs(books.residual_j) < ENERGY_REL * books.turnover_j


def test_energy_books_close_over_the_published_stop_and_the_rocking(published):
    """The flywheel's energy after the stop stays in the flywheel and the spring; only the
    drum's last kinetic energy (<= I_d (v_s/R)^2 / 2) is booked at the stick."""
    _stepper, block = published
    books = energy_balance(block, BrakeParameters())
    assert abs(books.residual_j) < ENERGY_REL * books.turnover_j
    p = BrakeParameters()
    w_lock = p.friction.smoothing_speed_m_s / p.shoe.drum_radius_m
    assert 0.0 < block["lock_loss_j"][-1] <= 0.5 * p.driveline.drum_inertia_kg_m2 * w_lock**2


def test_held_drum_neither_creeps_nor_chatters(published):
    stepper, block = published
    after = block.time_s > stepper.stop_time_s + DT
    assert stepper.breakaways == 0
    assert np.all(block["drum_sticking"][after] == 1.0)
    assert np.all(block["regime"][after] == L.REGIME_STOPPED)
    assert np.all(block["drum_speed_rad_s"][after] == 0.0)
    assert np.ptp(block["drum_angle_rad"][after]) == 0.0
    # the flywheel rocks on the coupling, it is not frozen
    assert np.ptp(block["flywheel_speed_rad_s"][after]) > 0.5


def test_pivot_forces_equal_where_the_coupling_torque_vanishes(published):
    """Held drum: the shoes' static friction carries the coupling torque, so the leading
    and trailing pivot forces differ by an amount odd in that torque and are equal where it
    crosses zero (the published 'equal at standstill')."""
    stepper, block = published
    after = np.flatnonzero(block.time_s > stepper.stop_time_s + 0.05)
    torque = _coupling_torque(block, BrakeParameters())[after]
    diff = (block.pivot_force_magnitude("left") - block.pivot_force_magnitude("right"))[after]
    mean = 0.5 * (block.pivot_force_magnitude("left") + block.pivot_force_magnitude("right"))
    zeros = np.flatnonzero(np.sign(torque[:-1]) != np.sign(torque[1:]))
    assert zeros.size >= 2
    for k in zeros:
        frac = torque[k] / (torque[k] - torque[k + 1])
        at_zero = diff[k] + frac * (diff[k + 1] - diff[k])
        assert abs(at_zero) < 1e-3 * mean[after][k]
    assert np.corrcoef(diff, torque)[0, 1] > 0.99


def test_rocking_decays_at_the_coupling_damping_rate():
    """With the drum held the flywheel is a damped oscillator on the coupling; its speed
    peaks fall by exp(-zeta w_n T_d) per period: a closed-form check of the held state."""
    stepper = FixedStepStepper(BrakeSetup(), DT)
    block = stepper.run(14.0, record_every=25)
    after = block.time_s > stepper.stop_time_s + 0.2
    w = block["flywheel_speed_rad_s"][after]
    d = BrakeParameters().driveline
    wn = math.sqrt(d.coupling_stiffness_n_m_per_rad / d.flywheel_inertia_kg_m2)
    zeta = d.coupling_damping_n_m_s_per_rad / (
        2 * math.sqrt(d.coupling_stiffness_n_m_per_rad * d.flywheel_inertia_kg_m2)
    )
    peaks = np.flatnonzero((w[1:-1] > w[:-2]) & (w[1:-1] >= w[2:]) & (w[1:-1] > 0)) + 1
    assert peaks.size >= 5
    ratios = w[peaks[1:]] / w[peaks[:-1]]
    expected = math.exp(-zeta * wn * 2 * math.pi / (wn * math.sqrt(1 - zeta**2)))
    np.testing.assert_allclose(ratios, expected, rtol=2e-3)


def test_release_after_a_stop_lets_the_drum_turn_again():
    """Releasing the brake at standstill: the capacity falls below the coupling torque, the
    drum breaks away and the wound coupling turns it, in the direction of that torque."""
    setup = BrakeSetup(actuation=Actuation(RELEASE, RELEASE))
    stepper = FixedStepStepper(setup, DT)
    block = stepper.run(8.0)
    assert stepper.stop_time_s is not None and stepper.stop_time_s < 7.0
    assert stepper.breakaways >= 1 and not stepper.locked
    held = (block.time_s > stepper.stop_time_s + 0.01) & (block.time_s < 7.0)
    assert np.all(block["drum_sticking"][held] == 1.0)
    free = block.time_s > 7.2
    assert np.all(block["drum_sticking"][free] == 0.0)
    assert np.ptp(block["drum_angle_rad"][free]) > 1e-3
    assert np.all(block["left_normal_force_n"][free] == 0.0)
    books = energy_balance(block, setup.params)
    assert abs(books.residual_j) < ENERGY_REL * books.turnover_j
    residual = _flywheel_residual(block, setup.params)
    assert np.abs(residual).max() < 0.01 * np.abs(_coupling_torque(block, setup.params)).max()


def test_every_level_applies_the_same_stick_rule():
    """Fixed-step kernel, adaptive reference and quasi-static contact-regime level: the same
    stop, the drum held after it, and the same rocking flywheel."""
    fixed = FixedStepStepper(BrakeSetup(), DT)
    fb = fixed.run(7.5)
    ref = run_reference(BrakeSetup(), 7.5, rtol=1e-8)
    qs = run_contact_regime(BrakeSetup(), 7.5)
    assert ref.stop_time_s == pytest.approx(fixed.stop_time_s, rel=1e-6)
    assert qs.stop_time_s == pytest.approx(fixed.stop_time_s, rel=1e-3)
    for block, stop in ((ref.samples, ref.stop_time_s), (qs.samples, qs.stop_time_s)):
        after = block.time_s > stop + 0.01
        assert np.all(block["drum_speed_rad_s"][after] == 0.0)
        assert np.all(block["drum_sticking"][after] == 1.0)
    # the rocking after the stop: same phase and amplitude (tolerances relative to the
    # amplitude; the fixed-step stick lands at the end of the step that crossed v_s)
    w_end = fb["flywheel_speed_rad_s"][-1]
    amplitude = np.abs(fb["flywheel_speed_rad_s"][fb.time_s > fixed.stop_time_s]).max()
    assert abs(ref.samples["flywheel_speed_rad_s"][-1] - w_end) < 1e-3 * amplitude
    assert abs(qs.samples["flywheel_speed_rad_s"][-1] - w_end) < 1e-2 * amplitude
