"""The learned baseline's severity estimate on hand-made windows whose answer is known: a
defect whose severity sets the backing plate's vibration level, at four well separated
levels 10 % apart; windows of fresh noise at a trained level read a severity nearer that
level than any other (within half the spacing; a few trees, splitting on a noisy band
level, may send a window to a neighbour's leaf), and the windows' truth reaches the
regressor only through ``TrainingWindow.severities``."""

from __future__ import annotations

import numpy as np
import pytest

from brake_sim_ros.detection.detector import SampleChunk, TrainingWindow
from brake_sim_ros.detection.learned import LearnedClassifier

FS = 2560.0
WINDOW = 256  # 0.1 s
SEVERITIES = (-10.0, -20.0, -30.0, -40.0)  # friction_change, %: mu lowered by that much
DEFECT = ("friction_change", "left")


def _level(severity: float) -> float:
    """The y acceleration's standard deviation, m/s^2, of a brake with this defect."""
    return 1.0 + abs(severity) / 5.0


def _channels(rng: np.random.Generator, level: float, n: int) -> dict[str, np.ndarray]:
    return {
        "backing_plate_accel_x": rng.normal(0.0, 1.0, n),
        "backing_plate_accel_y": rng.normal(0.0, level, n),
        "wheel_speed": np.zeros(n),
        "line_pressure": np.full(n, 50.0),
    }


def _run(rng, run_id: str, severity: float | None, windows: int = 6) -> list[TrainingWindow]:
    level = 1.0 if severity is None else _level(severity)
    out = []
    for w in range(windows):
        out.append(
            TrainingWindow(
                _channels(rng, level, WINDOW),
                FS,
                () if severity is None else (DEFECT,),
                run_id=run_id,
                last_sample_index=(w + 1) * WINDOW - 1,
                severities=() if severity is None else (severity,),
            )
        )
    return out


@pytest.fixture(scope="module")
def detector() -> LearnedClassifier:
    rng = np.random.default_rng(11)
    windows: list[TrainingWindow] = []
    for r in range(6):
        windows += _run(rng, f"healthy-{r}", None)
    for s in SEVERITIES:
        for r in range(3):
            windows += _run(rng, f"{s}-{r}", s)
    d = LearnedClassifier()
    d.fit(windows)
    return d


def test_a_trained_level_reads_its_severity(detector):
    assert set(detector.severity_models) == {"friction_change:left"}
    rng = np.random.default_rng(12)  # noise the forest has not seen
    for s in SEVERITIES:
        detector.reset()
        found = detector.feed(SampleChunk(0, FS, _channels(rng, _level(s), 10 * WINDOW)))
        assert len(found) == 10
        diagnosed = [a.diagnosis for a in found if a.diagnosis is not None]
        assert len(diagnosed) >= 8  # a forest's vote may waver on a window or two
        for d in diagnosed:
            assert (d.kind, d.location) == DEFECT
            assert abs(d.severity - s) < 5.0  # half the spacing of the levels


def test_healthy_windows_carry_no_diagnosis(detector):
    rng = np.random.default_rng(13)
    detector.reset()
    found = detector.feed(SampleChunk(0, FS, _channels(rng, 1.0, 10 * WINDOW)))
    assert not any(a.alarm for a in found)
    assert all(a.diagnosis is None for a in found)


def test_no_severity_without_known_severities():
    """Windows whose severities are not known (an older caller) train no regressor: the
    diagnosis says NaN, not a made-up number."""
    rng = np.random.default_rng(14)
    windows = [w for r in range(4) for w in _run(rng, f"h{r}", None)]
    for r in range(4):
        windows += [
            TrainingWindow(w.channels, FS, w.defects, w.run_id, w.last_sample_index)
            for w in _run(rng, f"d{r}", -40.0)
        ]
    d = LearnedClassifier()
    d.fit(windows)
    assert d.severity_models == {}
    found = d.feed(SampleChunk(0, FS, _channels(rng, _level(-40.0), 10 * WINDOW)))
    diagnosed = [a.diagnosis for a in found if a.diagnosis is not None]
    assert diagnosed and all(np.isnan(x.severity) for x in diagnosed)
