"""Shared fixtures: runs of the built-in scenarios are cached per test session."""

from __future__ import annotations

import functools

import pytest

from brake_sim_ros.model.trajectory import SampleBlock
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.stream.run import RunResult, run_scenario

IMPACTING_S = 0.3  # the impacting regime of the symmetric run ends at 0.27 s


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
