"""Remaining useful life labels (datasets/life.py): failure times worked out by hand from
the laws, then the ``rul [s]`` column of a real run's Parquet file read back by pyarrow."""

from __future__ import annotations

import json
import math

import numpy as np
import pyarrow.parquet as pq
import pytest

from brake_sim_ros.datasets import life, parquet
from brake_sim_ros.model.catalogue import Growth
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.stream.build import stepper_for
from tests.sample_blocks import scenario_table

TIMES = np.arange(0, 3001) * 1e-3  # 0 .. 3 s in ms
PIVOT = "pivot_radius_change"  # service limit 3 %
FRICTION = "friction_change"  # service limit -50 %


def _pivot(final: float, growth: Growth) -> Defects:
    return Defects(
        left=ShoeDefect(pivot_radius_change_pct=final), growth=((PIVOT, "left", growth),)
    )


def _fail(d: Defects, times=TIMES) -> life.Failure:
    return life.failure(d, times, d.label_series(times))


def test_a_linear_growth_fails_when_it_reaches_the_service_limit_within_the_run():
    # 0 at 1 s, +2 %/s: 3 % at 1 + 3 / 2 = 2.5 s
    f = _fail(_pivot(4.0, Growth(1.0, "linear", rate_per_s=2.0)))
    assert (f.kind, f.location, f.source, f.service_limit, f.unit) == (
        PIVOT,
        "left",
        "run",
        3.0,
        "%",
    )
    assert f.time_s == pytest.approx(2.5, abs=1e-3)  # the first sample at or past it
    rul = life.rul_series(TIMES, f)
    assert rul[0] == pytest.approx(2.5, abs=1e-3)
    assert rul[1000] == pytest.approx(1.5, abs=1e-3)
    assert np.all(rul[f.time_s <= TIMES] == 0.0)
    assert np.all(np.diff(rul) <= 0.0)


def test_a_run_cut_short_takes_the_failure_from_the_law():
    # exponential from 0.5 % at 0.5 s, doubling every 0.5 s: 3 % after log2(6) doublings
    d = _pivot(5.0, Growth(0.5, "exponential", doubling_time_s=0.5, start=0.5))
    short = TIMES[TIMES <= 1.0]
    f = _fail(d, short)
    assert f.source == "law"
    assert f.time_s == pytest.approx(0.5 + 0.5 * math.log2(6.0), rel=1e-12)
    assert life.rul_series(short, f)[0] == pytest.approx(f.time_s, rel=1e-12)


def test_a_defect_that_stays_below_its_limit_leaves_the_life_unknown():
    f = _fail(_pivot(2.0, Growth(0.0, "linear", rate_per_s=1.0)))
    assert (f.source, f.kind) == ("censored", "")
    assert math.isnan(f.time_s)
    assert np.all(np.isnan(life.rul_series(TIMES, f)))
    assert _fail(Defects()).source == "censored"  # a healthy brake
    assert f.as_dict()["time_s"] is None  # JSON has no NaN


def test_a_signed_limit_is_reached_only_in_its_direction():
    fade = Defects(
        left=ShoeDefect(friction_change_pct=-60.0),
        growth=((FRICTION, "left", Growth(0.0, "linear", rate_per_s=40.0)),),
    )
    f = _fail(fade)
    assert (f.kind, f.source) == (FRICTION, "run")
    assert f.time_s == pytest.approx(50.0 / 40.0, abs=1e-3)
    gain = Defects(
        left=ShoeDefect(friction_change_pct=+50.0),  # more friction: not the fade limit
        growth=((FRICTION, "left", Growth(0.0, "linear", rate_per_s=40.0)),),
    )
    assert _fail(gain).source == "censored"


def test_the_first_defect_to_reach_its_limit_ends_the_life():
    d = Defects(
        left=ShoeDefect(pivot_radius_change_pct=3.0, friction_change_pct=-50.0),
        growth=(
            (PIVOT, "left", Growth(2.0)),  # a step at 2 s
            (FRICTION, "left", Growth(0.0, "linear", rate_per_s=25.0)),  # -50 % at 2.0 s too
        ),
    )
    f = _fail(d)
    assert f.time_s == pytest.approx(2.0, abs=1e-3)
    assert f.kind == PIVOT  # a tie goes to catalogue order
    later = Defects(
        left=ShoeDefect(pivot_radius_change_pct=3.0), growth=((PIVOT, "left", Growth(2.5)),)
    )
    assert _fail(later).time_s == pytest.approx(2.5, abs=1e-3)


def test_a_run_file_counts_its_life_down_to_the_failure(tmp_path):
    d = _pivot(4.0, Growth(0.2, "linear", rate_per_s=10.0))  # 3 % at 0.5 s
    sc = load_scenario("symmetric").with_defects(d)
    run = stepper_for(sc).run(0.8, record_every=64)
    table = scenario_table(sc, run)
    path = tmp_path / "run.parquet"
    parquet.write_history(path, table)
    back = pq.read_table(path)
    t = back["time_s"].to_numpy()
    rul = back[life.RUL_COLUMN].to_numpy()
    meta = json.loads(back.schema.metadata[parquet.METADATA_KEY])["life"]
    fail_t = t[np.argmax(t >= 0.5 - 1e-12)]  # the first recorded sample at or past 0.5 s
    assert np.allclose(rul, np.maximum(0.0, fail_t - t), rtol=0, atol=1e-12)
    assert rul[0] > 0.45 and rul[-1] == 0.0
    assert (meta["kind"], meta["source"], meta["service_limit"]) == (PIVOT, "run", 3.0)
    assert meta["time_s"] == fail_t


def test_an_accelerated_life_runs_to_failure_with_its_rul_counting_down():
    """The built-in run to failure: downhill drag with both linings wearing by their
    friction work. The leading (left) lining, which does about twice the trailing one's
    work, reaches its 3.4 mm service limit first, within the run; the RUL counts down to
    that sample and is 0 from it on."""
    sc = load_scenario("downhill_wear")
    run = stepper_for(sc).run(sc.duration_s, record_every=256)
    table = scenario_table(sc, run)
    t = table["time_s"].to_numpy()
    left = table["defect:lining_wear:left [mm]"].to_numpy()
    right = table["defect:lining_wear:right [mm]"].to_numpy()
    assert np.all(np.diff(left) >= 0.0) and np.all(np.diff(right) >= 0.0)  # wear only grows
    meta = json.loads(table.schema.metadata[parquet.METADATA_KEY])["life"]
    assert (meta["kind"], meta["location"], meta["source"]) == ("lining_wear", "left", "run")
    failed = int(np.argmax(left >= 3.4))
    assert meta["time_s"] == t[failed] and 0.0 < t[failed] < sc.duration_s
    assert right[failed] < 3.4  # the trailing lining is far from its limit then
    assert right[failed] / left[failed] == pytest.approx(0.5, abs=0.1)  # about half the work
    rul = table[life.RUL_COLUMN].to_numpy()
    np.testing.assert_array_equal(rul, np.maximum(0.0, t[failed] - t))
