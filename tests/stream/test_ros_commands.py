"""Actuation-command checks and timeout behaviours of the ROS node: pure logic, no ROS."""

from __future__ import annotations

import math

import numpy as np
import pytest

from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.stream.build import stepper_for
from brake_sim_ros.stream.commands import (
    ActuationPlanner,
    CommandPolicy,
    TimeoutBehaviour,
    check_command,
)

DT = 4e-5
TIMEOUT_STEPS = 5000  # 0.2 s


def covered(segments) -> int:
    return sum(n for n, _ in segments)


# -- checks ---------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("left", "right", "fragment"),
    [
        (math.nan, 0.0, "left_force_n=nan is not a finite number"),
        (0.0, math.inf, "right_force_n=inf is not a finite number"),
        (-math.inf, 0.0, "left_force_n=-inf is not a finite number"),
        (-1.0, 0.0, "negative"),
        (0.0, 2000.5, "exceeds max_actuation_force_n = 2000 N"),
    ],
)
def test_bad_commands_are_rejected_with_a_reason(left, right, fragment):
    reason = check_command(left, right, 2000.0)
    assert reason is not None and fragment in reason


@pytest.mark.parametrize(("left", "right"), [(0.0, 0.0), (2000.0, 2000.0), (12.5, 1999.0)])
def test_good_commands_pass(left, right):
    assert check_command(left, right, 2000.0) is None


def test_policy_and_behaviour_validation():
    assert TimeoutBehaviour.parse("ramp_to_zero") is TimeoutBehaviour.RAMP_TO_ZERO
    with pytest.raises(ValueError, match='allowed "hold", "ramp_to_zero", "profile"'):
        TimeoutBehaviour.parse("stop")
    with pytest.raises(ValueError, match="command_timeout_s"):
        CommandPolicy(timeout_s=0.0)
    with pytest.raises(ValueError, match="command_ramp_rate_n_per_s"):
        CommandPolicy(ramp_rate_n_per_s=math.nan)


# -- planning ----------------------------------------------------------------------------
def test_without_commands_the_profile_drives():
    planner = ActuationPlanner(DT)
    assert planner.segments(0, 250) == [(250, None)]
    assert planner.source(0) == "profile"
    assert planner.segments(0, 0) == []


@pytest.mark.parametrize("behaviour", list(TimeoutBehaviour))
def test_command_window_then_timeout_behaviour(behaviour):
    planner = ActuationPlanner(DT, CommandPolicy(0.2, behaviour, ramp_rate_n_per_s=5000.0))
    assert planner.timeout_steps == TIMEOUT_STEPS
    planner.command((1000.0, 500.0), step=100)
    segs = planner.segments(100, TIMEOUT_STEPS + 10_000)
    assert covered(segs) == TIMEOUT_STEPS + 10_000
    forces = [f for n, f in segs for _ in range(n)]
    assert forces[:TIMEOUT_STEPS] == [(1000.0, 500.0)] * TIMEOUT_STEPS
    assert planner.source(100 + TIMEOUT_STEPS - 1) == "command"
    after = forces[TIMEOUT_STEPS:]
    if behaviour is TimeoutBehaviour.PROFILE:
        assert segs == [(TIMEOUT_STEPS, (1000.0, 500.0)), (10_000, None)]
        assert planner.source(100 + TIMEOUT_STEPS) == "profile"
    elif behaviour is TimeoutBehaviour.HOLD:
        assert segs == [(TIMEOUT_STEPS + 10_000, (1000.0, 500.0))]
        assert planner.source(100 + TIMEOUT_STEPS) == "hold"
    else:
        # per step: F(t) = max(0, F_cmd - rate (t - t_out)), t at the start of the step
        for k in (0, 1, 2500, 4999):
            assert after[k][0] == pytest.approx(max(0.0, 1000.0 - 5000.0 * k * DT))
            assert after[k][1] == pytest.approx(max(0.0, 500.0 - 5000.0 * k * DT))
        assert after[5000] == (0.0, 0.0) and after[-1] == (0.0, 0.0)
        assert segs[-1][1] == (0.0, 0.0) and segs[-1][0] > 1000  # zeros merged
        assert all(f[0] >= 0.0 and f[1] >= 0.0 for f in after)
        assert planner.source(100 + TIMEOUT_STEPS + 10) == "ramp"
        assert planner.source(100 + TIMEOUT_STEPS + 5000) == "zero"


def test_a_new_command_restarts_the_window():
    planner = ActuationPlanner(DT)
    planner.command((100.0, 100.0), step=0)
    planner.segments(0, 1000)
    planner.command((200.0, 200.0), step=1000)
    segs = planner.segments(1000, TIMEOUT_STEPS + 1)
    assert segs == [(TIMEOUT_STEPS, (200.0, 200.0)), (1, None)]


def test_segments_do_not_depend_on_how_steps_are_split():
    planner = ActuationPlanner(DT, CommandPolicy(0.01, TimeoutBehaviour.RAMP_TO_ZERO, 1e5))
    planner.command((300.0, 100.0), step=7)
    whole = [f for n, f in planner.segments(7, 2000) for _ in range(n)]
    pieces = []
    for start in range(7, 2007, 137):
        n = min(137, 2007 - start)
        pieces += [f for m, f in planner.segments(start, n) for _ in range(m)]
    assert pieces == whole


def test_superseded_and_cleared_commands_are_reported_as_dropped():
    planner = ActuationPlanner(DT)
    assert planner.command((1.0, 1.0), 0) is False
    assert planner.command((2.0, 2.0), 0) is True  # the first never reached a step
    planner.segments(0, 10)
    assert planner.command((3.0, 3.0), 10) is False
    assert planner.clear() is True
    assert planner.clear() is False
    assert planner.last_command is None


def test_chunked_stepping_with_commands_equals_one_offline_run():
    """Same commands at the same samples give the same numbers, however the run is cut;
    also when a command above the profile's peak makes the stepper take more substeps."""
    scenario = load_scenario("symmetric")
    policy = CommandPolicy(0.004, TimeoutBehaviour.RAMP_TO_ZERO, 2e5)

    def run(cuts: list[int]) -> np.ndarray:
        stepper = stepper_for(scenario)
        planner = ActuationPlanner(stepper.sample_period_s, policy)
        rows = []
        for i, n in enumerate(cuts):
            if i == 1:
                planner.command((3000.0, 900.0), stepper.sample_index)
            for count, forces in planner.segments(stepper.sample_index, n):
                rows.append(stepper.advance(count, actuation_n=forces).data)
        assert stepper.substeps == 2  # the limit for 3000 N: 28 us in a 39 us sample
        return np.concatenate(rows)

    a = run([500, 1000, 500])
    b = run([500, 1, 250, 249, 250, 250, 500])
    assert a.shape == b.shape == (2000, a.shape[1])
    np.testing.assert_array_equal(a, b)
