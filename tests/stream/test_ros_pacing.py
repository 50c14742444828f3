"""Pacing of the ROS node against the wall clock: pure logic, no ROS, no real clock."""

from __future__ import annotations

import random

import pytest

from brake_sim_ros.ros.pacing import Pacer, PacingMode

DT = 4e-5  # 25 kHz
CHUNK = 250  # 100 chunks per simulated second


def run_ticks(
    pacer: Pacer,
    tick_times: list[float],
    *,
    step: int = 0,
    max_chunks: int = 8,
    end_step: int | None = None,
) -> int:
    for now in tick_times:
        step += pacer.plan(now, step, CHUNK, max_chunks, end_step).steps
    return step


def test_modes():
    assert Pacer(DT).mode is PacingMode.REAL_TIME
    assert Pacer(DT, real_time_factor=0.0).mode is PacingMode.AS_FAST_AS_POSSIBLE
    assert Pacer(DT, paused=True).mode is PacingMode.PAUSED
    assert Pacer(DT, real_time_factor=0.0, paused=True).mode is PacingMode.PAUSED


def test_target_follows_elapsed_wall_time_times_factor():
    pacer = Pacer(DT, real_time_factor=2.0)
    pacer.restart(100.0, 1000)
    assert pacer.target_step(100.0) == 1000
    assert pacer.target_step(100.5) == 1000 + round(0.5 * 2.0 / DT)
    assert pacer.target_step(99.0) == 1000  # a clock reading before the anchor is not negative


def test_jittery_ticks_do_not_drift():
    """Thousands of jittery 5 ms ticks end exactly where elapsed time x factor says."""
    rng = random.Random(1)
    pacer = Pacer(DT)
    pacer.restart(0.0, 0)
    times, t = [], 0.0
    for _ in range(4000):
        t += 0.005 + rng.uniform(-0.002, 0.004)
        times.append(t)
    step = run_ticks(pacer, times)
    target = pacer.target_step(times[-1])
    # only whole chunks are taken, so at most one chunk short of the target, never ahead
    assert 0 <= target - step < CHUNK
    assert target == int(times[-1] / DT + 1e-9)


def test_late_tick_catches_up_with_several_chunks():
    pacer = Pacer(DT)
    pacer.restart(0.0, 0)
    assert pacer.plan(0.010, 0, CHUNK, 8).steps == CHUNK
    plan = pacer.plan(0.045, CHUNK, CHUNK, 8)  # 35 ms late
    assert plan.steps == 3 * CHUNK
    assert plan.behind_steps == round(0.045 / DT) - 4 * CHUNK
    assert plan.slipped_steps == 0


def test_only_whole_chunks_before_the_end():
    pacer = Pacer(DT)
    pacer.restart(0.0, 0)
    assert pacer.plan(0.009, 0, CHUNK, 8).steps == 0
    assert pacer.plan(0.019, 0, CHUNK, 8).steps == CHUNK


def test_catch_up_is_capped_per_tick_and_finishes_later():
    pacer = Pacer(DT, max_lag_s=1.0)
    pacer.restart(0.0, 0)
    plan = pacer.plan(0.1, 0, CHUNK, 4)  # 10 chunks due, 4 allowed
    assert plan.steps == 4 * CHUNK
    assert plan.behind_steps == 6 * CHUNK
    step = run_ticks(pacer, [0.1, 0.101, 0.102], max_chunks=4)
    assert step == 10 * CHUNK  # caught up without dropping anything


def test_a_long_stall_slips_instead_of_bursting():
    pacer = Pacer(DT, max_lag_s=0.5)
    pacer.restart(0.0, 0)
    plan = pacer.plan(2.0, 0, CHUNK, 4)  # starved for 2 s
    assert plan.steps == 4 * CHUNK
    assert plan.slipped_steps == round(2.0 / DT) - 4 * CHUNK
    # on time again right after the slip: nothing more due until the next chunk
    assert pacer.plan(2.0, 4 * CHUNK, CHUNK, 4).steps == 0
    assert pacer.deadline_s(4 * CHUNK) == pytest.approx(2.0)


def test_end_step_bounds_the_run_and_allows_a_final_partial_chunk():
    pacer = Pacer(DT)
    pacer.restart(0.0, 0)
    end = CHUNK + 100
    assert pacer.plan(0.005, 0, CHUNK, 8, end).steps == 0
    assert pacer.plan(0.011, 0, CHUNK, 8, end).steps == CHUNK
    assert pacer.plan(0.013, CHUNK, CHUNK, 8, end).steps == 0  # the last 100 are not due yet
    assert pacer.plan(0.014, CHUNK, CHUNK, 8, end).steps == 100  # the final, partial chunk
    assert pacer.plan(0.9, end, CHUNK, 8, end).steps == 0
    assert pacer.plan(0.9, 0, CHUNK, 8, end).steps == end  # late: everything up to the end


def test_as_fast_as_possible_offers_the_budget_up_to_the_end():
    pacer = Pacer(DT, real_time_factor=0.0)
    assert pacer.plan(0.0, 0, CHUNK, 8).steps == 8 * CHUNK
    assert pacer.plan(0.0, 0, CHUNK, 8, end_step=300).steps == 300
    with pytest.raises(RuntimeError):
        pacer.target_step(1.0)


def test_paused_takes_nothing_and_unpausing_does_not_jump():
    pacer = Pacer(DT)
    pacer.restart(0.0, 0)
    pacer.set_paused(True, 1.0, 5000)
    assert pacer.plan(10.0, 5000, CHUNK, 8).steps == 0
    pacer.set_paused(False, 10.0, 5000)
    assert pacer.target_step(10.0) == 5000
    assert pacer.plan(10.010, 5000, CHUNK, 8).steps == CHUNK


def test_factor_change_reanchors_at_the_current_step():
    pacer = Pacer(DT)
    pacer.restart(0.0, 0)
    pacer.set_real_time_factor(10.0, 1.0, 25_000)
    assert pacer.target_step(1.0) == 25_000
    assert pacer.target_step(1.1) == 25_000 + round(1.0 / DT)
    assert pacer.chunk_wall_period_s(CHUNK) == pytest.approx(0.001)


def test_deadline_of_a_step():
    pacer = Pacer(DT, real_time_factor=0.5)
    pacer.restart(3.0, 100)
    assert pacer.deadline_s(100 + CHUNK) == pytest.approx(3.0 + CHUNK * DT / 0.5)


@pytest.mark.parametrize("factor", [-1.0, float("nan"), float("inf")])
def test_invalid_factor_is_refused(factor):
    with pytest.raises(ValueError, match="real_time_factor"):
        Pacer(DT, real_time_factor=factor)
    pacer = Pacer(DT)
    with pytest.raises(ValueError, match="real_time_factor"):
        pacer.set_real_time_factor(factor, 0.0, 0)
    assert pacer.real_time_factor == 1.0


def test_invalid_arguments_are_refused():
    with pytest.raises(ValueError):
        Pacer(0.0)
    with pytest.raises(ValueError):
        Pacer(DT, max_lag_s=0.0)
    with pytest.raises(ValueError):
        Pacer(DT).plan(0.0, 0, 0, 1)


@pytest.mark.slow
def test_pure_ros_modules_do_not_import_rclpy():
    """pacing, commands, parameters, conversion and diagnostics stay testable without DDS."""
    import subprocess
    import sys

    code = (
        "import sys, brake_sim_ros.ros, brake_sim_ros.ros.pacing, brake_sim_ros.stream.commands,"
        " brake_sim_ros.stream.parameters\n"
        "try:\n    import brake_sim_ros.stream.conversion, brake_sim_ros.ros.diagnostics\n"
        "except ImportError:\n    pass  # message packages not installed\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] == 'rclpy'))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
