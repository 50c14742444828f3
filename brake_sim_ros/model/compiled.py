"""How the model's compiled (numba) functions are compiled: one set of options.

``@njit(**JIT)`` (or ``@njit(inline="always", **JIT)``) on every compiled function of the
model: cached on disk, and IEEE semantics for a division by zero (``inf``/``nan``, numba's
``error_model="numpy"``) instead of a test before every division that would raise
ZeroDivisionError inside compiled code. The tests cost about a tenth of the stepping
(``brake-sim bench cycle``), and a non-finite result is what the steppers already watch
for: the fixed-step kernel stops on a non-finite state and reports it (layout.K_STATUS).
Every division by a non-zero number gives the same bits either way.

Without numba's reference counting of arrays (``_nrt=False``, numba's own switch, which a
function compiled inside another's would otherwise inherit): a counted array costs an
atomic increment and decrement at every call that passes it, and the stepping kernel's
calls pass ``p`` and the state many times a stage. They took three quarters of the fixed-step
kernel's time (`perf` on the symmetric stop, 2026-11-28); without them the kernel runs
about three times as fast with the same bits (``scripts/hash_outputs.py``). Such a function
cannot allocate an array; the few that do (a kernel's shell that allocates its scratch and
hands it to a loop compiled without counting, a whole-array helper) take
``JIT_ALLOCATING``, which sets counting on explicitly so that it is not inherited off.
"""

from __future__ import annotations

JIT: dict[str, object] = {"cache": True, "error_model": "numpy", "_nrt": False}
JIT_ALLOCATING: dict[str, object] = {"cache": True, "error_model": "numpy", "_nrt": True}
