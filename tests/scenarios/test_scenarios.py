"""Scenario loading is strict: every kind of malformed file gets its specific error."""

from __future__ import annotations

import pytest

from brake_sim_ros.errors import ScenarioError
from brake_sim_ros.scenarios import builtin_names, load_scenario, parse_scenario

GOOD = """
name = "t"
duration_s = 1.0
[actuation]  # a key written after this line belongs to [actuation] until the next table
profile = "ramp"
peak_force_n = 1000.0
"""


def test_every_builtin_loads_and_the_papers_cases_are_there():
    names = builtin_names()
    assert "symmetric" in names
    assert sum(n.startswith("case") for n in names) == 8
    for name in names:
        assert load_scenario(name).name == name
        assert load_scenario(name).sample_rate_hz == 25_600.0  # the default


def test_piecewise_actuation_and_overrides_are_applied():
    s = parse_scenario("""
name = "pw"
[actuation]
profile = "piecewise"
left = { times_s = [0.0, 0.1, 0.5], forces_n = [0.0, 0.0, 800.0] }
right = { times_s = [0.0], forces_n = [300.0] }
[parameters.friction]
coefficient = 0.31
[defects.left]
actuation_share = 0.6
[model]
rigid_coupling = true
shoes = ["left"]
""")
    assert s.setup.actuation.left(0.3) == pytest.approx(400.0)
    assert s.setup.actuation.right(5.0) == pytest.approx(300.0)
    assert s.setup.params.friction.coefficient == 0.31
    assert s.setup.defects.right.actuation_share == pytest.approx(0.4)
    assert s.setup.options.rigid_coupling and s.setup.options.shoes == ("left",)


@pytest.mark.parametrize(
    ("extra", "key", "fragment"),
    [
        ("bogus = 1", "actuation.bogus", "unknown key"),
        (
            "[parameters.friction]\ncoefficent = 0.3",
            "parameters.friction.coefficent",
            "unknown key",
        ),
        (
            '[parameters.friction]\ncoefficient = "high"',
            "parameters.friction.coefficient",
            "a number",
        ),
        ("[parameters.friction]\ncoefficient = nan", "parameters.friction.coefficient", "finite"),
        ("[parameters.shoe]\nmass_kg = inf", "parameters.shoe.mass_kg", "finite"),
        ("[solver]\nmax_step_s = -1e-5", "solver.max_step_s", ">= 1e-08"),
        ("[solver]\nmax_step = 1", "solver.max_step", "unknown key"),
        ("[solver]\ndt_s = 4e-5", "solver.dt_s", "sample_rate_hz"),  # retired
        ("sample_rate_hz = 0", "sample_rate_hz", ">= 1"),
        ('sample_rate_hz = "25.6k"', "sample_rate_hz", "a number"),
        ('[solver]\nmethod = "euler"', "solver.method", "one of"),
        ("seed = -3", "seed", "integer"),
        ("[defects.left]\ninitial_angle_deg = true", "defects.left.initial_angle_deg", "a number"),
    ],
)
def test_malformed_values_name_file_key_value_and_what_is_allowed(extra, key, fragment):
    text = extra + "\n" + GOOD if not extra.startswith(("[", "bogus")) else GOOD + "\n" + extra
    with pytest.raises(ScenarioError) as info:
        parse_scenario(text, "my_case.toml")
    message = str(info.value)
    assert "my_case.toml" in message and f"'{key}'" in message and fragment in message


@pytest.mark.parametrize(
    ("extra", "fragment"),
    [
        ("[parameters.friction]\ncoefficient = 3.0", "coefficient=3.0 is invalid: allowed 0 to 1"),
        ("[parameters.shoe]\npivot_radius_m = 0.5", "pivot_radius_m=0.5 is invalid"),
        ("[defects.left]\ninitial_angle_deg = 2.0", "inside the drum"),
        ("[defects.right]\npivot_radius_change_pct = 18.0", "inside the drum"),
        ("[defects.left]\nactuation_share = 1.5", "actuation_share=1.5 is invalid"),
        (
            "[defects.left]\nactuation_share = 0.6\n[defects.right]\nactuation_share = 0.6",
            "allowed a sum of exactly 1",
        ),
    ],
)
def test_absurd_physics_is_refused_with_the_reason(extra, fragment):
    with pytest.raises(ScenarioError, match=r"my_case\.toml") as info:
        parse_scenario(GOOD + "\n" + extra, "my_case.toml")
    assert fragment in str(info.value)


def test_broken_toml_and_piecewise_mistakes():
    with pytest.raises(ScenarioError, match="not valid TOML"):
        parse_scenario("name = ", "x.toml")
    with pytest.raises(ScenarioError, match="'name'"):
        parse_scenario("duration_s = 1.0", "x.toml")
    with pytest.raises(ScenarioError, match="equal length"):
        parse_scenario(
            'name="x"\n[actuation]\nprofile="piecewise"\n'
            "left={times_s=[0.0,1.0],forces_n=[1.0]}\n"
            "right={times_s=[0.0],forces_n=[1.0]}",
            "x.toml",
        )
    with pytest.raises(ScenarioError, match="strictly increasing"):
        parse_scenario(
            'name="x"\n[actuation]\nprofile="piecewise"\n'
            "left={times_s=[1.0,0.5],forces_n=[1.0,2.0]}\n"
            "right={times_s=[0.0],forces_n=[1.0]}",
            "x.toml",
        )


def test_unknown_scenario_and_unreadable_file(tmp_path):
    with pytest.raises(ScenarioError, match="unknown scenario 'nope'"):
        load_scenario("nope")
    with pytest.raises(ScenarioError, match="cannot read"):
        load_scenario(tmp_path / "missing.toml")


@pytest.mark.parametrize("side", ["left", "right"])
def test_a_shoe_defect_out_of_range_names_the_shoe(side):
    text = f'name = "x"\n[defects.{side}]\npivot_radius_change_pct = 50.0'
    with pytest.raises(ScenarioError, match=rf"\[defects\.{side}\].*pivot_radius_change_pct=50"):
        parse_scenario(text)
