"""Scenarios as data: the paper's cases and user files, loaded strictly.

The loader's names are imported on first use (PEP 562): the loader imports the numerics,
and a reader of this package's light modules (the defect catalogue's help,
:mod:`.defect_help`, for ``brake-sim defects``) does not pay for them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from brake_sim_ros.scenarios.loader import (
        builtin_names,
        load_scenario,
        on_brake,
        parse_scenario,
        read_scenario_file,
    )
    from brake_sim_ros.scenarios.types import Scenario, SolverSettings

__all__ = [
    "Scenario",
    "SolverSettings",
    "builtin_names",
    "load_scenario",
    "on_brake",
    "parse_scenario",
    "read_scenario_file",
]


def __getattr__(name: str) -> Any:
    if name in __all__:
        from brake_sim_ros.scenarios import loader, types

        return getattr(types, name) if hasattr(types, name) else getattr(loader, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
