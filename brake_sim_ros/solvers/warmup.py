"""Compile every physics kernel once, ahead of use, and say so while it happens.

numba compiles a kernel on its first call and keeps the machine code in the on-disk cache
(see :mod:`brake_sim_ros.model`). A first call otherwise sits silent for tens of seconds;
:func:`ensure_compiled` runs a tiny event through every path (each fixed-step scheme, the
sample evaluation of the reference solver, the contact-regime level, the step-limit
analysis and the default sensors' paths) when the cache has no record of it, printing one
line before, one every :data:`TICK_S` seconds while it compiles (the time so far, the
functions in the cache so far, each part compiling or done) and one after: a fixed
estimate of the time would not hold on a loaded machine. The set-up command runs it, so
the first ``brake-sim`` command starts at once.

numba's own cache (``cache=True``) keys each compiled function by its source file's path,
modification time and size, its signature and the target machine (CPU name and
features), so a cache is never loaded on a platform it was not built for;
:mod:`brake_sim_ros.model` adds a directory per hash of the model's sources (numba checks
only the file of each cached function, not the files of the functions it inlines).

Run ``python -m brake_sim_ros.solvers.warmup`` to compile (or check) explicitly.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import numba

# sets numba's cache directory, which the marker lives in: without it a caller that has not
# imported the model yet (the CLI starts light) would find no marker and compile again
import brake_sim_ros.model  # noqa: F401

_MARKER = "brake_sim_compiled"
TICK_S = 10.0  # s between two progress lines while the kernels compile
# what the child process runs (by the module's name: run as __main__, this one has another)
_CHILD = "from brake_sim_ros.solvers.warmup import _compile_the_rest; _compile_the_rest()"


def _marker() -> Path | None:
    cache = numba.config.CACHE_DIR
    return Path(cache) / _MARKER if cache else None


def is_compiled() -> bool:
    """Whether the kernels of this source version are in the cache already."""
    marker = _marker()
    return marker is not None and marker.exists()


def _compile_stepping() -> None:
    """The fixed-step kernel, every scheme: the longest compile by far."""
    from brake_sim_ros.model.run_setup import BrakeSetup
    from brake_sim_ros.solvers.fixed_step import FIXED_STEP_SCHEMES, FixedStepStepper

    setup = BrakeSetup()
    for scheme in FIXED_STEP_SCHEMES:
        FixedStepStepper(setup, 4e-5, scheme=scheme).advance(8, record_every=2)


def _compile_the_rest() -> None:
    """The reference solver's sample evaluation, the contact-regime level and the default
    sensor set's paths (on a block of zeros: no stepping, so no kernel of the other part)."""
    import numpy as np

    from brake_sim_ros.model.layout import COLUMNS
    from brake_sim_ros.model.run_setup import BrakeSetup, SampleBlock
    from brake_sim_ros.sensing.sensors import SensorBank, default_sensor_set
    from brake_sim_ros.solvers.contact_regime import run_contact_regime
    from brake_sim_ros.solvers.reference import run_reference

    setup = BrakeSetup()
    run_reference(setup, 0.01, rtol=1e-6)
    run_contact_regime(setup, 0.01)
    block = SampleBlock(np.zeros((8, len(COLUMNS))), 0, 1.0 / 25_600.0)
    SensorBank(default_sensor_set(), 25_600.0, 0).advance(block)


def _cached_functions() -> int:
    """How many compiled functions the kernel cache holds (numba's index files)."""
    cache = numba.config.CACHE_DIR
    return sum(1 for _ in Path(cache).rglob("*.nbi")) if cache else 0


class _Progress:
    """A line to ``say`` every :data:`TICK_S` s from a daemon thread until stopped: the
    time so far, the functions cached so far and each part's state."""

    def __init__(self, say: Callable[[str], None] | None, parts: dict[str, str]) -> None:
        self.say, self.parts = say, parts
        self.start = time.perf_counter()
        self.stopped = threading.Event()
        self.thread = threading.Thread(target=self._tick, daemon=True)
        if say is not None:
            self.thread.start()

    def _tick(self) -> None:
        while not self.stopped.wait(TICK_S):
            states = ", ".join(f"{part}: {state}" for part, state in self.parts.items())
            self.say(  # type: ignore[misc]
                f"brake-sim: compiling the physics kernels: {time.perf_counter() - self.start:.0f}"
                f" s so far, {_cached_functions()} functions in the cache; {states}"
            )

    def stop(self) -> None:
        self.stopped.set()
        if self.thread.is_alive():
            self.thread.join()


def compile_kernels(say: Callable[[str], None] | None = None) -> float:
    """Run every kernel path once on a tiny event, telling ``say`` how far it is every
    :data:`TICK_S` s (None: silent); returns the wall time taken, s.

    On a machine with more than one core the two parts compile at once, the second in a
    child process (numba compiles one function on one core; the cache takes both). Should
    the child fail, its part compiles here after all, where an error shows in full."""
    start = time.perf_counter()
    child = None
    parts = {"fixed-step kernel": "compiling", "reference, regimes and sensors": "waiting"}
    if (os.cpu_count() or 1) > 1:
        child = subprocess.Popen(
            [sys.executable, "-c", _CHILD],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        parts["reference, regimes and sensors"] = "compiling in another process"
    progress = _Progress(say, parts)
    try:
        _compile_stepping()
        parts["fixed-step kernel"] = "done"
        if child is not None:
            child.wait()
        if child is None or child.returncode != 0:
            parts["reference, regimes and sensors"] = "compiling"
            _compile_the_rest()
        parts["reference, regimes and sensors"] = "done"
    finally:
        progress.stop()
        if child is not None and child.poll() is None:
            child.wait()
    return time.perf_counter() - start


def ensure_compiled(say: Callable[[str], None] | None = None) -> None:
    """Compile the kernels unless this source version's are cached, telling ``say``."""
    if is_compiled():
        return
    say = say or (lambda line: print(line, file=sys.stderr, flush=True))
    say(
        "brake-sim: compiling the physics kernels (once per installed version: minutes, a"
        f" line every {TICK_S:.0f} s says how far)"
    )
    took = compile_kernels(say)
    marker = _marker()
    if marker is not None:
        marker.parent.mkdir(parents=True, exist_ok=True)
        marker.write_text(f"compiled in {took:.1f} s\n", encoding="utf-8")
    say(f"brake-sim: kernels compiled in {took:.1f} s")


if __name__ == "__main__":
    ensure_compiled(lambda line: print(line, flush=True))
