"""Contact onset detection is written once (:mod:`brake_sim_ros.analysis.onsets`): the rule
on hand-made samples, and every consumer (impact metrics, contact events, BrakeState flags,
the Rerun sink's state-rate fallback: ``tests/viz/test_rerun_sink.py``) finding exactly the
onsets the shared rule finds."""

from __future__ import annotations

import numpy as np
import pytest

from brake_sim_ros.analysis import contact_events as ce
from brake_sim_ros.analysis.impacts import shoe_metrics
from brake_sim_ros.analysis.onsets import (
    ContactChanges,
    contact_changes,
    crossing_times,
    in_contact,
)
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.run_setup import SampleBlock
from tests.sample_blocks import cut


def _changes(flags: list[int], before: bool | None = None) -> tuple[list[int], list[int]]:
    c = contact_changes(np.array(flags, dtype=bool), before=before)
    return c.onsets.tolist(), c.separations.tolist()


def test_zero_indentation_is_not_contact():
    assert in_contact(np.array([-1e-9, 0.0, 1e-12])).tolist() == [False, False, True]
    assert in_contact(0.0) is False and in_contact(2e-6) is True  # plain bools for messages


def test_changes_with_unknown_and_carried_predecessor():
    flags = [1, 1, 0, 0, 1, 0, 1]
    assert _changes(flags) == ([4, 6], [2, 5])  # unknown: the first sample is no change
    assert _changes(flags, before=False) == ([0, 4, 6], [2, 5])
    assert _changes(flags, before=True) == ([4, 6], [2, 5])
    assert _changes([0, 1], before=True) == ([1], [0])
    assert _changes([]) == ([], [])
    c = contact_changes(np.array([1, 0, 0, 1, 0], dtype=bool), before=False)
    assert c.positions.tolist() == [0, 1, 3, 4]


def test_crossing_time_is_the_linear_zero_crossing():
    t = np.array([0.0, 1.0, 2.0, 3.0])
    eps = np.array([-3.0, 1.0, 2.0, -2.0])
    c = contact_changes(in_contact(eps))
    assert crossing_times(t, eps, c.onsets).tolist() == [0.75]
    assert crossing_times(t, eps, c.separations).tolist() == [2.5]


def _shared(block: SampleBlock, side: str, before: bool | None = None) -> ContactChanges:
    return contact_changes(in_contact(block[f"{side}_indentation_m"]), before=before)


@pytest.mark.parametrize("side", ["left", "right"])
def test_impact_metrics_use_the_shared_onsets(symmetric_impacting, side):
    shared = _shared(symmetric_impacting, side)
    assert shared.onsets.size >= 7  # measured: 8 (left), 7 (right)
    m = shoe_metrics(symmetric_impacting, side, stop_time_s=None)
    t, eps = symmetric_impacting.time_s, symmetric_impacting[f"{side}_indentation_m"]
    np.testing.assert_array_equal(m.onsets_s, crossing_times(t, eps, shared.onsets))
    np.testing.assert_array_equal(m.separations_s, crossing_times(t, eps, shared.separations))
    # each interpolated instant lies between the sample before and the onset sample
    assert np.all((t[shared.onsets - 1] < m.onsets_s) & (m.onsets_s <= t[shared.onsets]))


@pytest.mark.parametrize("sizes", [[250], [1, 7, 4000]])
def test_contact_events_are_the_shared_onsets(symmetric_impacting, sizes):
    detector = ce.ContactEventDetector()
    events = [e for piece in cut(symmetric_impacting, sizes) for e in detector.feed(piece)]
    for shoe, side in enumerate(ce.SHOES):
        shared = _shared(symmetric_impacting, side, before=False)  # a run starts out of contact
        mine = [e for e in events if e.shoe == shoe]
        onsets = [e.sample_index for e in mine if e.kind == ce.KIND_ONSET]
        seps = [e.sample_index for e in mine if e.kind == ce.KIND_SEPARATION]
        assert len(onsets) >= 7  # measured: 8 (left), 7 (right)
        np.testing.assert_array_equal(onsets, symmetric_impacting.first_index + shared.onsets)
        np.testing.assert_array_equal(seps, symmetric_impacting.first_index + shared.separations)


def test_a_contact_at_the_first_sample_is_an_event_but_no_impact():
    """The one place the consumers differ, by definition: a run that starts in contact
    gives a contact event at sample 0 (``before=False``) but no impact (no crossing seen,
    ``before=None``); every later onset is the same for both."""
    data = np.zeros((5, L.N_COLUMNS))
    data[:, L.COL["time_s"]] = np.arange(5) * 0.5
    data[:, L.COL["left_indentation_m"]] = [1.0, -1.0, -1.0, 1.0, 1.0]
    data[:, L.COL["right_indentation_m"]] = -1.0
    block = SampleBlock(data, 0, 0.5)
    flags = in_contact(block["left_indentation_m"])
    assert contact_changes(flags).onsets.tolist() == [3]
    assert contact_changes(flags, before=False).onsets.tolist() == [0, 3]
    assert shoe_metrics(block, "left", stop_time_s=None).onsets_s.tolist() == [1.25]
    events = ce.ContactEventDetector().feed(block)
    assert [(e.sample_index, e.kind) for e in events] == [
        (0, ce.KIND_ONSET),
        (1, ce.KIND_SEPARATION),
        (3, ce.KIND_ONSET),
    ]


def test_brake_state_flags_are_the_shared_rule(symmetric_impacting):
    conversion = pytest.importorskip("brake_sim_ros.stream.conversion", reason="no brake_sim_msgs")
    rows = range(0, len(symmetric_impacting), 7)
    for side in ce.SHOES:
        flags = [
            getattr(conversion.brake_state(symmetric_impacting, r), f"{side}_in_contact")
            for r in rows
        ]
        assert all(type(f) is bool for f in flags)
        expected = in_contact(symmetric_impacting[f"{side}_indentation_m"][list(rows)])
        assert flags == expected.tolist()
        assert any(flags) and not all(flags)


def test_each_right_shoe_column_sits_at_its_stated_offset():
    """The compiled kernels write the right shoe at RIGHT_OF_* from the left shoe's column;
    the named layout must agree for every per-shoe column they write."""
    from brake_sim_ros.model import layout as L

    scalar = {
        L.C_INDENTATION: "indentation_m",
        L.C_NORMAL_FORCE: "normal_force_n",
        L.C_FRICTION_FORCE: "friction_force_n",
        L.C_ACTUATION_FORCE: "actuation_force_n",
        L.C_INDENTATION_RATE: "indentation_rate_m_s",
        L.C_SLIDING_SPEED: "sliding_speed_m_s",
        L.C_SHOE_REGIME: "regime",
    }
    vector = {
        L.C_PIVOT_FX: "pivot_fx_n",
        L.C_PIVOT_FY: "pivot_fy_n",
        L.C_CONTACT_X: "contact_x_m",
        L.C_CONTACT_Y: "contact_y_m",
    }
    for offset, columns in ((L.RIGHT_OF_SCALAR, scalar), (L.RIGHT_OF_VECTOR, vector)):
        for left, name in columns.items():
            assert L.COLUMNS[left] == f"left_{name}"
            assert L.COLUMNS[left + offset] == f"right_{name}"
