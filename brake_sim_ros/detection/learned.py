"""The learned baseline (``learned``): a random forest on windowed features, trained on the
train split, that detects (P(defective)) and isolates (which defect, where).

Features: :func:`~brake_sim_ros.detection.features.window_features` (the one feature
function of every baseline: rms, kurtosis, crest and band levels of both backing-plate
accelerations, their amplitudes at drum orders 1-20, the drum's angle fluctuation at those
orders from the tone ring, its speed and deceleration, the line pressure's mean and
spread) over the last :attr:`LearnedClassifier.history_s` = 0.5 s, assessed every 0.1 s
(:mod:`.history`). Classes: ``healthy`` and each ``kind:location`` of the catalogue seen in
training (a window's class is the first active defect at its last sample).

Model: ``sklearn.pipeline.Pipeline`` of a constant imputer (a missing channel's features
read 0) and ``RandomForestClassifier`` (:data:`N_TREES` trees, leaves of at least
:data:`MIN_LEAF` windows, ``random_state`` fixed, one job: the same data give the same
forest, bit for bit). Trees need no scaling of the features. The healthy windows together
weigh as much as all defective ones together: many windows of a defective run look healthy
(before the brake is applied, most defects change nothing), and with every class weighted
alike (1/19 each for healthy) such a window would read P(defective) = 0.95 and push the
alarm threshold up; weighted so, a window that tells nothing reads about 0.5. (On the
reference campaign's test split this and the deceleration-per-bar feature, added
together, moved the detections from 56 to 59 of 304 and the window AUROC from 0.67 to
0.72: the threshold was not the main limit.)

Health index: P(defective) = 1 - P(healthy) over the alarm threshold. The threshold is set
on healthy training windows the forest did not see: the windows of each training run are
scored by a forest trained on the other runs' (:data:`FOLDS` folds grouped by run, so no
window is scored by trees that saw its run), and the threshold is their
``1 - FALSE_ALARM_FRACTION`` quantile (at least 0.5). Diagnosis on alarm: the most
probable defective class, its probability as confidence, and its severity estimate.

Severity: per defective class, a ``RandomForestRegressor`` (:data:`SEVERITY_TREES` trees,
leaves of at least :data:`MIN_LEAF` windows, the same imputer and seed) on the same
features of that class's training windows, whose target is the class's defect severity at
the window's last sample (its label column, in the kind's unit, signed: what the scorer's
severity error compares against). A class with fewer than :data:`MIN_SEVERITY_WINDOWS`
training windows with a known severity gets none (severity NaN). A regressor per class,
not one for all: the kinds' units differ, and the diagnosis has already chosen the class.
Its estimate is an average of training severities, so it never leaves the range seen in
training (a larger defect than any trained on reads as the largest trained).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping

import numpy as np
from sklearn.ensemble import RandomForestClassifier, RandomForestRegressor
from sklearn.impute import SimpleImputer
from sklearn.model_selection import GroupKFold
from sklearn.pipeline import Pipeline

from brake_sim_ros.detection.detector import Assessment, Diagnosis, TrainingWindow
from brake_sim_ros.detection.features import CHANNELS, window_features
from brake_sim_ros.detection.forest import MAX_TREE_DEPTH, MAX_TREES, ForestArrays
from brake_sim_ros.detection.history import HistoryDetector

HEALTHY = "healthy"
N_TREES = MAX_TREES  # a saved forest may hold no more (forest.py)
MIN_LEAF = 2
FOLDS = 3
FALSE_ALARM_FRACTION = 0.01  # of healthy training windows over the threshold, out of fold
SEED = 0
SEVERITY_TREES = 30  # per defective class: the estimate settles well before 100 trees
MIN_SEVERITY_WINDOWS = 2 * MIN_LEAF


def _pipeline(
    forest: type[RandomForestClassifier] | type[RandomForestRegressor] = RandomForestClassifier,
    trees: int = N_TREES,
) -> Pipeline:
    """The constant imputer and a forest (the classifier, or a severity regressor)."""
    return Pipeline(
        [
            (
                "impute",
                SimpleImputer(strategy="constant", fill_value=0.0, keep_empty_features=True),
            ),
            (
                "forest",
                forest(
                    n_estimators=trees,
                    min_samples_leaf=MIN_LEAF,
                    max_depth=MAX_TREE_DEPTH,  # what a saved detector may hold (forest.py)
                    random_state=SEED,
                    n_jobs=1,
                ),
            ),
        ]
    )


def _weights(labels: np.ndarray) -> np.ndarray:
    """Sample weights: the healthy windows together weigh as much as the defective ones
    together (each defect's windows as their share of the defective ones)."""
    healthy = labels == HEALTHY
    return np.where(healthy, 0.5 / max(1, healthy.sum()), 0.5 / max(1, (~healthy).sum()))


class LearnedClassifier(HistoryDetector):
    """A random forest on windowed features (module docstring)."""

    def __init__(
        self,
        *,
        history_s: float = 0.5,
        window_s: float = 0.1,
        channels: tuple[str, ...] = CHANNELS,
    ) -> None:
        super().__init__()
        if not (window_s > 0.0 and history_s >= window_s):
            raise ValueError(
                f"window_s={window_s!r}, history_s={history_s!r}: allowed window_s > 0 and"
                " history_s >= window_s"
            )
        self.name = "learned"
        self.channels = tuple(channels)  # the features of a channel it does not read are 0
        self.window_s, self.history_s = float(window_s), float(history_s)
        # the fitted pipeline, or its trees as arrays when loaded from a file (:mod:`.saved`)
        self.model: Pipeline | ForestArrays | None = None
        self.classes: tuple[str, ...] = ()
        self.threshold: float | None = None
        self.healthy_index: np.ndarray = np.zeros(0)  # healthy training windows, out of fold
        # "kind:location" -> a fitted regressor of its severity (module docstring)
        self.severity_models: dict[str, Pipeline | ForestArrays] = {}

    def fit(self, windows: Iterable[TrainingWindow]) -> None:
        """Features of every training history, the forest, and the out-of-fold threshold
        (module docstring)."""
        X, y, groups, severity = [], [], [], []
        for history, w in self.histories(windows):
            mine = {c: history[c] for c in self.channels if c in history}  # as assessed
            X.append(window_features(mine, w.sample_rate_hz))
            y.append(HEALTHY if w.healthy else ":".join(w.defects[0]))
            groups.append(w.run_id)
            severity.append(w.severities[0] if w.severities and not w.healthy else np.nan)
        labels = np.array(y)
        if HEALTHY not in y or len(set(y)) < 2:
            raise ValueError(
                f"detector {self.name}: training windows of {sorted(set(y))}; it needs healthy"
                " and defective ones"
            )
        features = np.array(X)
        healthy = labels == HEALTHY
        p_defective = np.full(labels.size, np.nan)
        run_ids = np.array(groups)
        folds = min(FOLDS, len(set(groups)))
        if folds >= 2:
            for train, held in GroupKFold(n_splits=folds).split(features, labels, run_ids):
                if len(set(labels[train])) < 2 or HEALTHY not in labels[train]:
                    continue
                model = _pipeline().fit(
                    features[train],
                    labels[train],
                    forest__sample_weight=_weights(labels[train]),
                )
                proba = model.predict_proba(features[held])
                p_defective[held] = 1.0 - proba[:, list(model.classes_).index(HEALTHY)]
        scored = p_defective[healthy & np.isfinite(p_defective)]
        quantile = float(np.quantile(scored, 1.0 - FALSE_ALARM_FRACTION)) if scored.size else 0.5
        self.threshold = max(0.5, quantile)
        self.healthy_index = scored / self.threshold
        self.model = _pipeline().fit(features, labels, forest__sample_weight=_weights(labels))
        self.classes = tuple(str(c) for c in self.model.classes_)
        self.severity_models = {}
        target = np.array(severity, dtype=np.float64)
        for c in self.classes:
            rows = (labels == c) & np.isfinite(target)
            if c != HEALTHY and rows.sum() >= MIN_SEVERITY_WINDOWS:
                self.severity_models[c] = _pipeline(RandomForestRegressor, SEVERITY_TREES).fit(
                    features[rows], target[rows]
                )

    def judge(
        self, history: Mapping[str, np.ndarray], last_sample_index: int, sample_rate_hz: float
    ) -> Assessment:
        if self.model is None or self.threshold is None:
            raise RuntimeError(f"detector {self.name} is not fitted: call fit() first")
        x = window_features(history, sample_rate_hz)[None, :]
        proba = self.model.predict_proba(x)[0]
        healthy = self.classes.index(HEALTHY)
        index = (1.0 - float(proba[healthy])) / self.threshold
        alarm = index >= 1.0
        diagnosis = None
        if alarm:
            proba[healthy] = -1.0
            j = int(np.argmax(proba))
            kind, location = self.classes[j].split(":", 1)
            regressor = self.severity_models.get(self.classes[j])
            severity = math.nan if regressor is None else float(regressor.predict(x)[0])
            diagnosis = Diagnosis(kind, location, severity, confidence=float(proba[j]))
        return Assessment(
            last_sample_index, last_sample_index / sample_rate_hz, index, alarm, diagnosis
        )
