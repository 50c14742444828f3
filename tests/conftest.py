"""Shared fixtures: runs of the built-in scenarios are cached per test session."""

from __future__ import annotations

import functools

import pytest

from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.solvers.run import RunResult, run_scenario


@functools.cache
def cached_run(name: str, method: str = "rk4") -> RunResult:
    return run_scenario(load_scenario(name), method=method)


@pytest.fixture(scope="session")
def symmetric_rk4() -> RunResult:
    return cached_run("symmetric")


@pytest.fixture(scope="session")
def symmetric_reference() -> RunResult:
    return cached_run("symmetric", "reference")
