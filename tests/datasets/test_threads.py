"""One numerics thread (datasets/threads.py): a command's fresh process takes one BLAS,
OpenMP and numba thread unless its user set them; a process that has numpy already keeps
its environment; a sweep worker always takes one."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from brake_sim_ros.datasets.threads import THREAD_LIMIT_VARIABLES, one_numerics_thread

PROBE = """
import json, os
from brake_sim_ros.datasets.threads import THREAD_LIMIT_VARIABLES, one_numerics_thread
one_numerics_thread()
import numpy
from threadpoolctl import threadpool_info
blas = sorted({i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"})
print(json.dumps({"env": {k: os.environ.get(k) for k in THREAD_LIMIT_VARIABLES}, "blas": blas}))
"""


def _probe(**env: str) -> dict:
    base = {k: v for k, v in os.environ.items() if k not in THREAD_LIMIT_VARIABLES}
    done = subprocess.run(
        [sys.executable, "-c", PROBE],
        env={**base, **env},
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    return json.loads(done.stdout)


def test_a_fresh_process_takes_one_thread_unless_its_user_set_them():
    fresh = _probe()
    assert fresh["env"] == dict.fromkeys(THREAD_LIMIT_VARIABLES, "1")
    assert fresh["blas"] == [1]  # numpy's BLAS started with one thread
    chosen = _probe(OPENBLAS_NUM_THREADS="2")
    assert chosen["env"]["OPENBLAS_NUM_THREADS"] == "2"
    assert chosen["env"]["OMP_NUM_THREADS"] == "1"


def test_a_process_with_numpy_keeps_its_environment(monkeypatch):
    assert "numpy" in sys.modules  # the suite's process has it
    for name in THREAD_LIMIT_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    one_numerics_thread()
    assert not [name for name in THREAD_LIMIT_VARIABLES if name in os.environ]


KEPT = """
import brake_sim_ros.model
import numba
from numba import njit
from brake_sim_ros.datasets.threads import limit_threads
ours = numba.config.CACHE_DIR
limit_threads()
njit(lambda x: x + 1)(1)  # a compile: numba reads its changed settings then
print(ours != "" and numba.config.CACHE_DIR == ours)
"""


def test_limiting_threads_after_numba_keeps_the_kernel_cache():
    """A worker (or a benchmark) that limits its threads after numba is imported keeps
    numba's cache at the kernels' directory (numba would read NUMBA_NUM_THREADS again and
    its cache directory with it, back to its default)."""
    base = {k: v for k, v in os.environ.items() if k not in THREAD_LIMIT_VARIABLES}
    base.pop("NUMBA_CACHE_DIR", None)
    done = subprocess.run(
        [sys.executable, "-c", KEPT], env=base, capture_output=True, text=True, timeout=120
    )
    assert done.stdout.strip() == "True", done.stderr
