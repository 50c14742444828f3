"""The built-in drive cycles on the study brake, as they ran before they moved to the service
brake (issue 28): the same files with ``brake = "study"``. For the tests (and the lines of
``scripts/hash_outputs.py``) whose point is a figure of the study brake."""

from __future__ import annotations

from brake_sim_ros.scenarios import Scenario, load_scenario, on_brake


def on_study_brake(name: str) -> Scenario:
    """The built-in drive cycle ``name`` on the study brake (``bench cycle --brake study``'s
    rewrite).

    Raises:
        AssertionError: ``name`` does not ship on the service brake (the copy would be the
            file itself, not a study-brake run of it).
    """
    scenario = load_scenario(name)
    if scenario.setup.params.brake != "service":
        raise AssertionError(f"built-in {name}: expected it on the service brake")
    return on_brake(scenario, "study")


def study_text(name: str) -> str:
    """The text of :func:`on_study_brake` (a scenario's text, more tables may follow)."""
    return on_study_brake(name).text
