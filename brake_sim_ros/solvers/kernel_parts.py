"""Compiling the physics kernels in parts, once per source version, saying how far it is.

numba compiles a kernel on its first call and keeps the machine code in the on-disk cache
(see :mod:`brake_sim_ros.model`). A first call otherwise sits silent for tens of seconds.
The kernels come in parts (:data:`PARTS`, each registered by the module whose kernels it
runs), each compiled by running a tiny event through it when the cache has no record of it
(a marker file per part), printing one line before, one every :data:`TICK_S` seconds while
it compiles (the time so far, the parts done of those asked, the functions in the cache so
far, each part's state) and one after: a fixed estimate of the time would not hold on a
loaded machine. Processes that need a part at the same time (test or sweep workers) take
turns on a lock file: one compiles, the others then load it from the cache.

Which parts compile when: :mod:`brake_sim_ros.solvers.warmup`.
"""

from __future__ import annotations

import fcntl
import os
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numba

import brake_sim_ros.model  # noqa: F401 - its import points numba's cache (CACHE_DIR)

_MARKER = "brake_sim_compiled"
TICK_S = 10.0  # s between two progress lines while the kernels compile
# the child process's command (importing warmup registers every part); its parts are its
# arguments
_CHILD = (
    "import sys; import brake_sim_ros.solvers.warmup;"
    " from brake_sim_ros.solvers.kernel_parts import compile_parts; compile_parts(sys.argv[1:])"
)
DEFAULT_PARTS = ("stepping", "sensors")  # what the default paths run: compiled at set-up
# key -> (what the progress lines call it, what compiles it: a tiny event through it);
# each part's module registers it (register)
PARTS: dict[str, tuple[str, Callable[[], None]]] = {}


def register(key: str, name: str, compile_part: Callable[[], None]) -> None:
    """Make ``key`` a part, called ``name`` in the progress lines, compiled by
    ``compile_part`` (a tiny event through its kernels, a few ms once compiled)."""
    PARTS[key] = (name, compile_part)


_compiling: set[str] = set()  # parts this process compiles now (their drivers run inside)
# (cache directory, part) this process has seen compiled: no second look at the disk
_known: set[tuple[str | None, str]] = set()


def _marker(part: str) -> Path | None:
    cache = numba.config.CACHE_DIR
    return Path(cache) / f"{_MARKER}.{part}" if cache else None


def is_compiled(parts: Iterable[str] = DEFAULT_PARTS) -> bool:
    """Whether the kernels of ``parts`` (of this source version) are in the cache already."""
    for part in parts:
        marker = _marker(part)
        if (numba.config.CACHE_DIR, part) in _known:
            continue
        if marker is None or not marker.exists():
            return False
    return True


def compile_parts(parts: Iterable[str]) -> None:
    """Run the tiny event of each of ``parts`` here (their drivers' own checks stand aside)."""
    parts = list(parts)
    _compiling.update(parts)
    try:
        for part in parts:
            PARTS[part][1]()
    finally:
        _compiling.difference_update(parts)


def _cached_functions() -> int:
    """How many compiled functions the kernel cache holds (numba's index files)."""
    cache = numba.config.CACHE_DIR
    return sum(1 for _ in Path(cache).rglob("*.nbi")) if cache else 0


class _Progress:
    """A line to ``say`` every :data:`TICK_S` s from a daemon thread until stopped: the
    time so far, the parts done, the functions cached so far and each part's state."""

    def __init__(
        self,
        say: Callable[[str], None] | None,
        parts: dict[str, str],
        refresh: Callable[[], None] = lambda: None,
    ) -> None:
        self.say, self.parts, self.refresh = say, parts, refresh
        self.start = time.perf_counter()
        self.stopped = threading.Event()
        self.thread = threading.Thread(target=self._tick, daemon=True)
        if say is not None:
            self.thread.start()

    def _tick(self) -> None:
        while not self.stopped.wait(TICK_S):
            self.refresh()
            states = ", ".join(f"{part}: {state}" for part, state in self.parts.items())
            done = sum(state == "done" for state in self.parts.values())
            self.say(  # type: ignore[misc]
                f"brake-sim: compiling the physics kernels: {time.perf_counter() - self.start:.0f}"
                f" s so far, {done} of {len(self.parts)} parts done, {_cached_functions()}"
                f" functions in the cache; {states}"
            )

    def stop(self) -> None:
        self.stopped.set()
        if self.thread.is_alive():
            self.thread.join()


def compile_kernels(
    say: Callable[[str], None] | None = None, parts: Iterable[str] = DEFAULT_PARTS
) -> float:
    """Run each of ``parts`` once on a tiny event, telling ``say`` how far it is every
    :data:`TICK_S` s (None: silent); returns the wall time taken, s.

    On a machine with more than one core and more than one part, the first part compiles
    here and the others at once in a child process (numba compiles one function on one
    core; the cache takes both). Should the child fail, its parts compile here after all,
    where an error shows in full."""
    start = time.perf_counter()
    keys = list(parts)
    first, others = keys[:1], keys[1:]
    states = {PARTS[key][0]: "waiting" for key in keys}
    child = None
    if others and (os.cpu_count() or 1) > 1:
        child = subprocess.Popen(
            [sys.executable, "-c", _CHILD, *others],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        for key in others:
            states[PARTS[key][0]] = "compiling in another process"

    def refresh() -> None:  # the child's parts are done as soon as it ended well
        if child is not None and child.poll() == 0:
            states.update({PARTS[key][0]: "done" for key in others})

    progress = _Progress(say, states, refresh)
    try:
        for key in first:
            states[PARTS[key][0]] = "compiling"
            compile_parts([key])
            states[PARTS[key][0]] = "done"
        if child is not None:
            child.wait()
        if child is None or child.returncode != 0:
            for key in others:
                states[PARTS[key][0]] = "compiling"
                compile_parts([key])
                states[PARTS[key][0]] = "done"
        for key in others:
            states[PARTS[key][0]] = "done"
    finally:
        progress.stop()
        if child is not None and child.poll() is None:
            child.kill()
            child.wait()
    return time.perf_counter() - start


@contextmanager
def turn() -> Iterator[None]:
    """Hold the kernel cache's lock file: one process compiles at a time, the others wait
    and then find the parts in the cache; what must not run beside a compile (a test of
    wall-clock behaviour) waits for it to end. No lock without a cache directory one may
    write to: numba then compiles without caching, as it does without this module."""
    cache = numba.config.CACHE_DIR
    if not cache:  # numba's own places beside the sources: none of ours to lock
        yield
        return
    try:
        Path(cache).mkdir(parents=True, exist_ok=True)
        lock = open(Path(cache) / f"{_MARKER}.lock", "w")  # noqa: SIM115 - closed below
    except (OSError, TypeError):
        yield
        return
    with lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def ensure_compiled(
    say: Callable[[str], None] | None = None, parts: Iterable[str] = DEFAULT_PARTS
) -> None:
    """Compile the kernels of ``parts`` unless this source version's are cached, telling
    ``say`` (default: stderr) how far it is; a part this process compiles now is taken as
    done (its driver runs inside its compile)."""
    wanted = [part for part in parts if part not in _compiling]
    if is_compiled(wanted):
        return
    say = say or (lambda line: print(line, file=sys.stderr, flush=True))
    with turn():
        missing = [part for part in wanted if not is_compiled([part])]
        if missing:
            _compile_announced(say, missing)
    _known.update((numba.config.CACHE_DIR, part) for part in wanted)


def _compile_announced(say: Callable[[str], None], parts: list[str]) -> None:
    """Compile ``parts`` with a line before, the progress lines and a line after; then
    mark each done."""
    names = ", ".join(PARTS[part][0] for part in parts)
    say(
        f"brake-sim: compiling the physics kernels ({names}; once per installed version:"
        f" a line every {TICK_S:.0f} s says how far)"
    )
    took = compile_kernels(say, parts)
    for part in parts:
        marker = _marker(part)
        if marker is not None:
            try:
                marker.parent.mkdir(parents=True, exist_ok=True)
                marker.write_text(f"compiled in {took:.1f} s\n", encoding="utf-8")
            except OSError:  # a cache one may not write to: compiled again next time
                pass
    say(f"brake-sim: kernels compiled in {took:.1f} s ({names})")
