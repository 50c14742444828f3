"""A campaign's brake: the built-in campaigns run on the service brake (the study brake's
reference on request), the campaign key ``brake`` sets the base scenario's, strictly."""

from __future__ import annotations

import re

import pytest

from brake_sim_ros.campaigns import CampaignError, builtin_campaigns, load_campaign, parse_campaign
from brake_sim_ros.campaigns.axes import DefectAxis
from brake_sim_ros.model.catalogue import KINDS, LINE
from brake_sim_ros.scenarios import parse_scenario

LINE_KINDS = {k.name for k in KINDS if LINE in k.locations}
SERVICE_ONLY = {k.name for k in KINDS if k.service_only}  # the line's and the adjuster's
# the brake each built-in campaign runs on
BRAKE_OF = {"demo": "service", "reference": "service", "reference_study": "study"}

TINY = """
name = "tiny"
base = "symmetric"
{brake}
seed = 3
units = 3
[outputs]
duration_s = 0.2
sample_rate_hz = 2560.0
[[axes]]
defects = {defects}
severities = [1.0]
"""


def _kinds(campaign) -> set[str]:
    axis = next(a for a in campaign.axes if isinstance(a, DefectAxis))
    return {c.kind for c in axis.choices} - {"healthy"}


def test_every_built_in_campaign_states_its_brake():
    assert set(builtin_campaigns()) == set(BRAKE_OF)


@pytest.mark.parametrize("name", sorted(BRAKE_OF))
def test_a_built_in_campaigns_runs_are_runs_of_its_brake(name):
    """Planned on three of its units (its axes and brake as shipped): every run's scenario
    is a run of the campaign's brake, and the line's kinds are swept where it has a line."""
    text = load_campaign(name).text
    text, count = re.subn(r"(?m)^units = \d+", "units = 3", text)
    assert count == 1
    campaign = parse_campaign(text, name)
    brake = BRAKE_OF[name]
    assert campaign.brake == brake
    runs = campaign.runs()
    for run in runs[::9]:
        params = parse_scenario(run.scenario_text, run.run_id).setup.params
        assert params.brake == brake
        assert (params.service is not None) == (brake == "service")
    ran = {r.columns["defect_kind"] for r in runs}
    assert (ran >= LINE_KINDS) == (brake == "service")
    assert not LINE_KINDS & ran or brake == "service"


def test_the_brake_key_sets_the_runs_brake_and_without_it_the_base_decides(tmp_path):
    defects = '["initial_angle"]'
    for key, brake in (
        ("", "study"),
        ('brake = "study"', "study"),
        ('brake = "service"', "service"),
    ):
        campaign = parse_campaign(TINY.format(brake=key, defects=defects), "t.toml")
        assert campaign.brake == brake
        for run in campaign.runs():
            assert parse_scenario(run.scenario_text).setup.params.brake == brake
    # a base on the service brake: the campaign's "study" is honoured over it
    (tmp_path / "base.toml").write_text('name = "b"\nbrake = "service"\nduration_s = 0.1\n')
    text = TINY.format(brake='brake = "study"', defects=defects)
    (tmp_path / "c.toml").write_text(text.replace('"symmetric"', '"base.toml"'))
    runs = load_campaign(tmp_path / "c.toml").runs()
    assert {parse_scenario(r.scenario_text).setup.params.brake for r in runs} == {"study"}
    # "all" follows the brake: the line's kinds on the service brake only
    study = parse_campaign(TINY.format(brake='brake = "study"', defects='"all"'), "t.toml")
    service = parse_campaign(TINY.format(brake='brake = "service"', defects='"all"'), "t.toml")
    assert not _kinds(study) & SERVICE_ONLY
    assert _kinds(service) == _kinds(study) | SERVICE_ONLY


BAD_BRAKES = [
    ('brake = "disc"', "key 'brake' = 'disc' is invalid: allowed one of ['study', 'service']"),
    ("brake = 1", "key 'brake' = 1 is invalid: allowed a string"),
    ('brake = ["service"]', "key 'brake' = ['service'] is invalid: allowed a string"),
    ('brake = "Service"', "key 'brake' = 'Service'"),
]


@pytest.mark.parametrize(("line", "expected"), BAD_BRAKES)
def test_a_bad_brake_is_refused_in_one_line(line, expected):
    with pytest.raises(CampaignError) as info:
        parse_campaign(TINY.format(brake=line, defects='"all"'), "bad.toml")
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith("bad.toml: ")
    assert expected in message


def test_a_brake_the_campaign_cannot_run_is_refused_in_one_line(tmp_path):
    # the line's kinds on the study brake
    text = TINY.format(brake='brake = "study"', defects='["air_in_line"]')
    with pytest.raises(CampaignError, match=r"^bad\.toml: key 'axes\[0\]\.defects'.*service") as e:
        parse_campaign(text, "bad.toml")
    assert "\n" not in str(e.value)
    # an axis varying the brake beside the campaign's key: one of them would be ignored
    text = TINY.format(brake='brake = "service"', defects='"all"')
    text += '[[axes]]\nkey = "brake"\nvalues = ["study"]\n'
    with pytest.raises(CampaignError, match=r"^bad\.toml: key 'axes\[1\]\.key' = 'brake'"):
        parse_campaign(text, "bad.toml")
    # a base that reads the service brake's parameters, put on the study brake
    (tmp_path / "base.toml").write_text(
        'name = "b"\nbrake = "service"\n[parameters.service]\nresidual_force_n = 25.0\n'
    )
    text = TINY.format(brake='brake = "study"', defects='"all"')
    (tmp_path / "c.toml").write_text(text.replace('"symmetric"', '"base.toml"'))
    with pytest.raises(CampaignError, match=r"parameters\.service") as e:
        load_campaign(tmp_path / "c.toml")
    assert "\n" not in str(e.value) and "c.toml" in str(e.value)
