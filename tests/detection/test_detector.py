"""The detector contract: windows aligned to the sample index whatever the chunks, gaps,
and the threshold baseline on hand-made signals (pure logic: fakes are fine here)."""

from __future__ import annotations

import numpy as np
import pytest

from brake_sim_ros.detection.baselines import (
    VibrationThreshold,
    crest_factor,
    kurtosis,
    rms,
)
from brake_sim_ros.detection.detector import SampleChunk, TrainingWindow
from brake_sim_ros.detection.registry import make_detector

FS = 1000.0
CH = "accel"


def _chunks(x: np.ndarray, sizes: list[int], start: int = 0) -> list[SampleChunk]:
    out, k = [], 0
    while k < x.size:
        for n in sizes:
            if k >= x.size:
                break
            out.append(SampleChunk(start + k, FS, {CH: x[k : k + n]}))
            k += n
    return out


def _fitted(noise: np.random.Generator) -> VibrationThreshold:
    d = VibrationThreshold("rms", CH, window_s=0.1)
    d.fit(TrainingWindow({CH: noise.normal(0, 1.0, 100)}, FS) for _ in range(50))
    return d


def test_assessments_do_not_depend_on_how_the_samples_are_chunked():
    rng = np.random.default_rng(1)
    x = rng.normal(0, 1.0, 2000)
    x[1200:1500] *= 5.0  # a loud stretch
    results = []
    for sizes in ([2000], [100], [7, 333, 1], [256]):
        d = _fitted(np.random.default_rng(2))
        results.append([a for c in _chunks(x, sizes) for a in d.feed(c)])
    assert all(r == results[0] for r in results[1:])
    first = results[0]
    assert [a.sample_index for a in first] == list(range(99, 2000, 100))
    alarms = [a.sample_index for a in first if a.alarm]
    assert alarms == [1299, 1399, 1499]  # the three windows inside the loud stretch


def test_a_stream_joined_late_or_after_a_gap_waits_for_an_aligned_window():
    x = np.random.default_rng(3).normal(0, 1.0, 1000)
    d = _fitted(np.random.default_rng(2))
    got = d.feed(SampleChunk(250, FS, {CH: x[250:600]}))
    assert [a.sample_index for a in got] == [399, 499, 599]  # 250-299 dropped: not aligned
    got = d.feed(SampleChunk(650, FS, {CH: x[650:1000]}))  # a gap of 50 samples
    assert [a.sample_index for a in got] == [799, 899, 999]


def test_statistics_of_known_signals():
    sine = np.sin(2 * np.pi * np.arange(1000) / 100)
    assert rms(sine) == pytest.approx(1 / np.sqrt(2), rel=1e-9)
    assert crest_factor(sine) == pytest.approx(np.sqrt(2), rel=1e-6)
    assert kurtosis(sine) == pytest.approx(1.5, rel=1e-6)  # a sine's kurtosis is 3/2
    impulses = np.zeros(1000)
    impulses[::100] = 1.0
    assert kurtosis(impulses) > 50  # impacts raise it


def test_threshold_is_mean_plus_k_std_of_healthy_windows_and_needs_fitting():
    d = VibrationThreshold("rms", CH, window_s=0.1, k=2.0)
    with pytest.raises(RuntimeError, match="not fitted"):
        d.feed(SampleChunk(0, FS, {CH: np.ones(100)}))
    d.reset()
    windows = [TrainingWindow({CH: np.full(100, v)}, FS) for v in (1.0, 3.0)]
    windows.append(TrainingWindow({CH: np.full(100, 100.0)}, FS, (("drum_out_of_round", "drum"),)))
    d.fit(windows)
    assert d.threshold == pytest.approx(2.0 + 2.0 * 1.0)  # defective windows ignored
    (a,) = d.feed(SampleChunk(0, FS, {CH: np.full(100, 4.0)}))
    assert a.health_index == pytest.approx(1.0) and a.alarm


def test_bad_detectors_and_samples_are_refused_in_one_line():
    with pytest.raises(ValueError, match="allowed one of"):
        VibrationThreshold("median")
    with pytest.raises(ValueError, match="module:Class"):
        make_detector("nonsense")
    with pytest.raises(ValueError, match=r"no module .no_such_module_xyz. on the Python path"):
        make_detector("no_such_module_xyz:Thing")
    with pytest.raises(ValueError, match=r"not a .* Detector subclass"):
        make_detector("numpy:ndarray")
    d = make_detector("rms")
    with pytest.raises(ValueError, match="no channel"):
        d.feed(SampleChunk(0, FS, {"other": np.zeros(10)}))
    with pytest.raises(ValueError, match="one 1-D length"):
        SampleChunk(0, FS, {"a": np.zeros(3), "b": np.zeros(4)})
