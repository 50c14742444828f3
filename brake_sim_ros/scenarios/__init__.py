"""Scenarios as data: the paper's cases and user files, loaded strictly."""

from brake_sim_ros.scenarios.loader import (
    builtin_names,
    load_scenario,
    parse_scenario,
    read_scenario_file,
)
from brake_sim_ros.scenarios.types import Scenario, SolverSettings

__all__ = [
    "Scenario",
    "SolverSettings",
    "builtin_names",
    "load_scenario",
    "parse_scenario",
    "read_scenario_file",
]
