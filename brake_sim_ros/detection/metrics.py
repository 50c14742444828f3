"""The field's scoring metrics, each a pure function of arrays with a stated convention.

Conventions (the prognostics literature's, as the PHM and C-MAPSS benchmarks use them):

* **Held alarm.** A detector's raw alarm flickers; what counts is an alarm *held* for at
  least ``hold_s`` of simulated time (every sample of the interval alarmed). It is raised
  at the end of that interval: the moment a user acting on it could have acted.
* **Detection delay**: from a defect's onset to the first held alarm raised at or after the
  onset, s; missed when there is none.
* **False alarms per hour**: held alarms raised while the brake is healthy (no defect
  active), each run of consecutive alarmed samples counted once, per hour of healthy
  operation.
* **Isolation**: the confusion matrix of the diagnosed defect class against the true one
  (``sklearn.metrics.confusion_matrix``).
* **Health index**: AUROC and AUPRC (average precision) of a scalar index against the
  defective/healthy label (``sklearn.metrics``), the defective class positive.
* **Severity and remaining useful life**: RMSE of the estimate; for RUL also the
  asymmetric score of the C-MAPSS benchmark (Saxena et al., 2008), ``d = predicted - true``
  (cycles or s): ``exp(-d/13) - 1`` for early predictions (``d < 0``), ``exp(d/10) - 1``
  for late ones, summed: late predictions cost more.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from sklearn import metrics as skm

EARLY_SCALE = 13.0  # C-MAPSS asymmetric score: d < 0 (early) divides by 13
LATE_SCALE = 10.0  # and d >= 0 (late) by 10


def _bool_series(alarm: np.ndarray, time_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    alarm = np.asarray(alarm, dtype=bool)
    time_s = np.asarray(time_s, dtype=np.float64)
    if alarm.shape != time_s.shape or alarm.ndim != 1:
        raise ValueError(f"alarm {alarm.shape} and time {time_s.shape}: allowed equal 1-D shapes")
    if time_s.size > 1 and not np.all(np.diff(time_s) > 0.0):
        raise ValueError("time_s must increase strictly")
    return alarm, time_s


def alarm_runs(alarm: np.ndarray) -> list[tuple[int, int]]:
    """``(first, last)`` sample indices of each run of consecutive alarmed samples."""
    a = np.asarray(alarm, dtype=np.int8)
    edges = np.diff(np.concatenate(([0], a, [0])))
    starts = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1) - 1
    return list(zip(starts.tolist(), ends.tolist(), strict=True))


def held_alarm_times(alarm: np.ndarray, time_s: np.ndarray, hold_s: float) -> np.ndarray:
    """Times, s, at which held alarms are raised: for each run of alarmed samples that lasts
    at least ``hold_s`` (last minus first sample time), the first sample at which it has
    lasted that long."""
    alarm, time_s = _bool_series(alarm, time_s)
    if not hold_s >= 0.0:
        raise ValueError(f"hold_s={hold_s!r}: allowed >= 0 s")
    raised = []
    for first, last in alarm_runs(alarm):
        due = time_s[first] + hold_s
        k = first + int(np.searchsorted(time_s[first : last + 1], due - 1e-12))
        if k <= last:
            raised.append(time_s[k])
    return np.asarray(raised, dtype=np.float64)


def detection_delay(
    alarm: np.ndarray, time_s: np.ndarray, onset_s: float, hold_s: float
) -> float | None:
    """Seconds from ``onset_s`` to the first held alarm raised at or after it; None if
    missed. A held alarm raised before the onset is a false alarm, not a detection."""
    raised = held_alarm_times(alarm, time_s, hold_s)
    after = raised[raised >= onset_s]
    return float(after[0] - onset_s) if after.size else None


def false_alarms_per_hour(
    alarm: np.ndarray, time_s: np.ndarray, healthy: np.ndarray, hold_s: float
) -> tuple[int, float]:
    """``(count, hours)``: held alarms raised on healthy samples, and the hours of healthy
    operation (each healthy sample counts for the interval to the next sample; the last
    for the median interval). Their ratio is the false-alarm rate per hour."""
    alarm, time_s = _bool_series(alarm, time_s)
    healthy = np.asarray(healthy, dtype=bool)
    if healthy.shape != alarm.shape:
        raise ValueError(f"healthy {healthy.shape}: allowed the alarm's shape {alarm.shape}")
    if time_s.size == 0:
        return 0, 0.0
    dt = np.diff(time_s)
    widths = np.append(dt, np.median(dt) if dt.size else 0.0)
    hours = float(widths[healthy].sum() / 3600.0)
    raised = held_alarm_times(alarm, time_s, hold_s)
    index = np.searchsorted(time_s, raised)
    return int(np.count_nonzero(healthy[index])), hours


def confusion(true: Sequence[str], predicted: Sequence[str], classes: Sequence[str]) -> np.ndarray:
    """Rows: true class, columns: diagnosed class, in the order of ``classes``."""
    return skm.confusion_matrix(list(true), list(predicted), labels=list(classes))


def auroc(defective: np.ndarray, health_index: np.ndarray) -> float | None:
    """Area under the ROC curve of ``health_index`` (higher: more likely defective); None
    when only one class is present (the area is undefined)."""
    y = np.asarray(defective, dtype=bool)
    if y.all() or not y.any():
        return None
    return float(skm.roc_auc_score(y, np.asarray(health_index, dtype=np.float64)))


def roc_points(defective: np.ndarray, health_index: np.ndarray) -> tuple[list[float], list[float]]:
    """The ROC curve's corners ``(false positive rates, true positive rates)``
    (``sklearn.metrics.roc_curve``, collinear points dropped), from (0, 0) to (1, 1);
    empty lists when only one class is present."""
    y = np.asarray(defective, dtype=bool)
    if y.all() or not y.any():
        return [], []
    fpr, tpr, _ = skm.roc_curve(y, np.asarray(health_index, dtype=np.float64))
    return fpr.tolist(), tpr.tolist()


def auprc(defective: np.ndarray, health_index: np.ndarray) -> float | None:
    """Average precision (area under the precision-recall curve); None without positives."""
    y = np.asarray(defective, dtype=bool)
    if not y.any():
        return None
    return float(skm.average_precision_score(y, np.asarray(health_index, dtype=np.float64)))


def rmse(estimate: np.ndarray, truth: np.ndarray) -> float:
    e = np.asarray(estimate, dtype=np.float64) - np.asarray(truth, dtype=np.float64)
    if e.size == 0:
        raise ValueError("no estimates to score")
    return float(np.sqrt(np.mean(e * e)))


def rul_score(predicted: np.ndarray, true: np.ndarray) -> float:
    """The C-MAPSS asymmetric score of remaining-useful-life predictions (lower is better,
    0 when exact): ``sum(exp(-d/13) - 1)`` over early (``d < 0``), ``sum(exp(d/10) - 1)``
    over late predictions, ``d = predicted - true``."""
    d = np.asarray(predicted, dtype=np.float64) - np.asarray(true, dtype=np.float64)
    early = d < 0.0
    return float(
        np.sum(np.expm1(-d[early] / EARLY_SCALE)) + np.sum(np.expm1(d[~early] / LATE_SCALE))
    )
