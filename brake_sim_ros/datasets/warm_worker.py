"""Imported once by the sweep's fork server (:mod:`.sweep`), before it forks the pool's
workers: limits each worker to one numerics thread, imports what a run needs and runs a
tiny scenario through the run and table path, so every kernel is loaded from numba's
cache once and each forked worker starts warm instead of loading them itself (some
seconds of CPU each). Writes nothing; a warm-up that fails only leaves the workers to load
the kernels themselves.
"""

from __future__ import annotations

from brake_sim_ros.datasets.orphans import die_with_parent
from brake_sim_ros.datasets.threads import limit_threads

die_with_parent()  # the server is the sweep's child: it ends with it (its workers with it)
limit_threads()  # before numba, numpy's BLAS or pyarrow start their threads

import pyarrow  # noqa: E402

from brake_sim_ros.datasets.parquet import run_table  # noqa: E402
from brake_sim_ros.scenarios.loader import parse_scenario  # noqa: E402
from brake_sim_ros.stream.run import run_scenario  # noqa: E402

pyarrow.set_cpu_count(1)
try:
    _TINY = parse_scenario(
        'name = "warm-up"\nduration_s = 0.02\nsample_rate_hz = 2560.0\n', "<sweep worker warm-up>"
    )
    run_table(_TINY, run_scenario(_TINY), _TINY.duration_s)
except Exception:  # a failed warm-up costs time, not runs: each worker loads its own
    pass
