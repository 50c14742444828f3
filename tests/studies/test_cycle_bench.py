"""``brake-sim bench cycle --brake``: the cycle scenario on the brake named (the parsing
only; the benchmark's figures are docs/benchmarks.md's)."""

from __future__ import annotations

import pytest

from brake_sim_ros.errors import ScenarioError
from brake_sim_ros.scenarios import load_scenario, on_brake, parse_scenario
from brake_sim_ros.studies.cycle_bench import main


def test_on_brake_sets_the_brake_and_keeps_the_rest():
    urban = load_scenario("urban")
    assert urban.setup.params.brake == "service"  # the drive cycles run the service brake
    study = on_brake(urban, "study")
    assert study.setup.params.brake == "study" and study.setup.params.service is None
    assert study.setup.cycle == urban.setup.cycle
    assert (study.name, study.duration_s, study.seed) == (urban.name, 50.0, 0)
    assert study.sensors == urban.sensors
    assert on_brake(urban, "service") is urban  # on its brake already: itself
    back = on_brake(study, "service")  # its brake line rewritten again
    assert back.setup.params.brake == "service" and back.setup.cycle == urban.setup.cycle
    plain = parse_scenario('name = "s"\nduration_s = 1.0\n', "s.toml")  # no brake key: added
    assert on_brake(plain, "service").setup.params.brake == "service"


def test_on_brake_sets_a_brake_key_in_any_form_and_refuses_a_scenario_that_cannot_hold():
    text = 'name = "s"\nbrake = "service"  \t# a comment\nduration_s = 1.0\n'
    assert on_brake(parse_scenario(text, "s.toml"), "study").setup.params.brake == "study"
    inline = 'name = "s"\nduration_s = 1.0\nbrake=   """service"""\n'
    assert on_brake(parse_scenario(inline, "s.toml"), "study").setup.params.brake == "study"
    # the service brake's own tables do not hold on the study brake: one line, as the loader
    service = 'name = "s"\nbrake = "service"\n[parameters.service]\nresidual_force_n = 10.0\n'
    with pytest.raises(ScenarioError) as exc:
        on_brake(parse_scenario(service, "s.toml"), "study")
    assert "\n" not in str(exc.value) and "s.toml" in str(exc.value)


def test_an_unknown_brake_is_refused_in_one_line(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--brake", "disc"])
    assert exc.value.code == 2
    assert "invalid choice: 'disc'" in capsys.readouterr().err
