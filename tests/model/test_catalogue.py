"""The defect catalogue: one table of kinds that the defects, the node's parameters, the
ground truth and the CLI all read."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from brake_sim_ros.cli import main
from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model import catalogue
from brake_sim_ros.model.assembly import initial_state, pack
from brake_sim_ros.model.defects import (
    DEFAULT_PULSATION_HZ,
    MAX_PULSATION_HZ,
    Defects,
    ShoeDefect,
)
from brake_sim_ros.model.kind_check import missing_parts
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.scenarios.defect_help import catalogue_text
from brake_sim_ros.stream.parameters import _RANGES as RANGES
from tests.defect_reach import brake_of, reaches_everything


@pytest.mark.parametrize("kind", list(catalogue.KINDS), ids=lambda k: k.name)
def test_every_entry_is_complete_and_reaches_every_consumer(kind):
    """The completeness test: each entry carries every part (kind_check.missing_parts)
    and reaches the loader, the node's parameters, a campaign axis, the labels and the
    CLI help from its entry alone."""
    assert missing_parts(kind) == []
    reaches_everything(kind)


@pytest.mark.parametrize("kind", list(catalogue.KINDS), ids=lambda k: k.name)
def test_every_built_in_kind_packs_its_severity(kind):
    """A brake that carries the kind packs differently from the healthy brake (an initial
    condition: it starts from another state), at each of its locations."""
    params = BrakeParameters.of_brake(brake_of(kind))
    healthy = pack(params, Defects())
    for location in kind.locations:
        defects = Defects.single(kind.name, location, 0.5 * kind.service_limit)
        if kind.initial_condition:
            changed = initial_state(params, defects) != initial_state(params, Defects())
        else:
            changed = pack(params, defects) != healthy
        assert changed.any(), f"{kind.name} at {location} reaches neither the packed vector nor y0"


def test_the_drum_flat_is_one_entry_its_fields_written_there_once():
    flat = catalogue.KIND_BY_NAME[catalogue.FLAT_KIND]
    assert [f.name for f in flat.fields()] == ["flat_depth_um", "flat_centre_deg", "flat_width_deg"]
    assert [f.name for f in catalogue.fields_at("drum")] == [f.name for f in flat.fields()]
    assert not any(name.startswith("defects.harmonics") for name in RANGES)
    columns = catalogue.label_columns()
    assert len(set(columns)) == len(columns) == sum(len(k.locations) for k in catalogue.KINDS)


SHOE_KINDS = tuple(k for k in catalogue.KINDS if k.on_shoes)
# the one field of a shoe that is no kind's severity: a pulsation's frequency
FREQUENCY = "actuation_pulsation_hz"


@st.composite
def shoes(draw) -> ShoeDefect:
    """A shoe with every kind a shoe can carry absent or at any severity the catalogue
    accepts, and a pulsation frequency (> 0 with a pulsation)."""
    fields = {
        k.scenario_key: k.healthy_value
        + draw(st.one_of(st.just(0.0), st.floats(k.minimum, k.maximum)))
        for k in SHOE_KINDS
    }
    pulsating = fields["actuation_pulsation_pct"] != 0.0
    fields[FREQUENCY] = draw(st.floats(0.0, MAX_PULSATION_HZ, exclude_min=pulsating))
    return ShoeDefect(**fields)


def test_the_shoes_drawn_set_every_field_of_a_shoe():
    """The strategy below draws every field: a new field of a shoe (a kind's key or an
    attribute, from the catalogue) fails here until the strategy draws it too."""
    keys = {k.scenario_key for k in SHOE_KINDS}
    assert len(keys) == len(SHOE_KINDS) == 11
    assert set(ShoeDefect().values()) == keys | {FREQUENCY}


@given(shoes())
def test_severities_and_back_give_the_same_shoe(shoe):
    assert set(shoe.severities()) == {k.name for k in SHOE_KINDS}
    back = ShoeDefect.from_severities(shoe.severities())
    for kind in SHOE_KINDS:
        key = kind.scenario_key
        if key == "actuation_share":  # stored as share - 0.5, then 0.5 added back
            assert back.actuation_share == pytest.approx(shoe.actuation_share, abs=1e-15)
        else:
            assert getattr(back, key) == getattr(shoe, key), key
    # the frequency is no severity: the inverse gives a pulsation the default one
    pulsating = shoe.actuation_pulsation_pct != 0.0
    assert getattr(back, FREQUENCY) == (DEFAULT_PULSATION_HZ if pulsating else 0.0)


@given(shoes())
def test_the_ground_truth_lists_exactly_the_non_zero_severities(shoe):
    other = ShoeDefect(actuation_share=1.0 - shoe.actuation_share)
    defects = Defects(left=shoe, right=other)
    active = defects.active()
    columns = defects.severities()
    assert {catalogue.label_column(catalogue.KIND_BY_NAME[d.kind], d.location) for d in active} == {
        name for name, value in columns.items() if value != 0.0
    }
    assert all(d.severity != 0.0 and d.onset_s == 0.0 and d.growth == "step" for d in active)
    assert (len(active) == 0) == defects.is_healthy


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            {"pivot_radius_change_pct": 20.5},
            "pivot_radius_change_pct=20.5 is invalid: allowed -20 to 20",
        ),
        ({"initial_angle_deg": -10.5}, "initial_angle_deg=-10.5 is invalid: allowed -10 to 10"),
        (
            {"actuation_share": 1.5},
            "actuation_share=1.5 is invalid: allowed 0 to 1 (a shoe's share",
        ),
    ],
)
def test_a_severity_beyond_its_range_is_refused_naming_the_limit(change, message):
    with pytest.raises(ParameterError, match=message.replace("(", r"\(")):
        ShoeDefect(**change)


def test_the_cli_lists_every_kind_with_unit_locations_and_range(capsys):
    assert main(["defects"]) == 0
    out = capsys.readouterr().out
    assert out.strip() == catalogue_text()
    for kind in catalogue.KINDS:
        assert f"{kind.name} [{kind.unit}] at {', '.join(kind.locations)}" in out
        assert f"range {kind.minimum:g} to {kind.maximum:g} {kind.unit}" in out
