"""One numerics thread per sweep worker: the pool gives the parallelism, so numba, the
BLAS behind numpy and OpenMP must not each start a thread per core in every worker.

Kept apart from :mod:`.sweep` so that the fork server (:mod:`.warm_worker`) sets the
limits before anything imports numba or numpy.
"""

from __future__ import annotations

import os

THREAD_LIMIT_VARIABLES = (
    "NUMBA_NUM_THREADS",
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
)


def limit_threads() -> None:
    """Set each of :data:`THREAD_LIMIT_VARIABLES` to 1 in this process's environment
    (effective for libraries imported afterwards, and for processes started from it)."""
    for name in THREAD_LIMIT_VARIABLES:
        os.environ[name] = "1"
