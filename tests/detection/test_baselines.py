"""The shared window features and the order-analysis baseline on hand-made signals whose
answers are known by construction (pure logic: synthetic tone rings and sines)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from brake_sim_ros.detection import features as f
from brake_sim_ros.detection.detector import SampleChunk, TrainingWindow
from brake_sim_ros.detection.order_analysis import OrderAnalysis

FS = 51200.0
SPEED = 100.0  # rad/s: 15.9 revolutions per second
TEETH = f.TONE_RING_TEETH


def _angle(t: np.ndarray, ripple_rad: float = 0.0, order: int = 2) -> np.ndarray:
    """A drum turning at SPEED whose angle runs ahead and behind by ``ripple_rad`` at
    ``order`` (to first order in the ripple)."""
    return SPEED * t + ripple_rad * np.sin(order * SPEED * t)


def _pulse(angle: np.ndarray) -> np.ndarray:
    """The tone ring's pulse: 1 while a tooth is under the sensor (half of each pitch)."""
    phase = TEETH * angle / (2.0 * math.pi)
    return (phase - np.floor(phase) < 0.5).astype(np.float64)


def test_band_rms_of_a_sine_falls_in_its_band():
    t = np.arange(4096) / 5120.0
    x = 2.0 * np.sin(2 * math.pi * 500.0 * t)
    bands = f.band_rms(x, 5120.0)
    # 500 Hz is in the 200-850 Hz band: the sine's rms, 2 / sqrt(2)
    assert bands[1] == pytest.approx(math.sqrt(2.0), rel=0.01)
    assert np.all(np.delete(bands, 1) < 0.01 * bands[1])
    assert bands[3] == 0.0 or f.BANDS_HZ[3][0] < 2560.0  # above Nyquist reads 0


def test_speed_and_angle_from_the_tone_ring():
    t = np.arange(int(0.3 * FS)) / FS
    angle = _angle(t)
    est, speed, decel = f.drum_angle(_pulse(angle), FS)
    assert speed == pytest.approx(SPEED, rel=1e-3)
    assert abs(decel) < 1.0  # constant speed
    assert est is not None
    pitch_error = np.abs((est - est[0]) - (angle - angle[0]))
    assert pitch_error.max() < 0.05 * 2 * math.pi / TEETH  # within 5 % of a tooth


def test_order_amplitude_of_a_signal_tied_to_the_drum_angle():
    t = np.arange(int(0.5 * FS)) / FS
    angle = _angle(t)
    signal = 0.7 * np.cos(3.0 * angle)
    est, _, _ = f.drum_angle(_pulse(angle), FS)
    amplitudes = f.order_amplitudes(signal, est, FS)
    k3 = f.ORDERS.index(3)
    assert amplitudes[k3] == pytest.approx(0.7, rel=0.02)
    assert np.all(np.delete(amplitudes, k3) < 0.02)


def test_angle_fluctuation_at_its_order_from_the_tone_ring_alone():
    t = np.arange(int(0.5 * FS)) / FS
    ripple = 2e-3  # rad
    amplitudes = f.angle_fluctuation_orders(_pulse(_angle(t, ripple, order=2)), FS)
    k2 = f.ORDERS.index(2)
    assert amplitudes[k2] == pytest.approx(ripple, rel=0.05)
    # the other orders hold only the quantisation of the edges to the samples (up to
    # SPEED / FS / 2 = 1e-3 rad per edge; at a constant speed its pattern repeats, so it
    # gathers in lines rather than spreading over ~380 edges): well below the ripple
    assert np.all(np.delete(amplitudes, k2) < 0.2 * ripple)
    # fewer than two revolutions: nothing to analyse
    short = np.arange(int(0.1 * FS)) / FS
    assert not f.angle_fluctuation_orders(_pulse(_angle(short, ripple)), FS).any()


def test_window_features_are_named_and_missing_channels_read_nan():
    t = np.arange(int(0.5 * FS)) / FS
    rng = np.random.default_rng(0)
    window = {
        "backing_plate_accel_x": rng.normal(0.0, 1.0, t.size),
        "wheel_speed": _pulse(_angle(t)),
        "line_pressure": np.full(t.size, 40.0),
    }
    values = f.window_features(window, FS)
    names = f.feature_names()
    assert values.shape == (len(names),) == (len(set(names)),)
    got = dict(zip(names, values, strict=True))
    assert got["backing_plate_accel_x:rms"] == pytest.approx(1.0, rel=0.02)
    assert got["backing_plate_accel_x:kurtosis"] == pytest.approx(3.0, rel=0.1)
    assert math.isnan(got["backing_plate_accel_y:rms"])  # not in the window
    assert got["drum_speed_rad_s"] == pytest.approx(SPEED, rel=1e-3)
    assert got["revolutions"] == pytest.approx(0.5 * SPEED / (2 * math.pi), abs=0.1)
    assert got["line_pressure_mean_bar"] == 40.0 and got["line_pressure_std_bar"] == 0.0
    assert got["deceleration_per_bar"] == got["drum_deceleration_rad_s2"] / 40.0


def _tone_ring_windows(
    ripple: float, seeds: range, defects=(), accel_rms: float = 0.01
) -> list[TrainingWindow]:
    """0.1 s windows of 0.6 s runs whose drum angle jitters (a healthy brake's small
    random fluctuation, 2e-5 rad) plus an order-2 ripple, with a backing-plate y
    acceleration of white noise of ``accel_rms``."""
    fs = 10240.0
    n = int(0.1 * fs)
    out = []
    for seed in seeds:
        rng = np.random.default_rng(seed)
        t = np.arange(6 * n) / fs
        jitter = np.interp(t, np.linspace(0, t[-1], 200), rng.normal(0.0, 2e-5, 200))
        pulse = _pulse(_angle(t, ripple) + jitter)
        for w in range(6):
            out.append(
                TrainingWindow(
                    {
                        "wheel_speed": pulse[w * n : (w + 1) * n],
                        "backing_plate_accel_y": rng.normal(0.0, accel_rms, n),
                    },
                    fs,
                    defects,
                    run_id=f"run-{seed}",
                    last_sample_index=(w + 1) * n - 1,
                )
            )
    return out


def test_the_order_detector_alarms_on_an_order_ripple_and_names_the_drum():
    detector = OrderAnalysis(history_s=0.5, gate_channel=None)
    detector.fit(_tone_ring_windows(0.0, range(20)))
    assert detector.threshold is not None and detector.healthy_index.size > 0
    # the threshold is the 0.995 quantile of these healthy scores: at most 0.5 % above
    above = np.count_nonzero(detector.healthy_index > 1.0)
    assert above <= math.ceil(0.005 * detector.healthy_index.size)

    def last_assessment(windows: list[TrainingWindow]):
        detector.reset()
        found = []
        for w in windows:
            chunk = SampleChunk(w.last_sample_index - 1023, w.sample_rate_hz, w.channels)
            found += detector.feed(chunk)
        return found[-1]

    healthy = last_assessment(_tone_ring_windows(0.0, range(100, 101)))
    assert not healthy.alarm and healthy.diagnosis is None
    oval = last_assessment(_tone_ring_windows(3e-3, range(100, 101)))
    assert oval.alarm and oval.health_index > 1.0
    assert (oval.diagnosis.kind, oval.diagnosis.location) == ("drum_out_of_round", "drum")


def test_the_order_detector_judges_the_last_half_second_joined_across_chunks():
    windows = _tone_ring_windows(3e-3, range(1))
    detector = OrderAnalysis(history_s=0.5, gate_channel=None)
    detector.fit(_tone_ring_windows(0.0, range(10)))
    pulse = np.concatenate([w.channels["wheel_speed"] for w in windows])
    results = []
    for size in (1024, 333):
        detector.reset()
        found = []
        for start in range(0, pulse.size, size):
            found += detector.feed(
                SampleChunk(start, 10240.0, {"wheel_speed": pulse[start : start + size]})
            )
        results.append(found)
    assert results[0] == results[1] and len(results[0]) == 6
    # the first window has 1.6 revolutions: not enough, scored 0; later ones have more
    assert results[0][0].health_index == 0.0 and results[0][-1].alarm


def test_bad_order_detectors_are_refused():
    with pytest.raises(ValueError, match="history_s >= window_s"):
        OrderAnalysis(history_s=0.05)
    with pytest.raises(ValueError, match="2 or more"):
        OrderAnalysis(history_s=0.5, gate_channel=None).fit(_tone_ring_windows(0.0, range(1))[:1])
    with pytest.raises(RuntimeError, match="not fitted"):
        OrderAnalysis(history_s=0.5, gate_channel=None).feed(
            SampleChunk(0, 1000.0, {"wheel_speed": np.zeros(200)})
        )


def test_the_learned_baseline_isolates_a_separable_defect_the_same_way_twice():
    from brake_sim_ros.detection.learned import LearnedClassifier

    drum = (("drum_out_of_round", "drum"),)
    train = _tone_ring_windows(0.0, range(6)) + _tone_ring_windows(3e-3, range(6, 12), drum)
    test = _tone_ring_windows(3e-3, range(50, 51), drum)
    runs = []
    for _ in range(2):
        detector = LearnedClassifier(channels=("wheel_speed",))
        detector.fit(train)
        assert detector.classes == ("drum_out_of_round:drum", "healthy")
        found = []
        for w in test:
            chunk = SampleChunk(w.last_sample_index - 1023, w.sample_rate_hz, w.channels)
            found += detector.feed(chunk)
        runs.append(found)
    assert runs[0] == runs[1]  # a fixed seed and one job: the same forest
    last = runs[0][-1]
    assert last.alarm and (last.diagnosis.kind, last.diagnosis.location) == drum[0]
    with pytest.raises(ValueError, match="healthy and defective"):
        LearnedClassifier().fit(_tone_ring_windows(0.0, range(2)))


def test_the_order_detector_does_not_judge_a_history_louder_than_quiet_sliding():
    detector = OrderAnalysis(history_s=0.5)  # gated on the backing plate's y acceleration
    detector.fit(_tone_ring_windows(0.0, range(20)))
    assert detector.gate == pytest.approx(3 * 0.01, rel=0.1)  # 3x the quiet rms
    for accel_rms, judged in ((0.01, True), (0.1, False)):  # quiet, then impacts
        detector.reset()
        found = []
        for w in _tone_ring_windows(3e-3, range(100, 101), accel_rms=accel_rms):
            chunk = SampleChunk(w.last_sample_index - 1023, w.sample_rate_hz, w.channels)
            found += detector.feed(chunk)
        assert found[-1].alarm is judged
        assert (found[-1].health_index > 1.0) if judged else found[-1].health_index == 0.0


def test_the_detectability_floor_is_the_smallest_fraction_detected_from_there_up():
    from brake_sim_ros.studies import detectability as study

    # detected at 0.35 by chance, missed at 0.5, detected from 0.75: the floor is 0.75
    assert study.floor({0.1: 0.0, 0.35: 1.0, 0.5: 0.25, 0.75: 0.5, 1.0: 1.0}) == 0.75
    assert study.floor({0.1: 1.0, 0.5: 1.0, 1.0: 1.0}) == 0.1
    assert study.floor({0.5: 1.0, 1.0: 0.0}) is None  # missed at the service limit
    result = {
        "false_alarm": 0.01,
        "detectors": {
            "orders": {
                "threshold": 1.0,
                "false_alarms": 1,
                "healthy_hours": 0.5,
                "counts": {"drum_out_of_round@0.5": [3, 4], "drum_out_of_round@1": [4, 4]},
            }
        },
    }
    text = study.table(result)
    assert "| drum_out_of_round (150 um) | orders | 0.5 (75 um) |" in text
    assert "| - | 3/4 | - | 4/4 |" in text and "(2 per hour)" in text  # 0.75 not run
    assert "| friction_change (-50 %) | orders | not detected |" in text


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_a_window_a_dropout_emptied_is_left_out_of_the_fit_and_counted():
    """A healthy window whose channel is NaN throughout (a dropout) has no statistic: it is
    left out of the threshold, counted, and warns nothing (numpy's mean of an empty slice)."""
    from brake_sim_ros.detection.baselines import VibrationThreshold
    from brake_sim_ros.detection.fitted import facts_text

    rng = np.random.default_rng(3)
    windows = [
        TrainingWindow({"backing_plate_accel_y": rng.normal(0.0, 1.0, 256)}, 2560.0, ())
        for _ in range(8)
    ]
    empty = TrainingWindow({"backing_plate_accel_y": np.full(256, np.nan)}, 2560.0, ())
    for name in ("rms", "kurtosis", "crest"):
        assert math.isnan(f.STATISTICS[name](empty.channels["backing_plate_accel_y"]))
        whole, gapped = VibrationThreshold(name), VibrationThreshold(name)
        whole.fit(windows)
        gapped.fit([*windows[:4], empty, empty, *windows[4:]])
        assert gapped.threshold == whole.threshold
        assert (whole.unjudged_windows, gapped.unjudged_windows) == (0, 2)
        assert "2 healthy windows without a finite sample left out" in facts_text(gapped)
