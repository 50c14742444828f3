"""The sampled noise of a sensor path (``lti.with_input_noise``) against the exact one.

A continuous path driven by white noise, sampled every ``T``, is exactly a discrete process
whose state gains a Gaussian increment of covariance ``Q_d`` per sample (one draw per
state). The path's sampled form draws once per sample (innovations form); its output must
have the same autocovariance at every lag: here lags 0 to 64, each from its own matrices,
the reference in balanced coordinates (the cascaded filters' states span tens of orders of
magnitude).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import (
    expm,
    matrix_balance,
    solve_continuous_lyapunov,
    solve_discrete_lyapunov,
)

from brake_sim_ros.sensing.kinds import SENSOR_KINDS
from brake_sim_ros.sensing.lti import foh_discretise, with_input_noise

FS = 25_600.0
LAGS = 64


def _scaling(a: np.ndarray) -> np.ndarray:
    """A diagonal similarity that balances ``a`` (the cascaded filters' states span tens of
    orders of magnitude; the Lyapunov solvers need them comparable)."""
    _balanced, (scale, _perm) = matrix_balance(a, permute=False, separate=True)
    return np.diag(scale)


def _sampled_autocovariance(system, t: np.ndarray) -> np.ndarray:
    """r[l] of the output noise of ``system`` (its last input: unit normal draws), in the
    state coordinates ``t^-1 x``."""
    t_inv = np.linalg.inv(t)
    phi, c = t_inv @ system.phi @ t, system.c @ t
    g = t_inv @ system.g_prev[:, -1:]  # the draw of sample k moves the state at k + 1
    d = system.d[0, -1]  # and is in the output at k
    pi = solve_discrete_lyapunov(phi, g @ g.T)
    out = [(c @ pi @ c.T).item() + d * d]
    power = np.eye(phi.shape[0])
    for _ in range(1, LAGS):
        out.append((c @ power @ phi @ pi @ c.T).item() + (c @ power @ g).item() * d)
        power = power @ phi
    return np.array(out)


def _exact_autocovariance(a, b, c, q, t: np.ndarray, fs: float = FS) -> np.ndarray:
    """r[l] of the continuous path's output noise sampled at FS: its state increment over
    a sample has the covariance ``Q_d`` (Van Loan, from the continuous ``a``, ``b``) and
    the stationary state covariance ``P = Phi P Phi^T + Q_d``; ``r[l] = C Phi^l P C^T``.
    Computed in the balanced coordinates ``t^-1 x``."""
    t_inv = np.linalg.inv(t)
    a, b, c = t_inv @ a @ t, t_inv @ b, c @ t
    n = a.shape[0]
    big = np.zeros((2 * n, 2 * n))
    big[:n, :n], big[:n, n:], big[n:, n:] = -a, q * (b @ b.T), a.T
    e = expm(big / fs)
    phi = e[n:, n:].T
    q_d = phi @ e[:n, n:]
    p = solve_discrete_lyapunov(phi, 0.5 * (q_d + q_d.T))
    out, power = [], np.eye(n)
    for _ in range(LAGS):
        out.append((c @ power @ p @ c.T).item())
        power = power @ phi
    return np.array(out)


@pytest.mark.parametrize(
    ("preset", "resonance_factor", "fs"),
    [
        ("adxl1002_class", 1.0, FS),
        ("adxl1002_class", 0.5, FS),
        ("consumer_imu_class", 1.0, FS),
    ],
    ids=["adxl1002", "adxl1002-loose-mount", "consumer-imu"],
)
def test_sampled_noise_has_the_continuous_autocovariance_at_every_lag(preset, resonance_factor, fs):
    transducer = SENSOR_KINDS["accelerometer"].presets[preset]
    a, b, c, d = transducer.continuous(fs, resonance_factor)
    density = transducer.noise_density_per_sqrt_hz
    noisy = with_input_noise(foh_discretise(a, b, c, d, 1.0 / fs), density)
    assert noisy.g_prev.shape[1] == 2  # the signal and one draw per sample
    t = _scaling(a)
    expected = _exact_autocovariance(a, b, c, 0.5 * density**2, t, fs)
    got = _sampled_autocovariance(noisy, t)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9 * expected[0])
    assert abs(expected[1]) > 0.01 * expected[0]  # coloured noise: the lags matter


def test_at_a_slow_rate_the_noise_is_the_continuous_paths():
    """At 1 kHz the 21 kHz resonance spans twenty sample periods, where the exact
    reference above overflows: against the continuous process itself, ``r(l T) = C e^(A l
    T) P C^T`` with ``A P + P A^T + B q B^T = 0`` (solved in balanced coordinates, to
    about 1e-3 of the variance: the solver's own accuracy on this path)."""
    fs = 1000.0
    transducer = SENSOR_KINDS["accelerometer"].presets["adxl1002_class"]
    a, b, c, d = transducer.continuous(fs, 1.0)
    density = transducer.noise_density_per_sqrt_hz
    noisy = with_input_noise(foh_discretise(a, b, c, d, 1.0 / fs), density)
    t = _scaling(a)
    t_inv = np.linalg.inv(t)
    ab, bb, cb = t_inv @ a @ t, t_inv @ b, c @ t
    p = solve_continuous_lyapunov(ab, -0.5 * density**2 * (bb @ bb.T))
    step = expm(ab / fs)
    expected, power = [], np.eye(a.shape[0])
    for _ in range(LAGS):
        expected.append((cb @ power @ p @ cb.T).item())
        power = power @ step
    got = _sampled_autocovariance(noisy, t)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-3 * expected[0])


def test_a_path_much_faster_than_a_slow_sample_rate_still_gets_its_noise():
    """At 20 Hz the accelerometer's 21 kHz resonance spans a thousand times the sample
    period: the noise increment is still computed (no overflow) and realised with one draw
    per sample, its variance that of the continuous path (``Q_d`` settles to it)."""
    transducer = SENSOR_KINDS["accelerometer"].presets["adxl1002_class"]
    a, b, c, d = transducer.continuous(20.0, 1.0)
    noisy = with_input_noise(foh_discretise(a, b, c, d, 1.0 / 20.0), 25e-6 * 9.80665)
    assert noisy.g_prev.shape[1] == 2 and np.all(np.isfinite(noisy.g_prev))
    variance = _sampled_autocovariance(noisy, _scaling(a))[0]
    assert np.isfinite(variance) and variance > 0.0


def test_noise_needs_one_input_one_output_and_no_feedthrough():
    a = np.array([[-1.0]])
    system = foh_discretise(a, np.ones((1, 1)), np.ones((1, 1)), np.ones((1, 1)), 1.0 / FS)
    with pytest.raises(ValueError, match="no feedthrough"):
        with_input_noise(system, 1.0)
