"""Shared fixtures: runs of the built-in scenarios are cached per test session."""

from __future__ import annotations

import functools

import pytest

from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.solvers.run import RunResult, run_scenario


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
