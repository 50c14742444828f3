"""Campaign files whose held-out rules would hold nothing out, and a directory named like
a built-in campaign: refused in one line naming the key, or (the name) read as the
built-in. Pure logic: campaigns are loaded and planned, nothing is simulated."""

from __future__ import annotations

import pytest

from brake_sim_ros.campaigns import load_campaign
from brake_sim_ros.campaigns.campaign import CampaignError
from brake_sim_ros.campaigns.loader import builtin_campaigns

BASE = """
name = "held"
base = "symmetric"
units = 10
[[axes]]
name = "peak_force_n"
key = "actuation.peak_force_n"
values = [1200.0, 1300.0]
[[axes]]
defects = ["pivot_radius_change"]
severities = [0.5]
healthy = true
[split]
train = 0.6
validation = 0.2
test = 0.2
"""


@pytest.mark.parametrize(
    ("rule", "says"),
    [
        ('{column = "peak_force_n", values = ["1200"]}', "values[0]"),
        ('{column = "peak_force_n", values = [true]}', "values[0]"),
        ('{column = "peak_force_n", min = 1400.0, max = 1100.0}', "a maximum >= the minimum"),
        ('{column = "defect_kind", values = [3]}', "values[0]"),
        ('{column = "defect_kind", min = 0.0, max = 1.0}', "no numbers"),
        ('{column = "defect_location", values = [1.5]}', "values[0]"),
    ],
)
def test_held_out_rules_that_hold_nothing_out_are_refused(tmp_path, rule, says):
    path = tmp_path / "c.toml"
    path.write_text(BASE + f"held_out = [{rule}]\n")
    with pytest.raises(CampaignError) as info:
        load_campaign(path)
    message = str(info.value)
    assert "\n" not in message and says in message and "split.held_out[0]" in message


def test_held_out_rules_that_hold_every_condition_out_are_refused(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text(BASE + 'held_out = [{column = "peak_force_n", min = 0.0, max = 1e6}]\n')
    with pytest.raises(CampaignError) as info:
        load_campaign(path)
    message = str(info.value)
    assert "\n" not in message and "holds out every condition" in message


def test_an_empty_column_list_is_refused_not_read_as_every_column(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text(BASE.replace("[split]", "[outputs]\ncolumns = []\n[split]"))
    with pytest.raises(CampaignError) as info:
        load_campaign(path)
    assert "outputs.columns" in str(info.value) and "1 or more" in str(info.value)


@pytest.mark.parametrize(
    "rule",
    [
        '{column = "peak_force_n", values = [1300.0]}',
        '{column = "peak_force_n", min = 1250.0, max = 1350.0}',
        '{column = "peak_force_n", min = 1300.0, max = 1300.0}',
        '{column = "defect_kind", values = ["pivot_radius_change"]}',
    ],
)
def test_held_out_rules_of_the_right_kind_hold_their_runs_out(tmp_path, rule):
    path = tmp_path / "c.toml"
    path.write_text(BASE + f"held_out = [{rule}]\n")
    campaign = load_campaign(path)
    runs = campaign.runs()
    held = [r for r in runs if campaign.held_out[0].matches(r.columns)]
    assert held and all(r.split == "test" for r in held)


@pytest.mark.parametrize("name", builtin_campaigns())
def test_a_directory_named_like_a_built_in_does_not_shadow_it(tmp_path, monkeypatch, name):
    monkeypatch.chdir(tmp_path)
    (tmp_path / name).mkdir()
    assert load_campaign(name).source == f"<built-in campaign {name}>"
    with pytest.raises(CampaignError):  # the directory, named as a path, is refused
        load_campaign(f"./{name}")
