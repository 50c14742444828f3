"""Real-time budget check and its calibration (ROS-free)."""

from __future__ import annotations

import itertools
import math

import pytest

from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.solvers.realtime import (
    MIN_CALIBRATION_CHUNKS,
    STEPPER_SHARE,
    CostStats,
    calibrate_chunk_cost,
    check_realtime,
    measure_chunk_costs,
)

DT = 1 / 25_600  # the default sample period
CHUNK = 256  # 100 Hz chunks at 25.6 kHz: 10 ms of simulated time each


def test_a_cheap_stepper_fits_and_the_message_gives_its_headroom():
    verdict = check_realtime(
        130e-6, sample_period_s=DT, chunk_samples=CHUNK, real_time_factor=1.0, label="scenario 'x'"
    )
    assert verdict.ok
    assert verdict.chunk_period_s == pytest.approx(0.01)
    assert verdict.budget_s == pytest.approx(STEPPER_SHARE * 0.01)
    # the largest factor: share x 10 ms / 130 us
    assert verdict.max_real_time_factor == pytest.approx(STEPPER_SHARE * 0.01 / 130e-6)
    assert "130 us" in verdict.message and "scenario 'x'" in verdict.message


def test_a_stepper_over_its_share_is_refused_with_cost_budget_and_remedy():
    verdict = check_realtime(130e-6, sample_period_s=DT, chunk_samples=CHUNK, real_time_factor=50.0)
    # at 50x a chunk spans 200 us; half of it (100 us) is less than the 130 us it costs
    assert not verdict.ok
    assert "costs 130 us" in verdict.message and "(100 us)" in verdict.message
    assert f"at most {STEPPER_SHARE * 0.01 / 130e-6:.3g}" in verdict.message
    assert "faster solver preset or a lower sample rate" in verdict.message


def test_the_boundary_is_the_share_of_the_chunk_period():
    budget = STEPPER_SHARE * CHUNK * DT  # at factor 1
    at_factor_1 = {"sample_period_s": DT, "chunk_samples": CHUNK, "real_time_factor": 1.0}
    assert check_realtime(budget, **at_factor_1).ok
    assert not check_realtime(budget * 1.001, **at_factor_1).ok


def test_as_fast_as_possible_has_nothing_to_keep_up_with():
    assert check_realtime(1.0, sample_period_s=DT, chunk_samples=CHUNK, real_time_factor=0.0).ok


@pytest.mark.parametrize(
    "kwargs",
    [
        {"chunk_cost_s": 0.0},
        {"chunk_cost_s": math.nan},
        {"sample_period_s": -1.0},
        {"chunk_samples": 0},
        {"real_time_factor": -1.0},
        {"real_time_factor": math.inf},
    ],
)
def test_nonsense_inputs_are_refused(kwargs):
    args = {
        "chunk_cost_s": 1e-4,
        "sample_period_s": DT,
        "chunk_samples": CHUNK,
        "real_time_factor": 1.0,
    }
    args.update(kwargs)
    cost = args.pop("chunk_cost_s")
    with pytest.raises(ValueError, match="allowed"):
        check_realtime(cost, **args)


def test_cost_statistics():
    s = CostStats.of([1.0, 2.0, 3.0, 4.0, 100.0])
    assert (s.n_chunks, s.median_s, s.max_s) == (5, 3.0, 100.0)
    assert s.median_s <= s.p99_s <= s.p999_s <= s.max_s


def test_measurement_times_each_advance_and_respects_its_budget():
    """A fake clock that advances 1 s per reading: each chunk costs exactly 1 s, and the
    wall budget stops the measurement once min_chunks were taken."""
    ticks = itertools.count()
    stepper = FixedStepStepper(BrakeSetup(), DT)
    costs = measure_chunk_costs(
        stepper, 10, max_chunks=100, wall_budget_s=5.0, min_chunks=2, clock=lambda: next(ticks)
    )
    # readings: start 0; chunk 1 at 1 and 2, check 3; chunk 2 at 4 and 5, check 6 >= 5
    assert list(costs) == [1.0, 1.0]
    assert stepper.sample_index == 20


def test_calibration_steps_the_contact_code_and_takes_enough_chunks():
    stepper = FixedStepStepper(BrakeSetup(), DT)
    stats = calibrate_chunk_cost(stepper, CHUNK, force_n=2600.0)
    assert stats.n_chunks >= MIN_CALIBRATION_CHUNKS
    assert 0 < stats.median_s <= stats.max_s
    # driven by 2600 N from the start: at the substeps that force needs (limit 32 us)
    assert stepper.limit_force_n == 2600.0 and stepper.substeps == 2
    assert stepper.sample_index == 1 + stats.n_chunks * CHUNK
