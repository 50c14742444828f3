"""The model's smoothed sign, ``tanh(x)``, compiled (numba): friction's and rolling
resistance's ``tanh(v / v_s)``.

Beyond ``|x|`` of about 19.06, ``tanh(x)`` lies within half an ulp of 1 and rounds to
exactly +-1.0 (the C library's ``tanh``, which numba calls, returns that).
:func:`smooth_sign` returns +-1.0 from ``|x| >= 20`` without the call: the same bits
(``tests/model/test_smooth_sign.py``). A sliding drum is there: 0.02 m/s of smoothing
against metres a second of sliding, so each lining node's friction skips the call.
"""

from __future__ import annotations

import math

from numba import njit

from brake_sim_ros.model.compiled import JIT

# from here on tanh rounds to +-1.0 exactly (from 19.06, with a margin)
SATURATED = 20.0


@njit(inline="always", **JIT)
def smooth_sign(x):
    """``tanh(x)``, the same bits, without the call where it is +-1.0 (a NaN stays NaN)."""
    if x >= SATURATED:
        return 1.0
    if x <= -SATURATED:
        return -1.0
    return math.tanh(x)
