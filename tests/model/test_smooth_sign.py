"""The smoothed sign skips ``tanh`` only where ``tanh`` rounds to +-1.0: the same bits."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from brake_sim_ros.model.smooth_sign import SATURATED, smooth_sign


@njit(cache=False)
def _both(xs):
    out = np.empty((2, xs.shape[0]))
    for i in range(xs.shape[0]):
        out[0, i] = math.tanh(xs[i])
        out[1, i] = smooth_sign(xs[i])
    return out


def _arguments() -> np.ndarray:
    near = np.linspace(18.0, 40.0, 200_001)  # through the saturation, fine-grained
    wide = np.geomspace(1e-12, 1e12, 20_001)
    edges = np.array([SATURATED, np.nextafter(SATURATED, 0.0), 0.0, np.inf])
    positive = np.concatenate([near, wide, edges])
    return np.concatenate([positive, -positive, [np.nan, -0.0]])


def test_the_same_bits_as_tanh_everywhere() -> None:
    xs = _arguments()
    tanh, smooth = _both(xs)
    assert np.array_equal(tanh.view(np.int64), smooth.view(np.int64))


def test_tanh_is_plus_or_minus_one_from_the_threshold_on() -> None:
    """The premise, in the compiled code and in Python: numba calls the C library's tanh."""
    xs = np.linspace(SATURATED, 60.0, 100_001)
    tanh, _ = _both(np.concatenate([xs, -xs]))
    assert np.all(tanh[: xs.size] == 1.0) and np.all(tanh[xs.size :] == -1.0)
    assert math.tanh(SATURATED) == 1.0 and math.tanh(np.nextafter(19.0, 0.0)) < 1.0
