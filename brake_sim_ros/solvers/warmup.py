"""Compile the physics kernels ahead of use, and say so while it happens.

numba compiles a kernel on its first call and keeps the machine code in the on-disk cache
(see :mod:`brake_sim_ros.model`). A first call otherwise sits silent for tens of seconds.
The kernels come in parts (:data:`PARTS`), each compiled by running a tiny event through
it when the cache has no record of it (a marker file per part), printing one line before,
one every :data:`TICK_S` seconds while it compiles (the time so far, the parts done of
those asked, the functions in the cache so far, each part's state) and one after: a fixed
estimate of the time would not hold on a loaded machine.

The set-up command compiles the parts of the default paths (:data:`DEFAULT_PARTS`: the
fixed-step kernel and the default sensors, which ``brake-sim live`` and every preset run),
so that the first ``brake-sim`` command starts at once. The others (the reference solver,
the contact-regime levels) compile at their first use, with the same lines
(:func:`ensure_compiled` at the top of their drivers). Processes that need a part at the
same time (test or sweep workers) take turns on a lock file: one compiles, the others then
load it from the cache.

numba's own cache (``cache=True``) keys each compiled function by its source file's path,
modification time and size, its signature and the target machine (CPU name and
features), so a cache is never loaded on a platform it was not built for;
:mod:`brake_sim_ros.model` adds a directory per hash of the model's sources (numba checks
only the file of each cached function, not the files of the functions it inlines).

The machinery (markers, lock, progress lines) is :mod:`brake_sim_ros.solvers.kernel_parts`;
this module registers the default parts and imports the drivers that register theirs.
Run ``python -m brake_sim_ros.solvers.warmup`` to compile (or check) the default parts,
``... warmup --all`` for every part.
"""

from __future__ import annotations

import sys

# the drivers whose parts compile at first use register them on import
import brake_sim_ros.solvers.contact_regime
import brake_sim_ros.solvers.reference  # noqa: F401
from brake_sim_ros.solvers.kernel_parts import (  # noqa: F401 - this module's interface
    DEFAULT_PARTS,
    PARTS,
    TICK_S,
    compile_kernels,
    compile_parts,
    ensure_compiled,
    is_compiled,
    register,
)


def _compile_stepping() -> None:
    """The fixed-step kernel (every scheme is one compiled function) and the step-limit
    analysis: the longest compile by far."""
    from brake_sim_ros.model.run_setup import BrakeSetup
    from brake_sim_ros.solvers.fixed_step import FIXED_STEP_SCHEMES, FixedStepStepper

    setup = BrakeSetup()
    for scheme in FIXED_STEP_SCHEMES:
        FixedStepStepper(setup, 4e-5, scheme=scheme).advance(8, record_every=2)


def _compile_sensors() -> None:
    """The default sensor set's paths, on a block of zeros (no stepping)."""
    import numpy as np

    from brake_sim_ros.model.layout import COLUMNS
    from brake_sim_ros.model.run_setup import SampleBlock
    from brake_sim_ros.sensing.sensors import SensorBank, default_sensor_set

    block = SampleBlock(np.zeros((8, len(COLUMNS))), 0, 1.0 / 25_600.0)
    SensorBank(default_sensor_set(), 25_600.0, 0).advance(block)


register("stepping", "fixed-step kernel", _compile_stepping)
register("sensors", "default sensors", _compile_sensors)


if __name__ == "__main__":
    every = "--all" in sys.argv[1:]
    rest = tuple(part for part in PARTS if part not in DEFAULT_PARTS)
    ensure_compiled(
        lambda line: print(line, flush=True), DEFAULT_PARTS + rest if every else DEFAULT_PARTS
    )
