"""Each scoring metric on a hand-made case whose answer is known by construction."""

from __future__ import annotations

import math

import numpy as np
import pytest

from brake_sim_ros.detection import metrics as m

T = np.arange(20) * 0.5  # 0, 0.5, ..., 9.5 s


def _alarm(*on: int) -> np.ndarray:
    a = np.zeros(T.size, dtype=bool)
    a[list(on)] = True
    return a


def test_a_held_alarm_is_raised_when_it_has_lasted_the_hold():
    alarm = _alarm(2, 3, 4, 5, 10, 15, 16)  # runs 1.0-2.5 s, 5.0 s, 7.5-8.0 s
    np.testing.assert_array_equal(m.held_alarm_times(alarm, T, 1.0), [2.0])
    np.testing.assert_array_equal(m.held_alarm_times(alarm, T, 0.5), [1.5, 8.0])
    np.testing.assert_array_equal(m.held_alarm_times(alarm, T, 0.0), [1.0, 5.0, 7.5])
    assert m.alarm_runs(alarm) == [(2, 5), (10, 10), (15, 16)]


def test_detection_delay_counts_from_the_onset_and_ignores_earlier_alarms():
    alarm = _alarm(2, 3, 12, 13, 14)  # held (0.5 s) at 1.5 s (before onset) and at 6.5 s
    assert m.detection_delay(alarm, T, onset_s=4.0, hold_s=0.5) == pytest.approx(2.5)
    assert m.detection_delay(alarm, T, onset_s=1.0, hold_s=0.5) == pytest.approx(0.5)
    assert m.detection_delay(alarm, T, onset_s=7.0, hold_s=0.5) is None  # missed


def test_false_alarms_count_held_alarms_on_healthy_samples_per_healthy_hour():
    healthy = T < 6.0  # 12 healthy samples of 0.5 s: 6 s
    alarm = _alarm(1, 2, 6, 13, 14)  # held (0.5 s) at 1.0 s (healthy) and 7.0 s (defective)
    count, hours = m.false_alarms_per_hour(alarm, T, healthy, hold_s=0.5)
    assert count == 1 and hours == pytest.approx(6.0 / 3600.0)
    count, _ = m.false_alarms_per_hour(alarm, T, healthy, hold_s=0.0)
    assert count == 2  # the single-sample run at 3.0 s counts without a hold


def test_confusion_matrix_rows_are_true_columns_diagnosed():
    true = ["healthy", "drum", "drum", "left_pin", "healthy"]
    diagnosed = ["healthy", "drum", "left_pin", "left_pin", "drum"]
    got = m.confusion(true, diagnosed, ["healthy", "drum", "left_pin"])
    np.testing.assert_array_equal(got, [[1, 1, 0], [0, 1, 1], [0, 0, 1]])


def test_auroc_and_auprc_of_known_rankings():
    defective = np.array([0, 0, 1, 1], dtype=bool)
    assert m.auroc(defective, [0.1, 0.2, 0.8, 0.9]) == 1.0  # perfectly separated
    assert m.auroc(defective, [0.9, 0.8, 0.2, 0.1]) == 0.0  # inverted
    # one positive ranked below one negative: 3 of 4 pairs right
    assert m.auroc(defective, [0.1, 0.5, 0.4, 0.9]) == pytest.approx(0.75)
    # ranking 0.9 (+), 0.5 (-), 0.4 (+), 0.1 (-): precision 1 at recall 0.5, 2/3 at 1
    assert m.auprc(defective, [0.1, 0.5, 0.4, 0.9]) == pytest.approx(0.5 * 1 + 0.5 * 2 / 3)
    assert m.auroc(np.ones(3, dtype=bool), [1, 2, 3]) is None  # one class: undefined


def test_roc_points_of_a_known_ranking():
    defective = np.array([0, 0, 1, 1], dtype=bool)
    # ranking 0.9 (+), 0.5 (-), 0.4 (+), 0.1 (-): the curve goes up, right, up, right
    fpr, tpr = m.roc_points(defective, [0.1, 0.5, 0.4, 0.9])
    assert list(zip(fpr, tpr, strict=True)) == [
        (0.0, 0.0),
        (0.0, 0.5),
        (0.5, 0.5),
        (0.5, 1.0),
        (1.0, 1.0),
    ]
    assert m.roc_points(np.zeros(3, dtype=bool), [1, 2, 3]) == ([], [])  # one class


def test_rmse_and_the_asymmetric_rul_score():
    assert m.rmse([1.0, 2.0, 3.0], [1.0, 2.0, 3.0]) == 0.0
    assert m.rmse([0.0, 0.0], [3.0, 4.0]) == pytest.approx(math.sqrt(12.5))
    # d = -13 (early) costs e - 1; d = +10 (late) costs e - 1; d = 0 costs nothing
    assert m.rul_score([87.0, 110.0, 50.0], [100.0, 100.0, 50.0]) == pytest.approx(2 * (math.e - 1))
    # late costs more than early by the same amount
    assert m.rul_score([110.0], [100.0]) > m.rul_score([90.0], [100.0])


def test_bad_inputs_are_refused_with_what_is_allowed():
    with pytest.raises(ValueError, match="equal 1-D shapes"):
        m.held_alarm_times(np.zeros(3), np.arange(4.0), 0.0)
    with pytest.raises(ValueError, match="increase strictly"):
        m.held_alarm_times(np.zeros(3), np.array([0.0, 0.0, 1.0]), 0.0)
    with pytest.raises(ValueError, match=">= 0 s"):
        m.held_alarm_times(np.zeros(3), np.arange(3.0), -1.0)
