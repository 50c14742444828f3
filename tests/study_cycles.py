"""The built-in drive cycles on the study brake, as they ran before they moved to the service
brake (issue 28): the same files with ``brake = "study"``. For the tests (and the lines of
``scripts/hash_outputs.py``) whose point is a figure of the study brake."""

from __future__ import annotations

from importlib import resources

from brake_sim_ros.scenarios import Scenario, parse_scenario
from brake_sim_ros.scenarios.loader import BUILTIN_PACKAGE

SERVICE_LINE = 'brake = "service"'


def study_text(name: str) -> str:
    """The built-in scenario ``name``'s text with its brake line set to the study brake.

    Raises:
        AssertionError: the file has not exactly one ``brake = "service"`` line (the copy
            would silently be another scenario).
    """
    text = resources.files(BUILTIN_PACKAGE).joinpath(f"{name}.toml").read_text(encoding="utf-8")
    if text.count(SERVICE_LINE) != 1:
        raise AssertionError(f"built-in {name}: expected one {SERVICE_LINE!r} line")
    return text.replace(SERVICE_LINE, 'brake = "study"')


def on_study_brake(name: str) -> Scenario:
    """The built-in drive cycle ``name`` on the study brake (:func:`study_text`)."""
    return parse_scenario(study_text(name), f"<built-in {name}, study brake>")
