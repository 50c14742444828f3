"""Contact events from sample blocks: against the analysis module and independent of chunking.

The detector is pure numpy (no ROS); the ROS stream carries its events (see
``tests/ros/test_node_events.py`` for the node).
"""

from __future__ import annotations

import numpy as np
import pytest

from brake_sim_ros.analysis import contact_events as ce
from brake_sim_ros.analysis.contact_events import ContactEventDetector
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.stream.run import RunResult
from tests.sample_blocks import cut


def detect(blocks: list[SampleBlock]) -> list[ce.ContactEvent]:
    detector = ContactEventDetector()
    return [e for b in blocks for e in detector.feed(b)]


def test_onsets_and_peaks_match_the_impact_analysis(symmetric_run: RunResult, symmetric_impacting):
    events = detect(cut(symmetric_impacting, [250]))  # the node's default chunk: 10 ms
    assert events == sorted(events, key=lambda e: (e.sample_index, e.shoe))
    dt = symmetric_impacting.sample_period_s
    t = symmetric_impacting.time_s
    for shoe, side in enumerate(ce.SHOES):
        metrics = symmetric_run.metrics.shoe(side)
        mine = [e for e in events if e.shoe == shoe]
        onsets = [e for e in mine if e.kind == ce.KIND_ONSET]
        seps = [e for e in mine if e.kind == ce.KIND_SEPARATION]
        assert metrics.n_impacts >= 7  # measured: 8 (left), 7 (right)
        assert len(onsets) == metrics.n_impacts
        # the analysis interpolates the crossing; the onset sample is the one after it
        expected = np.searchsorted(t, metrics.onsets_s, side="right")
        np.testing.assert_array_equal([e.sample_index for e in onsets], expected)
        expected_sep = np.searchsorted(t, metrics.separations_s, side="right")
        np.testing.assert_array_equal([e.sample_index for e in seps], expected_sep)
        # onsets and separations alternate, starting with an onset
        assert [e.kind for e in mine][: 2 * len(seps)] == [0, 1] * len(seps)
        magnitude = symmetric_impacting.pivot_force_magnitude(side)
        for on, sep, analysed in zip(onsets, seps, metrics.impact_peaks_n, strict=False):
            window = magnitude[on.sample_index : sep.sample_index]
            assert sep.peak_pivot_force_n == window.max()
            assert sep.peak_sample_index == on.sample_index + int(np.argmax(window))
            assert sep.duration_s == pytest.approx((sep.sample_index - on.sample_index) * dt)
            # the analysis refines the sampled peak with a parabola: within 1 %
            assert sep.peak_pivot_force_n == pytest.approx(analysed, rel=0.01)
            assert on.peak_pivot_force_n == 0.0 and on.duration_s == 0.0
            assert on.time_s == on.sample_index * dt


@pytest.mark.parametrize("sizes", [[1], [7, 1, 250, 3], [1000], [17, 4000]])
def test_events_do_not_depend_on_the_chunking(symmetric_impacting, sizes):
    whole = detect([symmetric_impacting])
    assert len(whole) >= 28  # measured: 15 onsets, 13 separations in 0.3 s
    assert detect(cut(symmetric_impacting, sizes)) == whole


def test_episode_spanning_blocks_and_contact_at_the_first_sample():
    """Hand-made indentations: an episode crossing three blocks, one open at the start."""
    n = 12
    data = np.zeros((n, L.N_COLUMNS))
    data[:, L.COL["left_indentation_m"]] = [1, 1, -1, 0, 1, 1, 1, 1, 1, -1, -1, 1]
    data[:, L.COL["right_indentation_m"]] = -1.0
    data[:, L.COL["left_pivot_fx_n"]] = [5, 9, 0, 0, 3, 8, 8, 2, 1, 99, 0, 4]
    data[:, L.COL["left_pivot_fy_n"]] = 0.0
    dt = 0.5
    block = SampleBlock(data, 0, dt)
    for sizes in ([n], [1], [3, 2], [5, 4, 3]):
        events = detect(cut(block, sizes))
        found = [(e.sample_index, e.kind) for e in events]
        assert found == [(0, 0), (2, 1), (4, 0), (9, 1), (11, 0)]
        assert all(e.shoe == ce.SHOE_LEFT for e in events)
        first_sep, second_sep = events[1], events[3]
        assert (first_sep.peak_pivot_force_n, first_sep.peak_sample_index) == (9.0, 1)
        assert first_sep.duration_s == 1.0
        # the tie at 8 N goes to the first sample; the 99 N at the separation is outside
        assert (second_sep.peak_pivot_force_n, second_sep.peak_sample_index) == (8.0, 5)
        assert second_sep.duration_s == 2.5


def test_a_gap_is_refused_and_reset_starts_over(symmetric_impacting):
    blocks = cut(symmetric_impacting, [300])
    detector = ContactEventDetector()
    detector.feed(blocks[0])
    with pytest.raises(ValueError, match="reset"):
        detector.feed(blocks[2])
    detector.reset()
    # after a reset the same run gives the same events again, an open episode forgotten
    again = [e for b in blocks for e in detector.feed(b)]
    assert again == detect(blocks)
