"""RK4 stages where the shoes ride free skip the contact geometry: same bits, sound bound.

The fixed-step kernel evaluates a stage with the rotors' derivatives only
(``kernel.free_evaluate``) where ``kernel.rides_free`` proves that no shoe force acts:
the drum slides, no tip force, no contact forced on and each indentation provably negative
by the bound ``eps0 + 2 reach |theta - theta0|``. These tests step real states of the
urban cycle both ways and require identical bits, and check the bound against the contact
geometry itself near the drum, where it matters. The states are the study brake's
(the urban cycle with ``brake = "study"``, ``tests/study_cycles.py``): its shoes carry no
tip force between stops, the service brake's carry their springs' and stops'.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from brake_sim_ros.model import contact, kernel, rk4
from brake_sim_ros.model import layout as L
from brake_sim_ros.stream.build import stepper_for
from tests.study_cycles import on_study_brake

BASES = (L.P_SHOE_BASE, L.P_SHOE_BASE + L.SHOE_STRIDE)


def _bound(p: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The free-ride bound of the state ``y`` as the kernel builds it."""
    free = kernel.NOT_FREE.copy()
    for i, base in enumerate(BASES):
        kin = contact.kinematics(
            p, base, y[L.Y_LEFT_ANGLE + i], y[L.Y_LEFT_SPEED + i], y[L.Y_DRUM_ANGLE], 0.0
        )
        free[2 * i] = kin[0]
        free[2 * i + 1] = 2.0 * kernel.lining_reach(p, base)
    return free


def _step(p, y, dt, free, mode, t_knots, f_knots):
    """One RK4 step of ``y`` (both shoes in contact mode ``mode``) with the bound ``free``;
    returns the new state and the stages that rode free."""
    n = y.shape[0]
    work = np.empty((4, n))  # the step's k2, k3, k4 and stage state (rk4_step_call)
    k = [np.empty(n), work[0], work[1], work[2]]
    y_out = np.empty(n)
    out = np.empty((1, L.N_COLUMNS))
    kernel.evaluate(y, p, 0.0, 0.0, 0, mode, mode, k[0], out, -1, 0.0)
    free = free.copy()  # writable, as the kernel's bound: the call the set-up compiled
    rk4.rk4_step_call(
        y, k[0], 0.0, dt, p, 1.0, t_knots, f_knots, 1.0, t_knots, f_knots, 0, mode, mode,
        work, out, y_out, free,
    )  # fmt: skip
    free_stages = 0
    for j, c in enumerate((0.5, 0.5, 1.0)):
        stage = y + c * dt * k[j]
        force = kernel.force(p, L.P_SHOE_BASE, c * dt, t_knots, f_knots, 1.0)
        free_stages += kernel.rides_free(stage, y, free, 0, mode, mode, force, force)
    return y_out, free_stages


@pytest.mark.slow
def test_free_stages_step_the_urban_cycle_with_the_same_bits():
    scenario = on_study_brake("urban")
    stepper = stepper_for(scenario)
    dt = stepper.physics_step_s
    p = stepper.packed_parameters.copy()
    p[L.P_DRIVE_TORQUE] = 80.0  # the controller's drive while accelerating
    no_force = (np.array([0.0, 1.0]), np.zeros(2))
    pressed = (np.array([0.0, 1.0]), np.array([400.0, 400.0]))
    rode_free = refused = 0
    for t_s in (0.5, 4.0, 9.0, 14.0, 19.5, 23.0, 31.0):
        stepper.advance(round(t_s / stepper.sample_period_s) - stepper.sample_index)
        y = stepper.state.copy()
        for mode in (L.CONTACT_OFF, L.CONTACT_AUTO):
            for knots in (no_force, pressed):
                free_y, n_free = _step(p, y, dt, _bound(p, y), mode, *knots)
                full_y, n_full = _step(p, y, dt, kernel.NOT_FREE, mode, *knots)
                assert n_full == 0
                assert free_y.tobytes() == full_y.tobytes(), (t_s, mode, knots[1][0])
                if knots is pressed:
                    assert n_free == 0  # a tip force is never skipped
                rode_free += n_free
                refused += n_free == 0
    # not an empty comparison: most no-force stages rode free, braking ones (in contact) did not
    assert rode_free >= 24 and refused > 14


def test_no_stage_rides_free_with_a_contact_forced_on():
    stepper = stepper_for(on_study_brake("urban"))
    stepper.advance(round(4.0 / stepper.sample_period_s))
    p, y = stepper.packed_parameters, stepper.state
    knots = (np.array([0.0, 1.0]), np.zeros(2))
    _, n_free = _step(p, y, stepper.physics_step_s, _bound(p, y), L.CONTACT_ON, *knots)
    assert n_free == 0


@settings(max_examples=300, deadline=None)
@given(
    side=st.sampled_from((0, 1)),
    theta0_mrad=st.floats(-3.0, 1.0),
    turn_mrad=st.floats(-2.0, 2.0),
)
def test_the_bound_never_admits_a_penetrating_stage(side, theta0_mrad, turn_mrad):
    """Near and across the drum (a shoe from 3 mrad inside its clearance to 1 mrad into
    the drum, turning up to 2 mrad within the stage): wherever the bound says the shoe is
    clear, the contact geometry agrees."""
    p = stepper_for(on_study_brake("urban")).packed_parameters
    base = BASES[side]
    theta0 = theta0_mrad * 1e-3
    theta = theta0 + turn_mrad * 1e-3
    eps0 = contact.kinematics(p, base, theta0, 0.0, 0.0, 0.0)[0]
    eps = contact.kinematics(p, base, theta, 0.0, 0.0, 0.0)[0]
    reach = kernel.lining_reach(p, base)
    if eps0 + 2.0 * reach * abs(theta - theta0) < 0.0:
        assert eps < 0.0
    # the reach bounds the geometry's own rate: |d eps / d theta| <= reach
    assert abs(eps - eps0) <= reach * abs(theta - theta0) * (1.0 + 1e-9) + 1e-15
    assert math.isfinite(eps)
