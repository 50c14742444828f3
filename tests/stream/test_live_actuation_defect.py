"""Live actuation commands reach a delayed or lagging shoe through its defect, as the
scenario's history does (solvers/fixed_step.py CommandHistory): the node's ``~/actuation``
path is ``FixedStepStepper.advance(actuation_n=...)``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.stream.build import stepper_for

IDLE = 'name = "live"\nduration_s = 1.0\n[actuation]\npeak_force_n = 0.0\n'
COMMAND_N = 300.0


def _live(left: ShoeDefect, before_s: float = 0.1, after_s: float = 0.2):
    """Zero commanded until ``before_s``, then COMMAND_N on both shoes: the blocks after."""
    sc = parse_scenario(IDLE).with_defects(Defects(left=left))
    stepper = stepper_for(sc)
    period = stepper.sample_period_s
    stepper.advance(round(before_s / period), actuation_n=(0.0, 0.0))
    t0 = stepper.sample_index * period
    blocks = [stepper.advance(64, actuation_n=(COMMAND_N, COMMAND_N)) for _ in range(80)]
    return t0, stepper.physics_step_s, blocks


def _column(blocks, name):
    return np.concatenate([b[name] for b in blocks]), np.concatenate([b.time_s for b in blocks])


def test_a_live_command_reaches_a_delayed_shoe_after_its_delay():
    t0, ramp, blocks = _live(ShoeDefect(actuation_delay_ms=50.0))
    left, t = _column(blocks, "left_actuation_force_n")
    right, _ = _column(blocks, "right_actuation_force_n")
    assert np.all(right == COMMAND_N)  # the healthy shoe: at once
    assert np.all(left[t <= t0 + 0.05] == 0.0)
    assert np.all(left[t >= t0 + 0.05 + ramp] == COMMAND_N)


def test_a_live_command_reaches_a_lagging_shoe_through_its_lag():
    """The command is a ramp over one physics step ``h``; a first-order lag ``tau`` turns
    it into ``F (1 - tau/h (e^(-(t - t0 - h)/tau) - e^(-(t - t0)/tau)))`` after the ramp."""
    tau = 0.03
    t0, h, blocks = _live(ShoeDefect(actuation_lag_ms=1e3 * tau))
    left, t = _column(blocks, "left_actuation_force_n")
    after = t >= t0 + h
    x = t[after] - t0
    expected = COMMAND_N * (1.0 - tau / h * (np.exp(-(x - h) / tau) - np.exp(-x / tau)))
    np.testing.assert_allclose(left[after], expected, rtol=1e-9, atol=1e-9)
    assert left[after][0] < 0.01 * COMMAND_N and left[-1] > 0.99 * COMMAND_N
    first = t[np.flatnonzero(left >= (1.0 - math.exp(-1.0)) * COMMAND_N)[0]]
    assert first - t0 == pytest.approx(tau, abs=2 * h)  # 63 % after one time constant


def test_a_shoe_without_delay_or_lag_keeps_the_constant_command():
    _t0, _h, blocks = _live(ShoeDefect(actuation_gain_change_pct=-20.0))
    left, _ = _column(blocks, "left_actuation_force_n")
    assert np.all(left == 0.8 * COMMAND_N)
