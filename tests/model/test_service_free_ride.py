"""The service brake's free ride: RK4 stages whose linings provably exert nothing skip the
contact geometry but still evaluate the tips (return springs, rest stops, pistons and
line), the shoes' motion under them and the tyre: same bits as the full evaluation.

The bound is the study brake's (``eps0 + 2 reach |theta - theta0|``, tests/model/
test_free_ride.py, which also checks it against the contact geometry). These tests step
real states of the service brake (the urban cycle; an application and its release: the
shoes at rest on their stops, approaching the drum, braking, returning and landing) both
ways for identical bits, compare the free evaluation with the full one slot by slot, and
check that a state in contact or a held drum never rides free. With the lining over its
arc (``distributed_lining``) the bound's indentation is the deepest node's (the located
scheme's switch test, ``lining.switching``), and the free ride is the lined evaluation's
where no node presses.
"""

from __future__ import annotations

import numpy as np
import pytest

from brake_sim_ros.model import contact, kernel, rk4
from brake_sim_ros.model import layout as L
from brake_sim_ros.scenarios import load_scenario, on_brake, parse_scenario
from brake_sim_ros.stream.build import stepper_for

BASES = (L.P_SHOE_BASE, L.P_SHOE_BASE + L.SHOE_STRIDE)
_KNOTS = "times_s = [0.0, 0.1, 0.15, 0.25, 0.27]\nforces_n = [0.0, 0.0, 1000.0, 1000.0, 0.0]\n"
# one application to 1000 N per shoe and its release (tests/model/test_service_brake.py)
APPLICATION = (
    'name = "application"\nbrake = "service"\nduration_s = 0.7\n[actuation]\n'
    f'profile = "piecewise"\n[actuation.left]\n{_KNOTS}[actuation.right]\n{_KNOTS}'
)
LINED = "[parameters.service]\ndistributed_lining = true\n"
# before the application (on the stops), approaching, braking, released, returning, landed
APPLICATION_TIMES_S = (0.05, 0.11, 0.13, 0.2, 0.26, 0.28, 0.3, 0.35, 0.45, 0.65)


def _bound(p: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The free-ride bound of the state ``y`` as the kernel builds it on the service brake."""
    free = kernel.NOT_FREE.copy()
    lined = p[L.P_LINING_NODE_STIFFNESS] > 0.0
    for i, base in enumerate(BASES):
        if lined:  # the deepest node's (the located scheme's switch test)
            eps = rk4.shoe_switch(p, i, y, False)[0]
        else:
            eps = contact.kinematics(
                p, base, y[L.Y_LEFT_ANGLE + i], y[L.Y_LEFT_SPEED + i], y[L.Y_DRUM_ANGLE], 0.0
            )[0]
        free[4 + 2 * i] = eps  # the service brake's slots
        free[4 + 2 * i + 1] = 2.0 * kernel.lining_reach(p, base)
    return free


def _rides(y, y0, p, free, mode, fel, fer) -> bool:
    """Whether ``kernel.stage_evaluate`` rides free at ``y`` (both shoes in ``mode``, the
    drum sliding) in a step from ``y0``; never the study brake's ``kernel.rides_free``."""
    assert not kernel.rides_free(y, y0, free, 0, mode, mode, fel, fer)
    out, dydt = np.empty((1, L.N_COLUMNS)), np.empty(y.size)
    return kernel.stage_evaluate(y, y0, p, free, fel, fer, 0, mode, mode, dydt, out, 0.0)


def _step(p, y, t0, dt, free, mode, knots):
    """One RK4 step of ``y`` from ``t0`` (both shoes in contact mode ``mode``, the
    actuation ``knots``: left times, forces, right times, forces) with the bound ``free``;
    returns the new state and the stages that rode free."""
    n = y.shape[0]
    work = np.empty((4, n))  # the step's k2, k3, k4 and stage state (rk4_step_call)
    k = [np.empty(n), work[0], work[1], work[2]]
    y_out = np.empty(n)
    out = np.empty((1, L.N_COLUMNS))
    tl, fl, tr, fr = knots
    fe = (kernel.force(p, BASES[0], t0, tl, fl, 1.0), kernel.force(p, BASES[1], t0, tr, fr, 1.0))
    kernel.evaluate(y, p, fe[0], fe[1], 0, mode, mode, k[0], out, -1, t0)
    free = free.copy()  # writable, as the kernel's bound: the call the set-up compiled
    rk4.rk4_step_call(
        y, k[0], t0, dt, p, 1.0, tl, fl, 1.0, tr, fr, 0, mode, mode,
        work, out, y_out, free,
    )  # fmt: skip
    free_stages = 0
    for j, c in enumerate((0.5, 0.5, 1.0)):
        stage = y + c * dt * k[j]
        t = t0 + c * dt
        fel = kernel.force(p, BASES[0], t, tl, fl, 1.0)
        fer = kernel.force(p, BASES[1], t, tr, fr, 1.0)
        free_stages += _rides(stage, y, p, free, mode, fel, fer)
    return y_out, free_stages


def _compare(p, y, t0, dt, knots) -> tuple[int, int]:
    """Steps ``y`` with and without the bound in both modes a free ride may take: the
    same bits; returns (stages that rode free, steps where none did)."""
    rode_free = refused = 0
    for mode in (L.CONTACT_OFF, L.CONTACT_AUTO):
        free_y, n_free = _step(p, y, t0, dt, _bound(p, y), mode, knots)
        full_y, n_full = _step(p, y, t0, dt, kernel.NOT_FREE, mode, knots)
        assert n_full == 0
        assert free_y.tobytes() == full_y.tobytes(), (t0, mode)
        rode_free += n_free
        refused += n_free == 0
    return rode_free, refused


def _in_contact(p: np.ndarray, y: np.ndarray) -> bool:
    """Whether either lining touches the drum at ``y`` (a node of a lining over its arc)."""
    if p[L.P_LINING_NODE_STIFFNESS] > 0.0:
        return any(rk4.shoe_switch(p, i, y, False)[0] > 0.0 for i in range(2))
    return any(
        contact.kinematics(p, base, y[L.Y_LEFT_ANGLE + i], 0.0, y[L.Y_DRUM_ANGLE], 0.0)[0] > 0.0
        for i, base in enumerate(BASES)
    )


@pytest.mark.slow
def test_free_stages_step_the_service_urban_cycle_with_the_same_bits():
    stepper = stepper_for(on_brake(load_scenario("urban"), "service"))
    dt = stepper.physics_step_s
    p = stepper.packed_parameters.copy()
    p[L.P_DRIVE_TORQUE] = 80.0  # the controller's drive while accelerating
    one_s = np.array([0.0, 60.0])
    no_force = (one_s, np.zeros(2), one_s, np.zeros(2))
    pressed = (one_s, np.full(2, 400.0), one_s, np.full(2, 400.0))
    rode_free = refused = 0
    for t_s in (0.5, 4.0, 9.0, 10.5, 14.0, 19.5, 23.0, 31.0):
        stepper.advance(round(t_s / stepper.sample_period_s) - stepper.sample_index)
        y = stepper.state.copy()
        for knots in (no_force, pressed):
            n_free, n_refused = _compare(p, y, t_s, dt, knots)
            if _in_contact(p, y):
                assert n_free == 0  # a lining in contact is never skipped
            rode_free += n_free
            refused += n_refused
    # not an empty comparison: most stages rode free, those braking (in contact) did not
    assert rode_free >= 60 and refused >= 4


@pytest.mark.slow
@pytest.mark.parametrize("lining", ["point", "arc"])
def test_free_stages_step_applications_and_releases_with_the_same_bits(lining):
    """The shoes on their rest stops, leaving them, approaching the drum under a rising
    line pressure, braking, released and returning to land on their stops: the stages that
    ride free (clear of the drum: also approaching and returning, whose tips move the
    shoes) give the full evaluation's bits, those in contact never ride free. With the
    point contact and with the lining over its arc."""
    scenario = parse_scenario(APPLICATION + (LINED if lining == "arc" else ""))
    stepper = stepper_for(scenario)
    dt = stepper.physics_step_s
    p = stepper.packed_parameters
    knots = scenario.setup.actuation.as_arrays()
    rode_free = refused = moving_free = 0
    for t_s in APPLICATION_TIMES_S:
        stepper.advance(round(t_s / stepper.sample_period_s) - stepper.sample_index)
        y = stepper.state.copy()
        t0 = stepper.sample_index * stepper.sample_period_s
        n_free, n_refused = _compare(p, y, t0, dt, knots)
        if _in_contact(p, y):
            assert n_free == 0
        elif abs(y[L.Y_LEFT_SPEED]) > 1e-3:  # a shoe moving under its tips, clear
            moving_free += n_free
        rode_free += n_free
        refused += n_refused
    assert rode_free >= 20 and refused >= 2 and moving_free >= 6


@pytest.mark.slow
@pytest.mark.parametrize("lining", ["point", "arc"])
def test_the_free_evaluation_is_the_full_one_where_the_bound_holds(lining):
    """``kernel.stage_evaluate``'s free ride against ``kernel.evaluate`` on the same state,
    every slot of the derivative bit for bit (but the sign of a zero), over the
    application's run (every 2 ms) wherever it rides free at the state itself (no turn
    since the bound's state). With the point contact and with the lining over its arc."""
    scenario = parse_scenario(APPLICATION + (LINED if lining == "arc" else ""))
    stepper = stepper_for(scenario)
    p = stepper.packed_parameters
    tl, fl, tr, fr = scenario.setup.actuation.as_arrays()
    out = np.empty((1, L.N_COLUMNS))
    compared = pushed = 0
    while stepper.time_s < scenario.duration_s - 0.002:
        stepper.advance(round(0.002 / stepper.sample_period_s))
        y = stepper.state.copy()
        t = stepper.time_s
        fel = kernel.force(p, BASES[0], t, tl, fl, 1.0)
        fer = kernel.force(p, BASES[1], t, tr, fr, 1.0)
        for mode in (L.CONTACT_OFF, L.CONTACT_AUTO):
            full, free = np.empty(y.shape[0]), np.empty(y.shape[0])
            bound = _bound(p, y)
            if not kernel.stage_evaluate(y, y, p, bound, fel, fer, 0, mode, mode, free, out, t):
                continue
            kernel.evaluate(y, p, fel, fer, 0, mode, mode, full, out, -1, t)
            # the same bits, but for the sign of a zero (the drum's torque from a lining that
            # exerts nothing: -0.0 or 0.0), which adds to the state as the other zero does
            assert np.array_equal(free, full), (t, mode)
            nonzero = full != 0.0
            assert free[nonzero].tobytes() == full[nonzero].tobytes(), (t, mode)
            compared += 1
            pushed += free[L.Y_LEFT_SPEED] != 0.0  # the tips turn the shoe: not zeros
    assert compared >= 400  # most of the 0.7 s: all but the ~0.15 s in contact
    assert pushed >= 100  # off its stop (approaching, returning) or before it settles


def test_no_stage_rides_free_with_a_contact_forced_on_or_a_held_drum():
    stepper = stepper_for(parse_scenario(APPLICATION))
    stepper.advance(round(0.05 / stepper.sample_period_s))
    p, y = stepper.packed_parameters, stepper.state
    free = _bound(p, y)
    out, dydt = np.empty((1, L.N_COLUMNS)), np.empty(y.size)

    def rides(stuck, mode_left):
        modes = (mode_left, L.CONTACT_AUTO)
        return kernel.stage_evaluate(y, y, p, free, 20.0, 20.0, stuck, *modes, dydt, out, 0.0)

    assert rides(0, L.CONTACT_AUTO) and rides(0, L.CONTACT_OFF)
    assert not rides(0, L.CONTACT_ON) and not rides(1, L.CONTACT_AUTO)
    assert not kernel.stage_evaluate(
        y, y, p, kernel.NOT_FREE, 20.0, 20.0, 0, L.CONTACT_AUTO, L.CONTACT_AUTO, dydt, out, 0.0
    )
