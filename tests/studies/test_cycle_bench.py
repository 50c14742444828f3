"""``brake-sim bench cycle --brake``: the cycle scenario on the brake named (the parsing
only; the benchmark's figures are docs/benchmarks.md's)."""

from __future__ import annotations

import pytest

from brake_sim_ros.errors import ScenarioError
from brake_sim_ros.scenarios import load_scenario, parse_scenario
from brake_sim_ros.studies.cycle_bench import main, on_brake


def test_on_brake_sets_the_brake_and_keeps_the_rest():
    urban = load_scenario("urban")
    assert urban.setup.params.brake == "study"
    service = on_brake(urban, "service")
    assert service.setup.params.brake == "service" and service.setup.params.service is not None
    assert service.setup.cycle == urban.setup.cycle
    assert (service.name, service.duration_s, service.seed) == (urban.name, 50.0, 0)
    assert service.sensors == urban.sensors
    assert on_brake(urban, "study") is urban  # on its brake already: itself


def test_on_brake_refuses_a_scenario_that_names_another_brake():
    text = 'name = "s"\nbrake = "service"\nduration_s = 1.0\n'
    with pytest.raises(ScenarioError, match=r"brake = 'service': allowed --brake only for"):
        on_brake(parse_scenario(text, "s.toml"), "study")


def test_an_unknown_brake_is_refused_in_one_line(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--brake", "disc"])
    assert exc.value.code == 2
    assert "invalid choice: 'disc'" in capsys.readouterr().err
