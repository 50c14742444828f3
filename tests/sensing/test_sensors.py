"""Sensors: the noise floor against its datasheet prediction, range and ADC, seeds,
streaming in blocks, the tone ring and line pressure, and every sensor fault."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy import signal

from brake_sim_ros.errors import ParameterError, ScenarioError
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.scenarios import load_scenario, parse_scenario
from brake_sim_ros.sensing import faults as sf
from brake_sim_ros.sensing.faults import SensorFault
from brake_sim_ros.sensing.kinds import SENSOR_KINDS
from brake_sim_ros.sensing.sensors import (
    IDEAL,
    AnalogPath,
    SensorBank,
    SensorChannel,
    SensorFrame,
    SensorSet,
    accelerometer,
    default_channels,
)
from brake_sim_ros.sensing.structure import Mode
from tests.conftest import IMPACTING_S
from tests.sample_blocks import faulted_set

FS = 25_600.0
G0 = 9.80665
ACTUATION_START_S = 0.2  # the published ramp: no force before it


@pytest.fixture(scope="module")
def stop(symmetric_run) -> SampleBlock:
    """The first 1.5 s of the healthy stop: zero force, impacts, steady contact."""
    s = symmetric_run.samples
    n = round(1.5 / s.sample_period_s)
    return SampleBlock(s.data[:n], 0, s.sample_period_s, s.columns)


def _in_blocks(bank: SensorBank, block: SampleBlock, sizes: tuple[int, ...]) -> SensorFrame:
    frames, start = [], 0
    while start < len(block):
        for size in sizes:
            part = SampleBlock(
                block.data[start : start + size],
                block.first_index + start,
                block.sample_period_s,
                block.columns,
            )
            if len(part):
                frames.append(bank.advance(part))
            start += size
    return SensorFrame.concatenate(frames)


def _path_response(transducer, resonance_factor: float = 1.0):
    a, b, c, _ = transducer.continuous(FS, resonance_factor)
    f = np.geomspace(1.0, 1e7, 100_001)
    h = (c @ np.linalg.solve(2j * np.pi * f[:, None, None] * np.eye(a.shape[0]) - a, b))[:, 0, 0]
    return f, h


@pytest.mark.parametrize("preset", ["adxl1002_class", "consumer_imu_class"])
def test_noise_floor_of_a_healthy_stop_matches_density_and_bandwidth(stop, preset):
    """Before the actuation the structure is at rest: what the channel shows is its noise.
    Its in-band density must be the datasheet's, and its rms the density integrated over
    the path's response (resonance, bandwidth, anti-alias filter), each within 20 %."""
    channel = accelerometer("acc", "backing_plate", "x", preset)
    frame = SensorBank(SensorSet(channels=(channel,)), FS, seed=7).advance(stop)
    quiet = frame["acc"].values[frame["acc"].time_s < ACTUATION_START_S]
    density = channel.transducer.noise_density_per_sqrt_hz
    f, p = signal.welch(quiet, FS, nperseg=512)
    band = (f >= 200.0) & (f <= 800.0)  # well inside both bandwidths
    assert math.sqrt(p[band].mean()) == pytest.approx(density, rel=0.2)
    freq, h = _path_response(channel.transducer)
    predicted_rms = density * math.sqrt(np.trapezoid(np.abs(h) ** 2, freq))
    assert quiet.std() == pytest.approx(predicted_rms, rel=0.2)
    # the figure a user reads: ADXL1002 class about 2.8 mg rms, consumer IMU about 10 mg
    assert quiet.std() / G0 == pytest.approx(
        {"adxl1002_class": 2.8e-3, "consumer_imu_class": 1.0e-2}[preset], rel=0.2
    )


def test_clipping_at_the_range_and_quantisation_step():
    transducer = dataclasses.replace(
        SENSOR_KINDS["accelerometer"].presets["adxl1002_class"], adc_bits=10
    )
    channel = SensorChannel("acc", "accelerometer", "backing_plate", "x", transducer)
    t = np.arange(round(0.05 * FS)) / FS
    true = 2.0 * transducer.range_max * np.sin(2 * np.pi * 200.0 * t)
    values = AnalogPath(channel, 1 / FS, seed=0).advance(t, true)
    step = (transducer.range_max - transducer.range_min) / 2**10
    assert transducer.adc_step == step
    assert values.max() == pytest.approx(transducer.range_max - step, rel=1e-12)
    assert values.min() == pytest.approx(transducer.range_min, rel=1e-12)
    codes = (values - transducer.range_min) / step
    assert np.allclose(codes, np.round(codes), atol=1e-6)
    levels = np.unique(values)
    assert np.min(np.diff(levels)) == pytest.approx(step, rel=1e-9)
    # clipped for a while at each extreme
    assert np.sum(values == values.max()) > 10 and np.sum(values == values.min()) > 10


def test_the_default_accelerometers_clip_in_the_first_impacts(stop):
    """The published event's first impacts exceed +-50 g at the backing plate (y): the
    default set reports them clipped, at the top code."""
    frame = SensorBank(SensorSet(), FS, seed=0).advance(stop)
    transducer = SENSOR_KINDS["accelerometer"].presets["adxl1002_class"]
    y = frame["backing_plate_accel_y"].values
    assert y.max() == transducer.range_max - transducer.adc_step or y.min() == transducer.range_min


def test_the_100_g_preset_keeps_the_first_impacts_in_range(stop):
    """The +-100 g part of the same family reports the same stop unclipped, within its
    range, with peaks beyond the 50 g part's."""
    wide = SensorSet(channels=(accelerometer("acc_y", "backing_plate", "y", "adxl1001_class"),))
    transducer = SENSOR_KINDS["accelerometer"].presets["adxl1001_class"]
    y = SensorBank(wide, FS, seed=0).advance(stop)["acc_y"].values
    assert transducer.range_min < y.min() and y.max() < transducer.range_max - transducer.adc_step
    assert np.abs(y).max() > 50.0 * 9.80665


def test_one_seed_gives_the_same_bits_two_seeds_independent_noise(stop):
    a = SensorBank(SensorSet(), FS, seed=1).advance(stop)
    b = SensorBank(SensorSet(), FS, seed=1).advance(stop)
    c = SensorBank(SensorSet(), FS, seed=2).advance(stop)
    for name in a.series:
        assert np.array_equal(a[name].values, b[name].values, equal_nan=True)
    quiet = a["line_pressure"].time_s < ACTUATION_START_S
    for name in ("backing_plate_accel_x", "backing_plate_accel_y"):
        x, y = a[name].values[quiet], c[name].values[quiet]
        assert not np.array_equal(x, y)
        assert abs(np.corrcoef(x, y)[0, 1]) < 0.06
    # two channels of one run are independent too
    x, y = a["backing_plate_accel_x"].values[quiet], a["backing_plate_accel_y"].values[quiet]
    assert abs(np.corrcoef(x, y)[0, 1]) < 0.06


@pytest.mark.parametrize("sensors", [SensorSet(), faulted_set()], ids=["default", "faulted"])
def test_a_stream_in_blocks_equals_one_block_bit_for_bit(stop, sensors):
    whole = SensorBank(sensors, FS, seed=3).advance(stop)
    streamed = _in_blocks(SensorBank(sensors, FS, seed=3), stop, (256, 1, 77, 1000, 5))
    assert whole.series.keys() == streamed.series.keys()
    for name, s in whole.series.items():
        for attr in ("time_s", "values", "fault_label"):
            assert np.array_equal(getattr(s, attr), getattr(streamed[name], attr), equal_nan=True)
    for name, edges in whole.edges_s.items():
        assert np.array_equal(edges, streamed.edges_s[name])
    assert np.array_equal(whole.structure, streamed.structure)


def test_measured_stream_publishes_due_chunks_and_the_rest_at_flush(stop):
    """The stream holds blocks until a chunk is due, then one MeasuredChunk carries every
    pending sample; a flush publishes the rest; joined, they are one block's bits."""
    from brake_sim_ros import stream

    measured = stream.MeasuredStream(SensorBank(SensorSet(), FS, seed=3), chunk_samples=2560)
    chunks, start = [], 0
    for size in (256, 256, 1000, 1100, 256, 77, 3000, 40):  # 5985 samples
        part = SampleBlock(
            stop.data[start : start + size], start, stop.sample_period_s, stop.columns
        )
        chunks.extend(msg for _topic, msg, _ns in measured.feed(part))
        start += size
    assert [m.sample_count for m in chunks] == [2612, 3333]  # due at >= 2560 pending
    assert measured.pending_samples == 40
    rest = [msg for _topic, msg, _ns in measured.flush()]
    assert [m.sample_count for m in rest] == [40] and measured.pending_samples == 0
    assert list(measured.flush()) == []
    chunks += rest
    assert [m.first_sample_index for m in chunks] == [0, 2612, 5945]
    whole = SensorBank(SensorSet(), FS, seed=3).advance(
        SampleBlock(stop.data[:start], 0, stop.sample_period_s, stop.columns)
    )
    for name in chunks[0].channel_names:  # values are channel-major in each chunk
        parts = []
        for m in chunks:
            k = list(m.channel_names).index(name)
            bounds = np.cumsum([0, *m.channel_sample_counts])
            parts.append(np.asarray(m.values)[bounds[k] : bounds[k + 1]])
        assert np.array_equal(np.concatenate(parts), whole[name].values, equal_nan=True), name


def test_decimated_channel_keeps_every_nth_sample_and_refuses_other_rates(stop):
    frame = SensorBank(faulted_set(), FS, seed=0).advance(stop)
    imu = frame["imu_y"]
    assert np.allclose(np.diff(imu.time_s), 1 / 3200.0)
    with pytest.raises(ParameterError, match="rate_hz"):
        SensorBank(
            SensorSet(channels=(dataclasses.replace(default_channels()[0], rate_hz=3000.0),)),
            FS,
            seed=0,
        )


def test_tone_ring_edges_give_the_drum_speed_and_one_index_per_revolution(stop):
    frame = SensorBank(SensorSet(), FS, seed=0).advance(stop)
    teeth = default_channels()[2].tone_ring_teeth
    edges = frame.edges_s["wheel_speed"]
    speed = 2 * np.pi / teeth / np.diff(edges)
    middle = 0.5 * (edges[1:] + edges[:-1])
    true = np.interp(middle, stop.time_s, stop["drum_speed_rad_s"])
    # a tooth's mean speed against the speed at mid-tooth: exact to second order where
    # the speed is smooth (after the impacts, which shake the drum on its coupling, and
    # 20 ms for the last one's shake to pass)
    smooth = middle > IMPACTING_S + 0.02
    assert np.max(np.abs(speed[smooth] / true[smooth] - 1)) < 1e-4
    assert np.max(np.abs(speed / true - 1)) < 0.02
    turns = (stop["drum_angle_rad"][-1] - stop["drum_angle_rad"][0]) / (2 * np.pi)
    assert len(edges) == pytest.approx(teeth * turns, abs=1)
    index = frame["wheel_speed_index"].values
    rising = np.count_nonzero(np.diff(index) > 0.5)
    assert rising == pytest.approx(turns, abs=1)
    pulse = frame["wheel_speed"].values
    assert np.count_nonzero(np.diff(pulse) > 0.5) == pytest.approx(len(edges), abs=1)


def test_line_pressure_is_the_actuation_force_over_the_piston_area(stop):
    frame = SensorBank(SensorSet(), FS, seed=0).advance(stop)
    channel = default_channels()[3]
    area = np.pi * channel.piston_diameter_m**2 / 4
    full = frame["line_pressure"].time_s > 1.0
    expected_bar = 1300.0 / area / 1e5
    assert frame["line_pressure"].values[full].mean() == pytest.approx(expected_bar, rel=2e-3)
    assert 40.0 < expected_bar < 50.0  # TESTBED: 50-180 bar in hard stops; this one is mild


# --- faults --------------------------------------------------------------------------------
def _ideal_path(*faults: SensorFault, transducer=IDEAL) -> AnalogPath:
    channel = SensorChannel("acc", "accelerometer", "backing_plate", "x", transducer, faults=faults)
    return AnalogPath(channel, 1 / FS, seed=0)


T = np.arange(round(0.1 * FS)) / FS
TRUE = 30.0 * np.sin(2 * np.pi * 170.0 * T) + 5.0
ON = T >= 0.04


def test_gain_error():
    out = _ideal_path(SensorFault("gain_error", 0.04, 0.1)).advance(T, TRUE)
    assert np.array_equal(out[~ON], TRUE[~ON])
    assert np.allclose(out[ON], 1.1 * TRUE[ON], rtol=1e-15)


def test_bias_drift():
    out = _ideal_path(SensorFault("bias_drift", 0.04, 2.0)).advance(T, TRUE)
    assert np.array_equal(out[~ON], TRUE[~ON])
    assert np.allclose(out[ON] - TRUE[ON], 2.0 * (T[ON] - 0.04), atol=1e-12)


def test_dropout_for_its_duration():
    out = _ideal_path(SensorFault("dropout", 0.04, duration_s=0.03)).advance(T, TRUE)
    window = ON & (T < 0.07)
    assert np.all(np.isnan(out[window]))
    assert np.array_equal(out[~window], TRUE[~window])


def test_stuck_holds_the_last_value_before_the_onset():
    out = _ideal_path(SensorFault("stuck", 0.04, duration_s=0.03)).advance(T, TRUE)
    window = ON & (T < 0.07)
    first = np.argmax(window)
    assert np.all(out[window] == TRUE[first - 1])
    assert np.array_equal(out[~window], TRUE[~window])


def test_saturation_clips_at_its_size():
    out = _ideal_path(SensorFault("saturation", 0.04, 20.0)).advance(T, TRUE)
    assert np.array_equal(out[~ON], TRUE[~ON])
    assert np.array_equal(out[ON], np.clip(TRUE[ON], -20.0, 20.0))
    assert out[ON].max() == 20.0


def test_loose_mount_moves_the_resonance_down_and_raises_the_response_there():
    transducer = dataclasses.replace(
        SENSOR_KINDS["accelerometer"].presets["adxl1002_class"], noise_density_per_sqrt_hz=0.0
    )
    rng = np.random.default_rng(0)
    t = np.arange(round(1.0 * FS)) / FS
    true = rng.standard_normal(t.shape[0])
    healthy = _ideal_path(transducer=transducer).advance(t, true)
    loose = _ideal_path(SensorFault("loose_mount", 0.5, 0.3), transducer=transducer).advance(
        t, true
    )
    assert np.array_equal(loose[t < 0.5], healthy[t < 0.5])
    after = t >= 0.55
    f, p_healthy = signal.welch(healthy[after], FS, nperseg=1024)
    _, p_loose = signal.welch(loose[after], FS, nperseg=1024)
    ratio = p_loose / p_healthy
    peak = f[np.argmax(p_loose * (f > 2000.0))]
    assert peak == pytest.approx(0.3 * 21_000.0, rel=0.05)
    assert ratio[np.argmin(np.abs(f - 0.3 * 21_000.0))] > 20.0
    assert np.allclose(ratio[(f > 50.0) & (f < 1000.0)], 1.0, rtol=0.1)


def test_faults_are_labelled_per_sample_on_their_channel_only(stop):
    sensors = faulted_set()
    frame = SensorBank(sensors, FS, seed=0).advance(stop)
    for channel in sensors.channels:
        expected = np.zeros(frame[channel.name].time_s.shape, dtype=np.uint8)
        for fault in channel.faults:
            expected[fault.active(frame[channel.name].time_s)] |= sf.FAULT_BIT[fault.kind]
        assert np.array_equal(frame[channel.name].fault_label, expected)
        for fault in channel.faults:
            active = fault.active(frame[channel.name].time_s)
            assert active.any()
            bits = frame[channel.name].fault_label
            assert np.all(bits[active] & sf.FAULT_BIT[fault.kind])
            assert not np.any(bits[~active] & sf.FAULT_BIT[fault.kind])
    assert not frame["imu_y"].fault_label.any()
    # a fault does not disturb the channel before its onset, nor another channel
    clean = SensorBank(SensorSet(), FS, seed=0).advance(stop)
    before = clean["backing_plate_accel_x"].time_s < 0.5
    assert np.array_equal(
        frame["backing_plate_accel_x"].values[before], clean["backing_plate_accel_x"].values[before]
    )


@pytest.mark.parametrize(
    ("fault", "channel", "match"),
    [
        (SensorFault("loose_mount", 0.1, 0.5), default_channels()[3], "fault"),
        (SensorFault("gain_error", 0.1, 0.5), default_channels()[2], "fault"),
        (
            SensorFault("loose_mount", 0.1, 0.5),
            accelerometer("a", "backing_plate", "x", "consumer_imu_class"),
            "mounted resonance",
        ),
    ],
)
def test_faults_a_channel_cannot_have_are_refused(fault, channel, match):
    with pytest.raises(ParameterError, match=match):
        channel.with_faults(fault)


@pytest.mark.parametrize(
    "args",
    [
        ("tilt", 0.1),
        ("gain_error", -0.1, -1.0),
        ("dropout", 0.1, 1.0),
        ("loose_mount", 0.0, 1.5),
        ("saturation", 0.0, 0.0),
        ("bias_drift", -1.0, 1.0),
    ],
)
def test_invalid_faults_are_refused(args):
    with pytest.raises(ParameterError, match="sensor fault"):
        SensorFault(*args)


# --- scenario tables ------------------------------------------------------------------------
_HEAD = 'name = "t"\n'
_SENSORS = """
[structure]
mounts = ["plate", "arm"]
[[structure.modes]]
direction = "y"
frequency_hz = 2000.0
damping_ratio = 0.03
modal_mass_kg = 3.0
left_pin = 1.0
right_pin = 0.5
at_mounts = [1.0, 0.2]

[[sensors]]
name = "plate_y"
kind = "accelerometer"
preset = "consumer_imu_class"
location = "plate"
axis = "y"
rate_hz = 3200.0
bandwidth_hz = 0
adc_bits = 12
[[sensors.faults]]
kind = "bias_drift"
onset_s = 1.0
size = 0.5
duration_s = 2.0

[[sensors]]
name = "wheel"
kind = "wheel_speed"
location = "tone_ring"
tone_ring_teeth = 44
"""


def test_the_built_in_scenarios_carry_the_default_sensor_set():
    assert load_scenario("symmetric").sensors == SensorSet()


def test_structure_and_sensor_tables_are_read():
    scenario = parse_scenario(_HEAD + _SENSORS)
    s = scenario.sensors
    assert s.structure.mounts == ("plate", "arm")
    assert s.structure.modes == (Mode("y", 2000.0, 0.03, 3.0, 1.0, 0.5, (1.0, 0.2)),)
    plate, wheel = s.channels
    assert plate.transducer.bandwidth_hz is None and plate.transducer.adc_bits == 12
    assert plate.transducer.noise_density_per_sqrt_hz == pytest.approx(300e-6 * G0)
    assert plate.rate_hz == 3200.0
    assert plate.faults == (SensorFault("bias_drift", 1.0, 0.5, 2.0),)
    assert wheel.tone_ring_teeth == 44
    assert parse_scenario(_HEAD + "sensors = []\n").sensors.channels == ()


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (('axis = "y"', 'axis = "z"'), r"\[sensors\[0\]\].*axis"),
        (("rate_hz = 3200.0", "colour = 1"), r"key 'sensors\[0\]\.colour'.*unknown key"),
        (('kind = "bias_drift"', 'kind = "rust"'), r"key 'sensors\[0\]\.faults\[0\]\.kind'"),
        (('preset = "consumer_imu_class"', 'preset = "adxl9"'), r"sensors\[0\]\.preset"),
        (("adc_bits = 12", "adc_bits = 1.5"), r"sensors\[0\]\.adc_bits.*integer"),
        (('location = "plate"', 'location = "hub"'), r"\[sensors\].*mount point"),
        (("damping_ratio = 0.03", "damping_ratio = 1.5"), r"\[structure\.modes\[0\]\]"),
        (("at_mounts = [1.0, 0.2]", "at_mounts = [1.0]"), r"\[structure\].*one value per mount"),
        (('name = "wheel"', 'name = "plate_y"'), r"used twice"),
    ],
)
def test_bad_sensor_tables_are_refused_with_the_table_and_key(change, message):
    old, new = change
    assert old in _SENSORS
    with pytest.raises(ScenarioError, match=message) as info:
        parse_scenario(_HEAD + _SENSORS.replace(old, new, 1), "my.toml")
    assert str(info.value).startswith("my.toml: ")
    assert "\n" not in str(info.value)


def test_an_empty_block_changes_nothing(stop):
    sensors = faulted_set()
    whole = SensorBank(sensors, FS, seed=4).advance(stop)
    bank = SensorBank(sensors, FS, seed=4)
    n = len(stop) // 2
    frames = []
    for lo, hi in ((0, n), (n, n), (n, len(stop))):
        frames.append(
            bank.advance(SampleBlock(stop.data[lo:hi], lo, stop.sample_period_s, stop.columns))
        )
    joined = SensorFrame.concatenate(frames)
    for name, s in whole.series.items():
        assert np.array_equal(s.values, joined[name].values, equal_nan=True)


def test_the_sensor_study_is_registered_and_prints_its_figures(capsys):
    from brake_sim_ros.studies import BENCHMARKS

    assert BENCHMARKS["sensors"].run(["--duration", "0.3", "--repeats", "1", "--no-cases"]) == 0
    out = capsys.readouterr().out
    assert "x real time" in out and "sensor set + structure" in out
