"""One numerics thread per sweep worker: the pool gives the parallelism, so numba, the
BLAS behind numpy and OpenMP must not each start a thread per core in every worker.
A command that runs the physics in its own process takes one too, unless its user set
the variables (:func:`one_numerics_thread`).

Kept apart from :mod:`.sweep` so that the fork server (:mod:`.warm_worker`) sets the
limits before anything imports numba or numpy.
"""

from __future__ import annotations

import os
import sys

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
    _keep_kernel_cache()


def _keep_kernel_cache() -> None:
    """Where numba is imported already: numba reads its ``NUMBA_*`` settings again when one
    changes (at its next compile), its cache directory with them, which would drop the
    directory ``brake_sim_ros.model`` pointed it at (numba's default places beside the
    sources instead). Read them now and point it back."""
    if "numba" not in sys.modules:
        return
    import numba

    cache = numba.config.CACHE_DIR
    numba.config.reload_config()
    numba.config.CACHE_DIR = cache


def one_numerics_thread() -> None:
    """Each of :data:`THREAD_LIMIT_VARIABLES` that the environment does not set, set to 1:
    for a command's own process (``brake-sim simulate``, ``bench``, ``node`` ...), before
    it imports numpy. Its matrices have a few dozen rows at most, where a BLAS thread per
    core buys nothing, and OpenBLAS's threads spin on a core after every call: after the
    sensors' set-up that took a fifth to a third of the CPU of ``brake-sim bench cycle``
    (2026-11-28, 2 cores). Nothing once numpy is imported (``brake_sim_ros.cli.main``
    called from a program that has it): its BLAS read them then, and the caller's
    environment is the caller's."""
    if "numpy" in sys.modules:
        return
    for name in THREAD_LIMIT_VARIABLES:
        os.environ.setdefault(name, "1")
