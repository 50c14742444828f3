"""The modal structure: its modes where they are set, the static solution, exactness of
the per-sample solution, and a stream in blocks equal to one block bit for bit."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy import signal

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.sensing.structure import (
    AXES,
    FORCE_COLUMNS,
    Mode,
    Structure,
    StructureParameters,
)
from tests.conftest import IMPACTING_S

PARAMS = StructureParameters()


def _spectrum_peak(x: np.ndarray, fs: float, lo: float, hi: float) -> float:
    f, p = signal.welch(x, fs, nperseg=8192)
    band = (f >= lo) & (f <= hi)
    return float(f[band][np.argmax(p[band])])


def test_modes_appear_at_their_frequencies_in_a_healthy_stop(symmetric_run):
    samples = symmetric_run.samples
    fs = 1.0 / samples.sample_period_s
    out = Structure(PARAMS, samples.sample_period_s).advance(samples)
    # steady contact after the impacts, up to the stop: the force's small broadband
    # fluctuations excite every mode (the impacts' steep force spectrum would pull the
    # response peaks below the natural frequencies)
    lo, hi = round(IMPACTING_S * fs), round(6.0 * fs)
    for mode in PARAMS.modes:
        col = Structure(PARAMS, samples.sample_period_s).names.index(
            f"backing_plate_accel_{mode.direction}_m_s2"
        )
        peak = _spectrum_peak(
            out[lo:hi, col], fs, 0.85 * mode.frequency_hz, 1.15 * mode.frequency_hz
        )
        assert peak == pytest.approx(mode.frequency_hz, rel=0.02), (mode, peak)


def test_constant_force_settles_to_the_static_solution():
    fs = 25_600.0
    n = round(0.5 * fs)
    force = np.zeros((n, len(FORCE_COLUMNS)))
    applied = np.array([-1500.0, 2500.0, 400.0, 900.0])  # pin forces on the shoes, N
    force[round(0.01 * fs) :] = applied
    structure = Structure(PARAMS, 1.0 / fs)
    out = structure.advance_forces(force)
    # by hand: each mode deflects by its generalised force over its stiffness; the plate
    # receives the opposite of the pin force
    for j, mount in enumerate(PARAMS.mounts):
        for axis in AXES:
            f_left = -applied[FORCE_COLUMNS.index(f"left_pivot_f{axis}_n")]
            f_right = -applied[FORCE_COLUMNS.index(f"right_pivot_f{axis}_n")]
            static = sum(
                m.at_mounts[j] * (m.left_pin * f_left + m.right_pin * f_right) / m.stiffness_n_m
                for m in PARAMS.modes
                if m.direction == axis
            )
            disp = out[-1, structure.names.index(f"{mount}_disp_{axis}_m")]
            acc = out[-1, structure.names.index(f"{mount}_accel_{axis}_m_s2")]
            assert disp == pytest.approx(static, rel=1e-6)
            assert (
                abs(acc)
                < 1e-6 * np.abs(out[:, structure.names.index(f"{mount}_accel_{axis}_m_s2")]).max()
            )


def test_per_sample_solution_is_exact_for_piecewise_linear_forces():
    """Against scipy's lsim (linear interpolation between samples: the same input)."""
    fs = 25_600.0
    rng = np.random.default_rng(3)
    force = np.cumsum(rng.standard_normal((4000, 4)), axis=0) * 20.0
    force[0] = 0.0
    structure = Structure(PARAMS, 1.0 / fs)
    ours = structure.advance_forces(force)
    a, b, c, d = PARAMS.continuous()
    t = np.arange(force.shape[0]) / fs
    _, theirs, _ = signal.lsim((a, b, c, d), force, t, interp=True)
    scale = np.abs(theirs).max(axis=0)
    assert np.all(np.abs(ours - theirs).max(axis=0) <= 1e-7 * scale)


def test_a_stream_in_blocks_equals_one_block_bit_for_bit(symmetric_run):
    samples = symmetric_run.samples
    n = round(1.0 / samples.sample_period_s)
    block = SampleBlock(samples.data[:n], 0, samples.sample_period_s, samples.columns)
    whole = Structure(PARAMS, block.sample_period_s).advance(block)
    streamed = Structure(PARAMS, block.sample_period_s)
    parts, start = [], 0
    for size in (1, 7, 256, 1000, 3, n):
        part = SampleBlock(
            block.data[start : start + size], start, block.sample_period_s, block.columns
        )
        parts.append(streamed.advance(part))
        start += size
        if start >= n:
            break
    assert np.array_equal(np.concatenate(parts), whole)


@pytest.mark.parametrize(
    "change",
    [
        {"direction": "z"},
        {"frequency_hz": 0.0},
        {"damping_ratio": 1.0},
        {"modal_mass_kg": -1.0},
        {"at_mounts": (1.0,)},
    ],
)
def test_invalid_modes_are_refused(change):
    with pytest.raises(ParameterError, match="structure"):
        mode = dataclasses.replace(PARAMS.modes[0], **change)
        StructureParameters(modes=(mode,))


def test_mode_rejects_nonfinite_shape():
    with pytest.raises(ParameterError):
        Mode("x", 1000.0, 0.02, 1.0, 1.0, 1.0, (float("nan"), 0.0))


def test_selected_outputs_are_the_full_outputs_bit_for_bit(symmetric_run):
    """A structure that computes some outputs (what a sensor set reads) gives exactly those
    columns of the full structure, in the order asked for, through the impacts."""
    samples = symmetric_run.samples
    n = round(1.0 / samples.sample_period_s)
    block = SampleBlock(samples.data[:n], 0, samples.sample_period_s, samples.columns)
    full = Structure(PARAMS, block.sample_period_s)
    everything = full.advance(block)
    assert np.max(np.abs(everything[:, full.names.index("backing_plate_accel_y_m_s2")])) > 100.0
    for names in (
        ("backing_plate_accel_x_m_s2", "backing_plate_accel_y_m_s2"),
        ("knuckle_disp_y_m", "backing_plate_accel_x_m_s2"),
        ("knuckle_accel_x_m_s2",),
    ):
        part = Structure(PARAMS, block.sample_period_s, names)
        assert part.names == names
        out = part.advance(block)
        assert out.shape == (n, len(names))
        for i, name in enumerate(names):
            column = everything[:, full.names.index(name)]
            assert np.array_equal(out[:, i].view(np.int64), column.view(np.int64)), name


def test_an_unknown_output_is_refused_in_one_line():
    with pytest.raises(ParameterError) as err:
        Structure(PARAMS, 1e-4, ("backing_plate_accel_z_m_s2",))
    message = str(err.value)
    assert "\n" not in message
    assert "backing_plate_accel_z_m_s2" in message and "knuckle_disp_y_m" in message
