"""The pure parts behind the Rerun sink: a PivotForceChunk read from its message, the
window of recent pivot-force samples the impact markers and the drawing look up, and the
BrakeState scalars. Messages are read by attribute, so plain namespaces stand for them."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("rerun")

from brake_sim_ros.viz import entities as E
from brake_sim_ros.viz.pivot_samples import PivotChunk, RecentPivotForces
from brake_sim_ros.viz.series import state_scalars
from brake_sim_ros.viz.settings import RerunSinkError

RATE_HZ = 1000.0  # 1 ms a sample: sample k at k ms


def chunk_msg(first: int, magnitude_left: list[float], *, rate_hz: float = RATE_HZ):
    """A PivotForceChunk stamped as at RATE_HZ: left |F| as given, fx = |F|, fy = 0;
    right |F| = 2 x left."""
    n = len(magnitude_left)
    left = np.asarray(magnitude_left, dtype=float)
    ns = first * round(1e9 / RATE_HZ)
    return SimpleNamespace(
        header=SimpleNamespace(stamp=SimpleNamespace(sec=ns // 10**9, nanosec=ns % 10**9)),
        sample_rate_hz=rate_hz,
        first_sample_index=first,
        left_magnitude_n=left,
        left_fx_n=list(left),  # lists and arrays alike
        left_fy_n=np.zeros(n),
        right_magnitude_n=2 * left,
        right_fx_n=2 * left,
        right_fy_n=np.zeros(n),
    )


def test_chunk_reads_every_series_and_its_times():
    chunk = PivotChunk.from_msg(chunk_msg(2000, [1.0, 5.0, 3.0]))
    assert (chunk.first_index, chunk.size) == (2000, 3)
    assert set(chunk.columns) == {(s, k) for s in E.SIDES for k in E.PIVOT_SERIES}
    np.testing.assert_array_equal(chunk.columns[("right", "magnitude")], [2.0, 10.0, 6.0])
    assert chunk.start_ns == 2 * 10**9
    assert chunk.end_ns == 2 * 10**9 + 2 * 10**6  # last sample 2 ms later


def test_chunk_refuses_a_bad_rate_and_unequal_arrays():
    with pytest.raises(RerunSinkError, match=r"sample_rate_hz=0\.0"):
        PivotChunk.from_msg(chunk_msg(0, [1.0], rate_hz=0.0))
    msg = chunk_msg(7, [1.0, 2.0])
    msg.right_fy_n = np.zeros(3)
    with pytest.raises(RerunSinkError, match=r"at sample 7: arrays of different lengths \[2, 3\]"):
        PivotChunk.from_msg(msg)


def test_recent_forces_by_sample_index():
    recent = RecentPivotForces()
    recent.add(PivotChunk.from_msg(chunk_msg(0, [1.0, 9.0, 2.0])))
    recent.add(PivotChunk.from_msg(chunk_msg(3, [4.0, 7.0])))
    assert recent.at(1) == {"left": (9.0, 0.0), "right": (18.0, 0.0)}
    assert recent.at(4) == {"left": (7.0, 0.0), "right": (14.0, 0.0)}
    assert recent.at(5) is None
    # the largest |F| in (after, upto], across chunks; after None: from the first held
    assert recent.peak_since("left", None, 4) == (1, 9.0)
    assert recent.peak_since("left", 1, 4) == (4, 7.0)
    assert recent.peak_since("right", 1, 3) == (3, 8.0)
    assert recent.peak_since("left", 4, 9) is None


def test_recent_forces_keep_the_samples_after_a_state():
    recent = RecentPivotForces()
    recent.add(PivotChunk.from_msg(chunk_msg(0, [1.0, 9.0])))
    recent.add(PivotChunk.from_msg(chunk_msg(2, [4.0, 3.0])))
    recent.keep_after(1)  # sample 1 is in the first chunk: kept
    assert recent.at(0) is not None
    recent.keep_after(2)  # the first chunk's samples all precede sample 2: dropped
    assert recent.at(1) is None and recent.at(2) is not None
    recent.keep_after(10)  # the last chunk stays, whatever the state's sample
    assert recent.at(3) == {"left": (3.0, 0.0), "right": (6.0, 0.0)}
    recent.clear()
    assert recent.at(3) is None


def test_state_scalars_units():
    sides = {}
    for side, sign in (("left", 1.0), ("right", -1.0)):
        sides |= {
            f"{side}_shoe_angle_rad": sign * math.radians(2.0),
            f"{side}_indentation_m": sign * 3e-6,
            f"{side}_normal_force_n": 100.0,
            f"{side}_friction_force_n": -30.0,
            f"{side}_actuation_force_n": 500,
            f"{side}_in_contact": side == "left",
        }
    msg = SimpleNamespace(flywheel_speed_rad_s=10.0, drum_speed_rad_s=9.5, regime=2, **sides)
    values = state_scalars(msg)
    assert list(values) == E.state_paths()
    assert values[f"{E.SHOE_ANGLE}/right"] == pytest.approx(-2.0)  # deg
    assert values[f"{E.INDENTATION}/left"] == pytest.approx(3.0)  # um
    assert values[f"{E.CONTACT}/left"] == 1.0 and values[f"{E.CONTACT}/right"] == 0.0
    assert values[f"{E.CONTACT}/regime"] == 2.0
    assert all(type(v) is float for v in values.values())
