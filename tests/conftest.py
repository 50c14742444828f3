"""Shared fixtures: runs of the built-in scenarios are cached per test session (under
pytest-xdist: per worker). And the suite on several cores: tests marked ``realtime`` run
with no other test running beside them."""

from __future__ import annotations

import fcntl
import functools
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.solvers import kernel_parts
from brake_sim_ros.stream.run import RunResult, run_scenario

IMPACTING_S = 0.3  # the impacting regime of the symmetric run ends at 0.29 s

# pytest writes each test module's assertion-rewritten bytecode beside it, and every later
# run reads it; where PYTHONDONTWRITEBYTECODE is set it would write none, and every worker
# of every run would rewrite all the test modules again (4.5 s of CPU a worker). So the
# suite writes them, as the set-up writes the package's and the venv's
# (scripts/compile_bytecode.py): its first run does, its workers in parallel.
sys.dont_write_bytecode = False


@functools.cache
def cached_run(name: str, method: str | None = "rk4") -> RunResult:
    """A run of a built-in scenario; ``method`` None = the scenario's own solver settings."""
    return run_scenario(load_scenario(name), method=method)


@pytest.fixture(scope="session")
def symmetric_run() -> RunResult:
    """The symmetric scenario with its own solver settings (what a user gets)."""
    return cached_run("symmetric", None)


@pytest.fixture(scope="session")
def symmetric_rk4() -> RunResult:
    return cached_run("symmetric")


@pytest.fixture(scope="session")
def symmetric_reference() -> RunResult:
    return cached_run("symmetric", "reference")


@pytest.fixture(scope="session")
def symmetric_impacting(symmetric_run: RunResult) -> SampleBlock:
    """The first :data:`IMPACTING_S` of the symmetric run (every impact of both shoes)."""
    samples = symmetric_run.samples
    n = round(IMPACTING_S / samples.sample_period_s)
    return SampleBlock(
        samples.data[:n], samples.first_index, samples.sample_period_s, samples.columns
    )


# --- the suite on several cores (pytest-xdist, options in pyproject.toml's addopts) -------


def pytest_addoption(parser, pluginmanager):
    """Without pytest-xdist (``-p no:xdist``, or not installed) accept its options that
    addopts passes, and run every test in this process."""
    if pluginmanager.has_plugin("xdist"):
        return
    group = parser.getgroup("xdist", "pytest-xdist not loaded: its options are ignored")
    for name in ("--numprocesses", "--maxprocesses", "--dist"):
        group.addoption(name, dest=f"ignored_{name[2:]}", help="ignored without pytest-xdist")
    group.addoption(
        "--no-loadscope-reorder", action="store_true", help="ignored without pytest-xdist"
    )


# The longest files, longest first (each file's wall time on its worker in one run of the
# suite on 2 cores, 3 workers): each worker takes one at the start and the shorter ones fill
# in behind them, so no long file is left to run alone at the end (longest processing time
# first). Files holding realtime tests are not among the first three, which start beside
# the session's background compile (a realtime test waits for it). Paths from tests/.
LONGEST_FILES = (
    "ros/test_monitor.py",
    "campaigns/test_campaigns.py",
    "datasets/test_sweep_fuzz.py",
    "datasets/test_sweep.py",
    "cli/test_cli.py",
    "fleet/test_units.py",
    "ros/test_recording_node.py",
    "detection/test_saved.py",
    "ros/test_monitor_brake.py",
    "detection/test_impact.py",
    "ros/test_replay.py",
    "project/test_setup_progress.py",
    "ros/test_node_realtime.py",
    "recording/test_recording_fuzz.py",
    "detection/test_evaluate.py",
    "project/test_docs.py",
)
MAX_WORKERS = 4  # the most the suite has run on (each worker has its own ROS domains)


@pytest.hookimpl(optionalhook=True, tryfirst=True)
def pytest_xdist_auto_num_workers(config: pytest.Config) -> int | None:
    """Workers for ``--numprocesses=logical`` (addopts): one per usable CPU and one more,
    at most :data:`MAX_WORKERS`. About a third of a worker's time is spent waiting (DDS
    discovery, nodes paced in real time, subprocesses, Dask clusters starting), which the
    extra worker fills: on 2 cores the suite took 358 s on 2 workers and 280 s on 3 (one
    session, warm kernels; 4 workers, before :data:`LONGEST_FILES` was ordered for 3:
    288 s). ``PYTEST_XDIST_AUTO_NUM_WORKERS`` decides when set."""
    if os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS"):
        return None
    return min(len(os.sched_getaffinity(0)) + 1, MAX_WORKERS)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The :data:`LONGEST_FILES` first, then the other files that hold a ``slow`` test,
    then the rest; each file's tests in their order.

    loadfile hands out whole files in collection order (``--no-loadscope-reorder``; by
    default it would sort them by their number of tests, which puts a long file of few
    tests last, alone on one worker while the other idles): the long files start at once
    and the many short ones fill in around them."""
    here = Path(__file__).parent
    gone = [name for name in LONGEST_FILES if not (here / name).is_file()]
    if gone:  # a file moved or renamed: its rank would be lost without a word
        raise pytest.UsageError(f"tests/conftest.py LONGEST_FILES names no file: {gone}")
    rank = {here / name: i for i, name in enumerate(LONGEST_FILES)}
    slow = {item.path for item in items if item.get_closest_marker("slow")}

    def order(item: pytest.Item) -> tuple[int, int]:
        if item.path in rank:
            return (0, rank[item.path])
        return (1 if item.path in slow else 2, 0)

    items.sort(key=order)  # stable: the order within a file and among the rest


def pytest_sessionstart(session: pytest.Session) -> None:
    """In the controller (or the one process): start compiling the kernels' parts that
    compile at first use (solvers/warmup.py; a no-op when this source version's are cached)
    in the background, so that they compile beside the first tests, in parallel, instead of
    inside the first test that needs one while the other workers wait for it. A test that
    needs a part meanwhile waits on the kernel cache's lock, as at any first use. Not for
    ``--collect-only`` (the set-up's bytecode step collects; no test needs a kernel)."""
    if os.environ.get("PYTEST_XDIST_WORKER") or session.config.option.collectonly:
        return
    from brake_sim_ros.solvers.warmup import PARTS, is_compiled

    if is_compiled(PARTS):
        return
    session.config.stash[_WARMUP] = subprocess.Popen(
        [sys.executable, "-m", "brake_sim_ros.solvers.warmup", "--all"],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,  # its own group: its compile child goes with it
    )


def pytest_sessionfinish(session: pytest.Session) -> None:
    """Stop the background compile should the session end before it (``-x``, Ctrl-C)."""
    proc = session.config.stash.get(_WARMUP, None)
    if proc is not None and proc.poll() is None:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()


_WARMUP = pytest.StashKey[subprocess.Popen]()


def pytest_configure(config):
    basetemp = config.option.basetemp
    if os.environ.get("PYTEST_XDIST_WORKER") and basetemp:  # gwN/, one per worker, side by side
        config.pluginmanager.register(RealtimeAlone(Path(basetemp).parent), "realtime-alone")


def _exclusive(item: pytest.Item) -> bool:
    return item.get_closest_marker("realtime") is not None


class RealtimeAlone:
    """In an xdist worker: each test holds a lock on a file the workers share, from the
    set-up of its fixtures to their teardown. A ``realtime`` test holds it exclusively
    (and keeps it over consecutive ``realtime`` tests, whose module fixtures may run a
    node in real time between them); every other test holds it shared. A realtime test
    waiting for the lock holds a gate that new shared holders must pass first, so it
    waits only for the test running on the other worker(s), never longer."""

    def __init__(self, folder: Path) -> None:
        self._gate = (folder / "realtime.gate").open("a")
        self._lock = (folder / "realtime.lock").open("a")
        self._exclusive: bool | None = None  # None: not held

    def _acquire(self, exclusive: bool) -> None:
        if exclusive:  # nor beside the session's background compile (pytest_sessionstart)
            with kernel_parts.turn():
                pass
        fcntl.flock(self._gate, fcntl.LOCK_EX)
        try:
            fcntl.flock(self._lock, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
        finally:
            fcntl.flock(self._gate, fcntl.LOCK_UN)
        self._exclusive = exclusive

    def _release(self) -> None:
        fcntl.flock(self._lock, fcntl.LOCK_UN)
        self._exclusive = None

    @pytest.hookimpl(wrapper=True)
    def pytest_runtest_protocol(self, item: pytest.Item, nextitem: pytest.Item | None):
        exclusive = _exclusive(item)
        if self._exclusive is not None and self._exclusive != exclusive:
            self._release()
        if self._exclusive is None:
            self._acquire(exclusive)
        try:
            return (yield)
        finally:
            if not (exclusive and nextitem is not None and _exclusive(nextitem)):
                self._release()
