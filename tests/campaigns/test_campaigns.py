"""Campaign files: strict loading, the plan of runs, seeds, and leak-free splits."""

from __future__ import annotations

import math
import subprocess
import sys
import tomllib

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from brake_sim_ros.campaigns import CampaignError, builtin_campaigns, load_campaign, parse_campaign
from brake_sim_ros.campaigns.axes import DefectChoice, defect_choices
from brake_sim_ros.campaigns.campaign import run_seed
from brake_sim_ros.campaigns.splits import SPLITS, HeldOut, leaks, unit_counts
from brake_sim_ros.model.catalogue import KINDS, brake_kinds
from brake_sim_ros.scenarios import parse_scenario
from brake_sim_ros.scenarios.toml_text import dumps

PIVOT = "pivot_radius_change"
TINY = """
name = "tiny"
base = "symmetric"
seed = 3
units = 4
[outputs]
duration_s = 0.2
sample_rate_hz = 2560.0
[[axes]]
defects = ["initial_angle", "drum_out_of_round"]
severities = [0.5, 1.0]
[[axes]]
name = "peak_force_n"
key = "actuation.peak_force_n"
values = [1100.0, 1300.0]
[split]
train = 0.5
validation = 0.25
test = 0.25
[[split.held_out]]
column = "defect_severity"
values = [-2.0]
"""


def _splits_by_unit(runs):
    out: dict[str, set[str]] = {}
    for r in runs:
        out.setdefault(r.unit_id, set()).add(r.split)
    return out


@pytest.mark.slow
@pytest.mark.parametrize("name", builtin_campaigns())
def test_builtin_campaigns_are_leak_free(name):
    campaign = load_campaign(name)
    runs = campaign.runs()
    assert runs
    assert all(len(s) == 1 for s in _splits_by_unit(runs).values())
    rows = [{"run_id": r.run_id, "unit_id": r.unit_id, "split": r.split, **r.columns} for r in runs]
    assert leaks(rows, campaign.held_out) == []
    held = [r for r in rows if any(h.matches(r) for h in campaign.held_out)]
    assert all(r["split"] == "test" for r in held)
    assert not campaign.held_out or held  # a held-out rule that matches nothing tests nothing


def test_the_demo_can_fit_and_score_every_baseline():
    """Every catalogue defect at its limit in every split (half of it on test only),
    several units per split (impact needs healthy stops of three train units), minutes of
    healthy operation on test, and runs longer than the 1.5 s the orders baseline needs."""
    campaign = load_campaign("demo")
    runs = campaign.runs()
    # the demo runs on the service brake: every kind, the line's too, but the pivot radius
    # (from half its limit the service brake's lining starts inside the drum)
    every = {(k.name, loc) for k in brake_kinds(True) if k.name != PIVOT for loc in k.locations}
    for split, units in (("train", 5), ("validation", 2), ("test", 2)):
        mine = [r for r in runs if r.split == split]
        assert len({r.unit_id for r in mine}) == units
        at_limit = {
            (r.columns["defect_kind"], r.columns["defect_location"])
            for r in mine
            if r.columns["defect_severity_fraction"] == 1.0
        }
        assert at_limit == every
        healthy = [r for r in mine if r.columns["defect_kind"] == "healthy"]
        assert len({r.unit_id for r in healthy}) == units
        assert len({r.seed for r in healthy}) == len(healthy)  # each its own run
        if split == "test":
            assert sum(r.duration_s for r in healthy) >= 120.0
    halves = {r.split for r in runs if r.columns["defect_severity_fraction"] == 0.5}
    assert halves == {"test"}
    assert min(r.duration_s for r in runs) > 1.5
    assert campaign.outputs.sample_rate_hz == 5120.0


def test_the_reference_campaign_runs_every_service_kind_but_the_pivot_radius():
    """The reference campaign (docs/benchmarks.md's service-brake scores): every kind the
    service brake carries, the seized adjuster and the line's too, but the pivot radius, at
    its two severities on each of its locations, and one healthy run, at each drawn force;
    forces from 1450 N up on the test units only."""
    campaign = load_campaign("reference")
    runs = campaign.runs()
    kinds = [k for k in brake_kinds(True) if k.name != PIVOT]
    assert {r.columns["defect_kind"] for r in runs} == {k.name for k in kinds} | {"healthy"}
    conditions = 2 * sum(len(k.locations) for k in kinds) + 1
    forces = {r.columns["peak_force_n"] for r in runs}
    assert len(forces) == 4  # the Latin hypercube's four draws
    held = sum(force >= 1450.0 for force in forces)
    assert 0 < held < len(forces)  # the held-out rule holds something out and keeps the rest
    counts = unit_counts(10, {"train": 0.6, "validation": 0.2, "test": 0.2})
    pairs = counts["test"] * len(forces) + (10 - counts["test"]) * (len(forces) - held)
    assert len(runs) == conditions * pairs
    for split, units in counts.items():
        assert len([r for r in runs if r.split == split]) == units * conditions * (
            len(forces) - (held if split != "test" else 0)
        )


def test_healthy_counts_make_that_many_healthy_runs_each_its_own():
    text = TINY.replace("severities = [0.5, 1.0]", "severities = [0.5, 1.0]\nhealthy = 3")
    runs = parse_campaign(text, "t.toml").runs()
    healthy = [r for r in runs if r.columns["defect_kind"] == "healthy"]
    per_unit = {r.unit_id for r in healthy}
    assert len(healthy) == 3 * 2 * len(per_unit)  # three per force on each unit
    assert sorted({r.columns["defect_repeat"] for r in healthy}) == [0, 1, 2]
    assert len({r.seed for r in healthy}) == len(healthy)
    defective = [r for r in runs if r.columns["defect_kind"] != "healthy"]
    assert {r.columns["defect_repeat"] for r in defective} == {0}
    for bad in ("-1", "1001", "1.5", "'all'"):
        with pytest.raises(CampaignError, match=r"axes\[0\]\.healthy"):
            parse_campaign(text.replace("healthy = 3", f"healthy = {bad}"), "t.toml")


def test_plan_crosses_units_and_axes_and_holds_values_out():
    campaign = parse_campaign(TINY, "tiny.toml")
    runs = campaign.runs()
    # (initial_angle at 2 sides + drum at 1) x 2 severities + healthy, x 2 forces
    n_points = ((2 + 1) * 2 + 1) * 2
    by_unit = _splits_by_unit(runs)
    assert sorted(len(v) for v in by_unit.values()) == [1, 1, 1, 1]
    assert sorted(s for v in by_unit.values() for s in v) == [
        "test",
        "train",
        "train",
        "validation",
    ]
    held = [r for r in runs if r.columns["defect_severity"] == -2.0]
    assert held and all(r.split == "test" for r in held)
    test_units = [u for u, s in by_unit.items() if s == {"test"}]
    # held-out points (initial angle -2 deg at two sides, two forces) are skipped elsewhere
    assert len(runs) == 4 * n_points - 3 * 4
    assert {r.unit_id for r in held} == set(test_units)
    # every varied scenario is what the scenario loader reads, with unit and seed set
    for r in runs[:5]:
        scenario = parse_scenario(r.scenario_text, r.run_id)
        assert scenario.unit_id == r.unit_id
        assert scenario.seed == r.seed
        assert scenario.duration_s == 0.2
        assert scenario.setup.actuation.left.forces_n[-1] == r.columns["peak_force_n"]
    assert len({r.run_id for r in runs}) == len(runs)


@pytest.mark.slow
def test_seeds_come_from_the_campaign_seed_and_the_run_identity_not_hash():
    runs = parse_campaign(TINY, "tiny.toml").runs()
    assert len({r.seed for r in runs}) == len(runs)
    more = parse_campaign(TINY.replace("units = 4", "units = 5"), "tiny.toml").runs()
    seeds = {(r.unit_id, r.run_id): r.seed for r in more}
    for r in runs:  # adding a unit changes no other run's seed
        if (r.unit_id, r.run_id) in seeds:
            assert seeds[(r.unit_id, r.run_id)] == r.seed
    other = parse_campaign(TINY.replace("seed = 3", "seed = 4"), "tiny.toml").runs()
    assert not {r.seed for r in runs} & {r.seed for r in other}
    code = (
        "from brake_sim_ros.campaigns.campaign import run_seed;"
        "print(run_seed(3, 'u', {'a': 1.0, 'b': 'x'}))"
    )
    printed = {
        subprocess.run(
            [sys.executable, "-c", code],
            env={"PYTHONHASHSEED": salt, "PYTHONPATH": ":".join(sys.path)},
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        for salt in ("1", "2")
    }
    assert printed == {str(run_seed(3, "u", {"a": 1.0, "b": "x"}))}


def test_drawn_axes_are_reproducible_and_within_their_range():
    text = (
        TINY.replace("values = [1100.0, 1300.0]", "uniform = [900.0, 1500.0]")
        + "[draws]\nmethod = 'lhs'\nn = 5\n"
    )
    a = parse_campaign(text, "t.toml").runs()
    b = parse_campaign(text, "t.toml").runs()
    forces = [r.columns["peak_force_n"] for r in a]
    assert forces == [r.columns["peak_force_n"] for r in b]
    assert all(900.0 <= f <= 1500.0 for f in forces)
    first_unit = sorted({f for r, f in zip(a, forces, strict=True) if r.unit_id == a[0].unit_id})
    # a Latin hypercube: one draw in each fifth of the range
    assert sorted(int((f - 900.0) // 120.0) for f in first_unit) == [0, 1, 2, 3, 4]


BAD = [
    ("name = 'x'\nbase = 'symmetric'\nsurprise = 1\n", "key 'surprise'"),
    ("base = 'symmetric'\n", "key 'name' is missing"),
    ("name = 'x'\nbase = 'nope'\n", "key 'base'"),
    ("name = 'x'\nbase = 'symmetric'\nunits = 0\n", "key 'units'"),
    ("name = 'x'\nbase = 'symmetric'\nunits = 2\n", "2 unit(s) cannot fill"),
    ("name = 'x'\nbase = 'symmetric'\nseed = -1\n", "key 'seed'"),
    ("name = 'x'\nbase = 'symmetric'\n[outputs]\nduration_s = 0\n", "outputs.duration_s"),
    ("name = 'x'\nbase = 'symmetric'\n[[axes]]\nkey = 'actuation.peak_force_n'\n"
     "values = ['a', 1]\n", "axes[0].values"),
    ("name = 'x'\nbase = 'symmetric'\n[[axes]]\nkey = 'unit_id'\nvalues = ['a']\n", "axes[0].key"),
    ("name = 'x'\nbase = 'symmetric'\n[[axes]]\nkey = 'a..b'\nvalues = [1]\n", "axes[0].key"),
    ("name = 'x'\nbase = 'symmetric'\n[[axes]]\nkey = 'actuation.peak_force_n'\nuniform = [1, 2]\n",
     "key 'draws' is missing"),
    ("name = 'x'\nbase = 'symmetric'\n[[axes]]\ndefects = ['rust']\n", "axes[0].defects"),
    ("name = 'x'\nbase = 'symmetric'\n[[axes]]\ndefects = 'all'\nseverities = [9.0]\n",
     "axes[0].severities"),
    ("name = 'x'\nbase = 'symmetric'\n[split]\ntrain = 0.5\ntest = 0.2\n", "key 'split'"),
    ("name = 'x'\nbase = 'symmetric'\n[[split.held_out]]\ncolumn = 'q'\nvalues = [1]\n",
     "split.held_out[0].column"),
    # a varied scenario the scenario loader refuses: the run and the scenario key named
    ("name = 'x'\nbase = 'symmetric'\nunits = 3\n[[axes]]\nkey = 'actuation.peak_force_n'\n"
     "values = [1300.0, 60000.0]\n", "key 'actuation.peak_force_n' = 60000.0"),
    ("name = 'x'\nbase = 'symmetric'\nunits = 3\n[[axes]]\nkey = 'actuation.nonsense'\n"
     "values = [1.0]\n", "key 'actuation.nonsense'"),
    ("name = 'x'\nbase = 'symmetric'\nunits = 3\n[outputs]\nduration_s = 3600\n", "samples"),
    ("name = 'x'\nbase = 'symmetric'\nnot toml", "not valid TOML"),
]  # fmt: skip


@pytest.mark.parametrize(("text", "expected"), BAD)
def test_bad_campaigns_are_refused_in_one_line_naming_file_and_key(text, expected):
    with pytest.raises(CampaignError) as info:
        parse_campaign(text, "bad.toml").runs()
    message = str(info.value)
    assert "\n" not in message
    assert "bad.toml" in message
    assert expected in message


def test_a_relative_base_path_is_read_beside_the_campaign(tmp_path):
    (tmp_path / "base.toml").write_text("name = 'b'\nduration_s = 0.1\n")
    (tmp_path / "c.toml").write_text("name = 'c'\nbase = 'base.toml'\nunits = 3\n")
    runs = load_campaign(tmp_path / "c.toml").runs()
    assert [parse_scenario(r.scenario_text).duration_s for r in runs] == [0.1, 0.1, 0.1]
    with pytest.raises(CampaignError, match="no such file"):
        load_campaign(tmp_path / "missing.toml")


@settings(max_examples=200, deadline=None)
@given(
    st.dictionaries(
        st.text(min_size=1, max_size=8),
        st.recursive(
            st.none().map(lambda _: 0)
            | st.booleans()
            | st.integers(-(2**63), 2**63 - 1)
            | st.floats(allow_nan=False)
            | st.text(max_size=12),
            lambda inner: (
                st.lists(inner, max_size=3)
                | st.dictionaries(st.text(max_size=5), inner, max_size=3)
            ),
            max_leaves=8,
        ),
        max_size=5,
    )
)
def test_toml_text_round_trips(data):
    assert tomllib.loads(dumps(data)) == data


# the kinds a campaign on the study brake ('symmetric') sweeps: the service brake's own
# (the line's, the seized adjuster) need its circuit or its adjuster
STUDY_KINDS = [k.name for k in KINDS if not k.service_only]


@st.composite
def _campaigns(draw):
    n_units = draw(st.integers(1, 9))
    fractions = draw(
        st.sampled_from(
            [(0.6, 0.2, 0.2), (0.8, 0.0, 0.2), (0.5, 0.5, 0.0), (1.0, 0.0, 0.0), (0.34, 0.33, 0.33)]
        )
    )
    forces = draw(
        st.lists(
            st.sampled_from([900.0, 1100.0, 1300.0, 1500.0]), min_size=1, max_size=3, unique=True
        )
    )
    kinds = draw(st.lists(st.sampled_from(STUDY_KINDS), min_size=1, max_size=2, unique=True))
    held = draw(st.sampled_from(["", "force", "kind", "range"]))
    text = (
        f"name = 'r'\nbase = 'symmetric'\nseed = {draw(st.integers(0, 2**63 - 1))}\n"
        f"units = {n_units}\n[outputs]\nduration_s = 0.1\n"
        f"[[axes]]\ndefects = {kinds!r}\nseverities = [1.0]\n"
        f"[[axes]]\nname = 'force'\nkey = 'actuation.peak_force_n'\nvalues = {forces!r}\n"
        f"[split]\ntrain = {fractions[0]}\nvalidation = {fractions[1]}\ntest = {fractions[2]}\n"
    )
    if held == "force":
        text += f"[[split.held_out]]\ncolumn = 'force'\nvalues = [{forces[0]}]\n"
    elif held == "kind":
        text += f"[[split.held_out]]\ncolumn = 'defect_kind'\nvalues = ['{kinds[0]}']\n"
    elif held == "range":
        text += "[[split.held_out]]\ncolumn = 'force'\nmin = 1000.0\nmax = 1200.0\n"
    return text, n_units, fractions


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_campaigns())
def test_random_campaigns_are_leak_free(case):
    text, n_units, fractions = case
    forces = tomllib.loads(text)["axes"][1]["values"]
    wanted = sum(f > 0 for f in fractions)
    try:
        campaign = parse_campaign(text, "r.toml")
        runs = campaign.runs()
    except CampaignError as exc:
        # the only refusals: too few units for the splits, a held-out rule without test, a
        # held-out range that no force falls in, or a rule that holds out every condition
        idle = "matches no run" in str(exc) and not any(1000.0 <= f <= 1200.0 for f in forces)
        data = tomllib.loads(text)
        rule = (data["split"].get("held_out") or [{}])[0]
        if rule.get("column") == "force":
            low, high = rule.get("min", -math.inf), rule.get("max", math.inf)
            held = [(f in rule["values"]) if "values" in rule else low <= f <= high for f in forces]
        elif rule.get("column") == "defect_kind":
            held = [k in rule["values"] for k in data["axes"][0]["defects"]]
        else:
            held = [False]
        every = "holds out every condition" in str(exc) and all(held)
        assert n_units < wanted or fractions[2] == 0.0 or idle or every, str(exc)
        return
    assert n_units >= wanted
    by_unit = _splits_by_unit(runs)
    assert all(len(s) == 1 for s in by_unit.values())  # no unit in two splits
    counts = unit_counts(n_units, dict(zip(SPLITS, fractions, strict=True)))
    assert all(counts[s] >= 1 for s, f in zip(SPLITS, fractions, strict=True) if f > 0)
    rows = [{"run_id": r.run_id, "unit_id": r.unit_id, "split": r.split, **r.columns} for r in runs]
    assert leaks(rows, campaign.held_out) == []
    for rule in campaign.held_out:
        assert all(r["split"] == "test" for r in rows if rule.matches(r))


def test_leaks_finds_a_unit_in_two_splits_and_a_held_out_value_outside_test():
    rows = [
        {"run_id": "a", "unit_id": "u1", "split": "train", "force": 1.0},
        {"run_id": "b", "unit_id": "u1", "split": "test", "force": 2.0},
        {"run_id": "c", "unit_id": "u2", "split": "validation", "force": 2.0},
    ]
    problems = leaks(rows, [HeldOut("force", (2.0,))])
    assert any("unit u1" in p for p in problems)
    assert any("run c" in p for p in problems)
    assert leaks(rows[:1] + rows[2:], []) == []


def test_defect_choices_cover_the_catalogue_and_build_one_defect_each():
    choices = defect_choices(tuple(k.name for k in KINDS), (1.0,), healthy=True)
    assert choices[0] == DefectChoice("healthy", "", 0.0)
    assert choices[0].defects().is_healthy
    for c in choices[1:]:
        found = {(d.kind, d.location): d.severity for d in c.defects().active()}
        assert found[(c.kind, c.location)] == pytest.approx(c.severity, abs=1e-12)
        # one defect; a share change moves the other shoe's share with it
        assert set(found) == {(c.kind, c.location)} or c.kind == "actuation_share_change"


def test_each_unit_is_one_brake_in_all_its_runs_each_run_its_own_seed():
    """The campaign's units are one fleet (fleet_seed = the campaign seed): a unit is the
    same brake in all its runs, units differ from one another, and every run has its own
    seed (its noise and draws)."""
    runs = parse_campaign(TINY, "t.toml").runs()
    brakes: dict[str, set] = {}
    for r in runs:
        scenario = parse_scenario(r.scenario_text, r.run_id)
        assert scenario.fleet_seed == 3
        brakes.setdefault(r.unit_id, set()).add(scenario.setup.params)
    assert all(len(b) == 1 for b in brakes.values())
    assert len({next(iter(b)) for b in brakes.values()}) == len(brakes) > 1
    assert len({r.seed for r in runs}) == len(runs)
    with pytest.raises(CampaignError, match="key 'seeds'"):
        parse_campaign(TINY.replace("seed = 3\n", "seed = 3\nseeds = 'unit'\n"), "t.toml")


def _demo_with_rule(rule: str) -> str:
    text = load_campaign("demo").text
    head = text[: text.index("[[split.held_out]]")]
    return head + "[[split.held_out]]\n" + rule


def test_a_held_out_rule_that_matches_no_run_is_refused_in_one_line():
    # the trap: severities are fractions of the service limit in [[axes]], while
    # defect_severity is the absolute size in each kind's unit: 0.25 matches no run
    text = _demo_with_rule("column = 'defect_severity'\nvalues = [0.25]\n")
    with pytest.raises(CampaignError) as caught:
        parse_campaign(text, "demo.toml")
    message = str(caught.value)
    assert "\n" not in message
    assert "split.held_out[0]" in message and "matches no run" in message
    assert "defect_severity_fraction" in message
    with pytest.raises(CampaignError, match=r"split\.held_out\[0\].*matches no run"):
        parse_campaign(_demo_with_rule("column = 'peak_force_n'\nmin = 5000.0\n"), "d.toml")


def test_the_severity_fraction_column_is_the_axis_value_and_holds_out_by_fraction():
    campaign = parse_campaign(
        _demo_with_rule("column = 'defect_severity_fraction'\nvalues = [0.5]\n"), "demo.toml"
    )
    axis = tomllib.loads(campaign.text)["axes"][0]
    runs = campaign.runs()
    limits = {k.name: k.service_limit for k in KINDS}
    healthy = [r for r in runs if r.columns["defect_kind"] == "healthy"]
    assert healthy and all(r.columns["defect_severity_fraction"] == 0.0 for r in healthy)
    for r in runs:
        c = r.columns
        if c["defect_kind"] == "healthy":
            continue
        assert c["defect_severity_fraction"] in axis["severities"]
        assert c["defect_severity"] == c["defect_severity_fraction"] * limits[c["defect_kind"]]
        if c["defect_severity_fraction"] == 0.5:
            assert r.split == "test"
    assert {r.columns["defect_severity_fraction"] for r in runs} == {0.0, 0.5, 1.0}


def test_the_fraction_column_leaves_every_run_seed_as_it_was():
    # a derived column is no part of a run's identity: datasets keep their seeds
    campaign = load_campaign("demo")
    for r in campaign.runs():
        identity = {
            k: v
            for k, v in r.columns.items()
            if k != "defect_severity_fraction" and not (k == "defect_repeat" and v == 0)
        }
        assert r.seed == run_seed(campaign.seed, r.unit_id, identity)
