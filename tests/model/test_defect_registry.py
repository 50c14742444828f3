"""A defect kind registered in a test reaches the scenario loader, the node's parameters,
a campaign's defect axis, the labels and ``brake-sim defects`` with no edit elsewhere; an
entry that lacks a part is refused, naming it; the rules a kind carries (growth, tied
shoes, shaped actuation) are read from its entry."""

from __future__ import annotations

import dataclasses

import pytest

from brake_sim_ros.errors import ParameterError, ScenarioError
from brake_sim_ros.model import catalogue
from brake_sim_ros.model.catalogue import ALL_LEVELS, DefectField, DefectKind
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.kind_check import missing_parts, register, registered
from brake_sim_ros.model.packing import pack_nothing
from brake_sim_ros.scenarios import parse_scenario
from tests.defect_reach import reaches_everything

# a kind the product does not have: a glazed lining, with an attribute (what share of
# the lining's arc is glazed); no physics of its own (the test is about its reach)
GLAZING = DefectKind(
    name="lining_glazing",
    locations=("left", "right"),
    unit="%",
    minimum=0.0,
    maximum=100.0,
    limit="a lining is at most all glazed",
    description="share of the lining's surface glazed by heat, in %",
    scenario_key="lining_glazing_pct",
    service_limit=40.0,
    levels=ALL_LEVELS,
    growth_id=None,
    packing=pack_nothing,
    attributes=(
        DefectField(
            "lining_glazing_arc_deg",
            "deg",
            0.0,
            0.0,
            120.0,
            "the arc of the lining the glazing covers, deg",
            attribute="arc_deg",
            present_default=30.0,
        ),
    ),
)
# a drum kind, to reach the drum's table and parameters
SCORING = DefectKind(
    name="drum_scoring",
    locations=("drum",),
    unit="um",
    minimum=0.0,
    maximum=500.0,
    limit="deeper grooves are a drum to replace",
    description="depth of circumferential grooves worn into the drum, in um",
    scenario_key="scoring_depth_um",
    service_limit=200.0,
    levels=frozenset({"rigid", "full"}),
    growth_id=None,
    packing=pack_nothing,
)


@pytest.mark.parametrize("kind", [GLAZING, SCORING], ids=lambda k: k.name)
def test_a_kind_registered_in_a_test_reaches_every_consumer(kind):
    with registered(kind):
        reaches_everything(kind)
        assert missing_parts(kind) == []
    assert kind.name not in catalogue.KIND_BY_NAME
    assert kind not in catalogue.KINDS


def test_a_registered_kind_is_ground_truth_with_its_attribute():
    with registered(GLAZING):
        defects = Defects.single("lining_glazing", "right", 25.0)
        (active,) = defects.active()
        assert (active.kind, active.location, active.severity) == ("lining_glazing", "right", 25.0)
        assert dict(active.attributes) == {"arc_deg": 30.0}
        with pytest.raises(ScenarioError, match="lining_glazing_pct=101 is invalid: allowed 0"):
            parse_scenario('name = "x"\n[defects.left]\nlining_glazing_pct = 101.0\n')
        with pytest.raises(ScenarioError, match="lining_glazing_arc_deg=150 is invalid"):
            parse_scenario('name = "x"\n[defects.left]\nlining_glazing_arc_deg = 150.0\n')
    # gone again: the key is refused as unknown
    with pytest.raises(ScenarioError, match="lining_glazing_pct"):
        parse_scenario('name = "x"\n[defects.left]\nlining_glazing_pct = 10.0\n')


@pytest.mark.parametrize(
    ("change", "part"),
    [
        ({"levels": frozenset()}, "fidelity levels"),
        ({"levels": frozenset({"exact"})}, "fidelity levels"),
        ({"description": ""}, "a description"),
        ({"limit": ""}, "a limit"),
        ({"service_limit": 0.0}, "a service_limit"),
        ({"service_limit": 150.0}, "a service_limit"),
        ({"minimum": 10.0}, "minimum <= 0 <= maximum"),
        ({"locations": ("left",)}, "locations"),
        ({"growth_id": 99}, "a growth_id"),
        ({"laws": ("linear",)}, "growth laws"),
        ({"laws": ("step", "friction_work")}, "'friction_work' only with"),
        ({"actuation": "squeal"}, "an actuation effect"),
        ({"packing": None}, "a packing"),
        ({"table": True}, "one table"),
        ({"scenario_key": "Glazing Pct"}, "a scenario key"),
        (
            {"attributes": (dataclasses.replace(GLAZING.attributes[0], attribute=""),)},
            "its attribute's name",
        ),
        (
            {"attributes": (dataclasses.replace(GLAZING.attributes[0], default=200.0),)},
            "low <= default <= high",
        ),
        (
            {"attributes": (dataclasses.replace(GLAZING.attributes[0], unit=""),)},
            "a unit and a description",
        ),
    ],
)
def test_an_entry_that_lacks_a_part_is_refused_naming_it(change, part):
    lacking = dataclasses.replace(GLAZING, **change)
    assert any(part in m for m in missing_parts(lacking)), missing_parts(lacking)
    with pytest.raises(ParameterError, match="lacks: .*" + part.replace("(", r"\(")):
        register(lacking)
    assert lacking.name not in catalogue.KIND_BY_NAME


def test_a_name_or_key_taken_by_another_kind_is_refused():
    for clash in (
        dataclasses.replace(GLAZING, name="lining_wear"),
        dataclasses.replace(GLAZING, scenario_key="lining_wear_mm"),
        dataclasses.replace(GLAZING, attributes=(catalogue.KIND_BY_NAME["drum_flat"].attributes)),
    ):
        with pytest.raises(ParameterError, match=r"registered already|taken by another kind"):
            register(clash)
    assert "lining_glazing" not in catalogue.KIND_BY_NAME


def test_the_shaped_actuation_rule_is_the_entries():
    """A kind with an actuation effect shapes the force: the kernel's shaped path, refused
    with a drive cycle; ``history`` kinds alone reshape the commanded history."""
    history = {k.name for k in catalogue.KINDS if k.actuation == "history"}
    release = {k.name for k in catalogue.KINDS if k.actuation == "release"}
    assert history == {"actuation_delay", "actuation_lag", "actuation_pulsation"}
    assert release == {"return_spring_weakening"}
    for name in history | release:
        shoe = ShoeDefect.from_severities({name: 0.5 * catalogue.KIND_BY_NAME[name].service_limit})
        assert shoe.force_shaped
        assert shoe.actuation_shaped == (name in history)
    assert not ShoeDefect(friction_change_pct=-20.0).force_shaped


def test_growth_rules_are_the_entries():
    """A kind without a growth id, or an initial condition, takes only a step at 0 s; a
    law a kind does not take is refused naming the keys that take it."""
    text = 'name = "x"\n[defects.left]\n{} = {{value = {}, growth = "{}", {}}}\n'
    with pytest.raises(ScenarioError, match="allowed only for lining_wear_mm"):
        parse_scenario(text.format("friction_change_pct", -20.0, "friction_work", "onset_s = 1.0"))
    with pytest.raises(ScenarioError, match="an initial condition of the run"):
        parse_scenario(text.format("initial_angle_deg", -2.0, "linear", "rate_per_s = 1.0"))
    with pytest.raises(ScenarioError, match='a value only with growth = "exponential"'):
        parse_scenario(
            text.format("friction_change_pct", -20.0, "linear", "rate_per_s = 5.0, start = -1.0")
        )
