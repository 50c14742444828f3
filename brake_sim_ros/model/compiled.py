"""How the model's compiled (numba) functions are compiled: one set of options.

``@njit(**JIT)`` (or ``@njit(inline="always", **JIT)``) on every compiled function of the
model: cached on disk, and IEEE semantics for a division by zero (``inf``/``nan``, numba's
``error_model="numpy"``) instead of a test before every division that would raise
ZeroDivisionError inside compiled code. The tests cost about a tenth of the stepping
(``brake-sim bench cycle``), and a non-finite result is what the steppers already watch
for: the fixed-step kernel stops on a non-finite state and reports it (layout.K_STATUS).
Every division by a non-zero number gives the same bits either way.
"""

from __future__ import annotations

JIT: dict[str, object] = {"cache": True, "error_model": "numpy"}
