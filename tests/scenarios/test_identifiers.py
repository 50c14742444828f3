"""One identifier rule (brake_sim_ros/identifiers.py) for a run id, a unit id and a
campaign's name and unit ids: each place accepts and refuses the same values."""

from __future__ import annotations

import pytest

from brake_sim_ros.campaigns.campaign import CampaignError
from brake_sim_ros.campaigns.loader import parse_campaign
from brake_sim_ros.errors import ParameterError, ScenarioError
from brake_sim_ros.identifiers import IDENTIFIER_RULE
from brake_sim_ros.scenarios import parse_scenario
from brake_sim_ros.stream.parameters import check_run_id

GOOD = ("a", "unit-0001", "Brake_7.rear", "_x", "9" * 64)
BAD = (".hidden", "-option", "a/b", "a b", "é", "9" * 65, "")
CAMPAIGN = 'name = "{name}"\nbase = "symmetric"\nunit_ids = ["{unit}", "u2", "u3"]\n'


def _places(value: str):
    yield lambda: check_run_id(value)
    yield lambda: parse_scenario(f'name = "x"\nunit_id = "{value}"\n')
    yield lambda: parse_campaign(CAMPAIGN.format(name=value, unit="u1"), "c.toml")
    yield lambda: parse_campaign(CAMPAIGN.format(name="c", unit=value), "c.toml")


@pytest.mark.parametrize("value", GOOD)
def test_every_place_accepts_an_identifier(value):
    for place in _places(value):
        place()


@pytest.mark.parametrize("value", BAD)
def test_every_place_refuses_what_is_not_one_naming_the_one_rule(value):
    places = list(_places(value))
    if value == "":
        places = places[1:]  # an empty run_id asks for a fresh UUID4 per run
    for place in places:
        with pytest.raises((ParameterError, ScenarioError, CampaignError)) as info:
            place()
        assert IDENTIFIER_RULE in str(info.value)
