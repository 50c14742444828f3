"""Defects in time: onsets and growth laws, evaluated inside the compiled model, in the
label columns and in the ground truth (model/catalogue.py, model/growth.py)."""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from brake_sim_ros.datasets import parquet
from brake_sim_ros.errors import FidelityError, ParameterError, ScenarioError
from brake_sim_ros.model import catalogue, growth
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import pack
from brake_sim_ros.model.catalogue import Growth
from brake_sim_ros.model.defects import Defects, DrumDefect, ShoeDefect
from brake_sim_ros.model.fidelity import plan
from brake_sim_ros.scenarios.loader import load_scenario, parse_scenario
from brake_sim_ros.solvers.contact_regime import run_contact_regime
from brake_sim_ros.solvers.reference import run_reference
from brake_sim_ros.stream.build import stepper_for
from brake_sim_ros.stream.ground_truth import PUBLISH_FRACTION, PUBLISH_PERIOD_S, TruthUpdates
from tests.sample_blocks import scenario_table

PIVOT_COLUMN = "defect:pivot_radius_change:left [%]"


# --- the laws ------------------------------------------------------------------------------
def test_a_step_is_absent_before_its_onset_and_whole_from_it_on():
    g = Growth(onset_s=1.5)
    assert [g.severity(t, 3.0) for t in (0.0, 1.4999, 1.5, 7.0)] == [0.0, 0.0, 3.0, 3.0]


def test_linear_growth_climbs_at_its_rate_and_holds_at_the_final_severity():
    g = Growth(onset_s=1.0, law="linear", rate_per_s=2.0)
    assert g.severity(0.99, -3.0) == 0.0
    assert g.severity(1.25, -3.0) == pytest.approx(-0.5, rel=1e-15)
    assert g.severity(2.0, -3.0) == pytest.approx(-2.0, rel=1e-15)
    assert g.reached_s(-3.0) == 2.5
    assert g.severity(2.5, -3.0) == g.severity(100.0, -3.0) == -3.0
    assert g.rate == 2.0


def test_exponential_growth_doubles_every_doubling_time_up_to_the_final_severity():
    g = Growth(onset_s=0.5, law="exponential", doubling_time_s=0.25, start=10.0)
    assert g.severity(0.4, 150.0) == 0.0
    assert g.severity(0.5, 150.0) == 10.0
    for k in (1, 2, 3):
        assert g.severity(0.5 + 0.25 * k, 150.0) == pytest.approx(10.0 * 2**k, rel=1e-12)
    assert g.reached_s(150.0) == pytest.approx(0.5 + 0.25 * math.log2(15.0))
    assert g.severity(1.5, 150.0) == 150.0  # 160 would be beyond: held at the final
    assert g.rate == pytest.approx(math.log(2.0) / 0.25)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"onset_s": -1.0}, "onset_s=-1 is invalid: allowed 0 to 86400 s"),
        ({"law": "sigmoid"}, "growth 'sigmoid' is invalid: allowed one of"),
        ({"law": "linear"}, "rate_per_s=0 with growth 'linear' is invalid: allowed a number > 0"),
        ({"rate_per_s": 1.0}, "rate_per_s=1 with growth 'step' is invalid"),
        ({"law": "exponential", "start": 1.0}, "doubling_time_s=0 with growth 'exponential'"),
        ({"onset_s": math.nan}, "onset_s=nan is invalid: allowed a finite number"),
    ],
)
def test_an_impossible_law_is_refused_in_one_line(kwargs, message):
    with pytest.raises(ParameterError, match=re.escape(message)) as info:
        Growth(**kwargs)
    assert "\n" not in str(info.value)


# --- scenario syntax ------------------------------------------------------------------------
def _scenario(defects: str, extra: str = "") -> str:
    return f'name = "grow"\nduration_s = 2.0\n{extra}\n{defects}'


def test_a_scenario_states_onset_and_growth_beside_the_final_value():
    sc = parse_scenario(
        _scenario(
            "[defects.left]\n"
            'pivot_radius_change_pct = {value = 3.0, onset_s = 0.5, growth = "linear",'
            " rate_per_s = 1.5}\n"
            'actuation_share = {value = 0.55, growth = "exponential", doubling_time_s = 0.2,'
            " start = 0.51}\n"
            "[defects.drum]\n"
            'harmonics = [{order = 2, amplitude_um = 40.0}]\nonset_s = 1.0\ngrowth = "step"\n'
        )
    )
    d = sc.setup.defects
    assert d.left.pivot_radius_change_pct == 3.0 and d.right.actuation_share == pytest.approx(0.45)
    assert d.growth_of("pivot_radius_change", "left") == Growth(0.5, "linear", rate_per_s=1.5)
    share = d.growth_of("actuation_share_change", "left")
    assert share.law == "exponential" and share.start == pytest.approx(0.01)
    # the other shoe's share mirrors it: the shares sum to 1 at every instant
    mirrored = d.growth_of("actuation_share_change", "right")
    for t in (0.0, 0.3, 0.6, 2.0):
        assert share.severity(t, 0.05) + mirrored.severity(t, -0.05) == pytest.approx(0.0)
    assert d.growth_of("drum_out_of_round", "drum") == Growth(onset_s=1.0)
    assert set(d.growing_kinds) == {"pivot_radius_change", "actuation_share_change", DRUM}


DRUM = catalogue.DRUM_KIND


@pytest.mark.parametrize(
    ("defects", "message"),
    [
        (
            "[defects.left]\npivot_radius_change_pct = {value = 25.0, onset_s = 1.0}",
            "pivot_radius_change_pct=25 is invalid: allowed -20 to 20",
        ),
        (
            "[defects.left]\npivot_radius_change_pct = {value = 3.0, onset_s = -0.5}",
            "pivot_radius_change_pct.onset_s' = -0.5 is invalid: allowed a number >= 0",
        ),
        (
            '[defects.left]\npivot_radius_change_pct = {value = 3.0, growth = "linear"}',
            "pivot_radius_change_pct.rate_per_s' is missing: allowed a number with growth",
        ),
        (
            "[defects.left]\npivot_radius_change_pct = {value = 3.0, rate_per_s = 1.0}",
            'rate_per_s\' = 1.0 is invalid: allowed a value only with growth = "linear"',
        ),
        (
            '[defects.left]\npivot_radius_change_pct = {value = 3.0, growth = "exponential",'
            " doubling_time_s = 0.1, start = 4.0}",
            "start=4 is invalid: allowed a value between the healthy 0 and the final 3",
        ),
        (
            '[defects.left]\ninitial_angle_deg = {value = -2.0, growth = "linear",'
            " rate_per_s = 1.0}",
            "allowed only a step at 0 s (an initial condition of the run",
        ),
        (
            "[defects.left]\nactuation_share = {value = 0.55, onset_s = 1.0}\n"
            "[defects.right]\nactuation_share = {value = 0.45, onset_s = 1.0}",
            "given twice: allowed one entry per defect"
            " (the other shoe's actuation_share mirrors it)",
        ),
        (
            "[defects.left]\npivot_radius_change_pct = {value = 0.0, onset_s = 1.0}",
            "has an onset and growth but no final severity",
        ),
        (
            "[defects.left]\npivot_radius_change_pct = {onset_s = 1.0}",
            "pivot_radius_change_pct.value' is missing: allowed a number (the final value)",
        ),
        (
            '[defects.drum]\nharmonics = [{order = 2, amplitude_um = 50.0}]\ngrowth = "linear"'
            "\nrate_per_s = -5.0",
            "rate_per_s' = -5.0 is invalid: allowed a number > 0 and <= inf",
        ),
    ],
)
def test_a_bad_growth_in_a_scenario_is_refused_in_one_line_naming_the_limit(defects, message):
    with pytest.raises(ScenarioError, match=re.escape(message)) as info:
        parse_scenario(_scenario(defects))
    assert "\n" not in str(info.value) and str(info.value).startswith("<string>")


def test_levels_and_solvers_that_hold_defects_fixed_refuse_a_growing_one():
    text = "[defects.left]\npivot_radius_change_pct = {value = 3.0, onset_s = 1.0}"
    with pytest.raises(ScenarioError, match="cannot represent the defect 'pivot_radius_change'"):
        parse_scenario(
            _scenario(text, '[needs]\noutputs = ["stop_time"]\nlevel = "contact_regime"\n')
        )
    planned = parse_scenario(_scenario(text, '[needs]\noutputs = ["stop_time"]\n'))
    assert planned.needs.growing == ("pivot_radius_change",)
    assert plan(planned.needs).level.name == "full"  # the contact levels are skipped
    setup = planned.setup
    with pytest.raises(ParameterError, match="reference solver holds the defects fixed"):
        run_reference(setup, 0.1)
    with pytest.raises(FidelityError, match="changing during the run"):
        run_contact_regime(setup, 0.1)


# --- the compiled model ----------------------------------------------------------------------
def test_a_defect_present_from_the_start_packs_as_it_did_whatever_its_spelling():
    plain = load_scenario("case1_left_pivot_out")
    table = parse_scenario(
        plain.text.replace(
            "pivot_radius_change_pct = 3.0",
            "pivot_radius_change_pct = {value = 3.0, onset_s = 0.0}",
        )
    )
    assert table.setup.defects == plain.setup.defects and table.setup.defects.is_static
    p0 = pack(plain.setup.params, plain.setup.defects)
    p1 = pack(table.setup.params, table.setup.defects)
    assert p0.tobytes() == p1.tobytes() and p0[L.P_GROWTH_COUNT] == 0.0


def test_the_compiled_placement_is_the_assembly_rule_of_the_static_pack():
    """A pin grown to its final place is where the static pack puts it (same slots)."""
    sc = load_scenario("case1_left_pivot_out")
    d = dataclasses.replace(
        sc.setup.defects,
        growth=(("pivot_radius_change", "left", Growth(0.0, "linear", rate_per_s=1.0)),),
    )
    p = pack(sc.setup.params, d)
    healthy = pack(sc.setup.params, Defects())
    pw = growth.working_copy(p)
    growth.apply(
        p, pw, 0.0, np.zeros(L.N_STATE), growth.ALL_ENTRIES
    )  # severity 0: the healthy shoe
    b = L.P_SHOE_BASE
    assert np.allclose(pw[b : b + L.SHOE_STRIDE], healthy[b : b + L.SHOE_STRIDE], rtol=1e-14)
    growth.apply(p, pw, 10.0, np.zeros(L.N_STATE), growth.ALL_ENTRIES)  # 3 % reached
    assert np.allclose(pw[b : b + L.SHOE_STRIDE], p[b : b + L.SHOE_STRIDE], rtol=1e-14)
    assert not np.allclose(p[b : b + L.SHOE_STRIDE], healthy[b : b + L.SHOE_STRIDE])


def test_a_pivot_grown_before_the_brake_is_applied_brakes_as_the_static_defect():
    """The pin moves from healthy to +3 % in the first 0.1 s (the actuation starts at
    0.2 s): from then on the run is the static case's, sample for sample; before, the
    shoe's indentation is the healthy one's."""
    static = load_scenario("case1_left_pivot_out")
    d = dataclasses.replace(
        static.setup.defects,
        growth=(("pivot_radius_change", "left", Growth(0.0, "linear", rate_per_s=30.0)),),
    )
    grown = stepper_for(static.with_defects(d)).run(0.8)
    ref = stepper_for(static).run(0.8)
    healthy = stepper_for(static.with_defects(Defects())).run(0.1)
    after = grown.time_s > 0.1 + 1e-9
    assert np.array_equal(grown.data[after], ref.data[after])
    eps = "left_indentation_m"
    assert grown[eps][0] == healthy[eps][0] != ref[eps][0]
    # the indentation follows the pin: it moves by 0.3 s worth of linear growth
    mid = np.searchsorted(grown.time_s, 0.05)
    expected = healthy[eps][mid] + (ref[eps][0] - healthy[eps][0]) * 0.5
    assert grown[eps][mid] == pytest.approx(expected, rel=0.02)


def test_a_pivot_that_moves_in_the_contact_regime_changes_the_steady_pivot_force():
    """A step of +3 % at 2 s on a healthy brake riding on the drum: before, the healthy
    run's samples exactly; 0.5 s after, the contact-regime pivot force of the static +3 %
    case (a shoe pressed steadily on the drum is in quasi-static balance: its force
    depends on where the pin is, not on how it got there)."""
    static = load_scenario("case1_left_pivot_out")
    d = dataclasses.replace(
        static.setup.defects, growth=(("pivot_radius_change", "left", Growth(onset_s=2.0)),)
    )
    sc = static.with_defects(d)
    run = stepper_for(sc).run(3.0)
    healthy = stepper_for(static.with_defects(Defects())).run(3.0)
    ref = stepper_for(static).run(3.0)
    before = run.time_s < 2.0
    assert np.array_equal(run.data[before], healthy.data[before])
    late = (run.time_s > 2.5) & (run.time_s < 3.0)
    force = run.pivot_force_magnitude("left")[late].mean()
    want = ref.pivot_force_magnitude("left")[late].mean()
    was = healthy.pivot_force_magnitude("left")[late].mean()
    assert abs(want - was) > 0.02 * was  # the defect matters in the contact regime (4x the bound)
    assert force == pytest.approx(want, rel=0.005)


def test_a_growing_share_moves_force_from_one_shoe_to_the_other_as_it_grows():
    """Shares 0.5 -> 0.6 linearly over 1-2 s: each actuation force is the commanded one
    times 2 x its share at that instant (0.5 + 0.1 (t - 1)), and the sum is kept."""
    sc = parse_scenario(
        _scenario(
            "[defects.left]\nactuation_share = {value = 0.6, onset_s = 1.0, growth = "
            '"linear", rate_per_s = 0.1}'
        )
    )
    run = stepper_for(sc).run(2.0)
    t = run.time_s
    commanded = np.interp(t, [0.0, 0.2, 0.7], [0.0, 0.0, 1300.0])
    share = np.where(t < 1.0, 0.5, 0.5 + 0.1 * (t - 1.0))
    assert np.allclose(run["left_actuation_force_n"], 2 * share * commanded, rtol=1e-12)
    assert np.allclose(run["right_actuation_force_n"], 2 * (1 - share) * commanded, rtol=1e-12)


def test_a_growing_drum_scales_every_harmonic_with_the_peak_runout():
    d = Defects(
        drum=DrumDefect.from_orders((2, 40.0, 10.0), (3, 10.0, 0.0)),
        growth=((DRUM, "drum", Growth(1.0, "linear", rate_per_s=25.0)),),
    )
    sc = load_scenario("symmetric")
    p = pack(sc.setup.params, d)
    pw = growth.working_copy(p)
    amplitude = L.P_DRUM_WAVE_BASE + L.W_AMPLITUDE
    growth.apply(p, pw, 0.5, np.zeros(L.N_STATE), growth.ALL_ENTRIES)
    assert pw[amplitude] == 0.0
    growth.apply(
        p, pw, 1.4, np.zeros(L.N_STATE), growth.ALL_ENTRIES
    )  # 10 um of 50 um: a fifth of each harmonic
    assert pw[amplitude] == pytest.approx(8e-6, rel=1e-12)
    assert pw[amplitude + L.DRUM_WAVE_STRIDE] == pytest.approx(2e-6, rel=1e-12)
    truth = {a.kind: a for a in d.active(1.4)}[DRUM]
    assert truth.severity == pytest.approx(10.0)
    assert dict(truth.attributes)["order_2_amplitude_um"] == pytest.approx(8.0)
    assert dict(truth.attributes)["final_severity_um"] == 50.0


# --- labels and ground truth ------------------------------------------------------------------
def _growing_pivot() -> Defects:
    return Defects(
        left=ShoeDefect(pivot_radius_change_pct=3.0),
        growth=(("pivot_radius_change", "left", Growth(0.5, "linear", rate_per_s=2.0)),),
    )


def test_the_ground_truth_lists_a_defect_from_its_onset_with_its_severity_then():
    d = _growing_pivot()
    assert d.active(0.4) == ()
    (now,) = d.active(1.0)
    assert (now.severity, now.onset_s, now.growth, now.growth_rate) == (1.0, 0.5, "linear", 2.0)
    assert dict(now.attributes) == {"final_severity_pct": 3.0}
    assert d.active()[0].severity == 3.0  # the run's description: the final severity


def test_parquet_label_columns_carry_the_severity_at_each_sample(tmp_path):
    sc = load_scenario("symmetric").with_defects(_growing_pivot())
    run = stepper_for(sc).run(2.5, record_every=64)
    table = scenario_table(sc, run)
    path = tmp_path / "run.parquet"
    parquet.write_history(path, table)
    back = pq.read_table(path)
    t = back["time_s"].to_numpy()
    expected = np.clip(2.0 * (t - 0.5), 0.0, 3.0)  # the scenario's law, written out
    assert np.allclose(back[PIVOT_COLUMN].to_numpy(), expected, rtol=1e-12, atol=1e-15)
    assert back[PIVOT_COLUMN].type == pa.float64()
    assert np.all(back["defect:initial_angle:left [deg]"].to_numpy() == 0.0)


def test_ground_truth_updates_follow_the_publication_rule():
    """Linear 0 -> 3 % over 0.5-2 s: the onset sample, then every 5 % of the 3 % service
    limit (0.15 %, i.e. every 75 ms), the final value; silence once it holds."""
    d = _growing_pivot()
    truth = TruthUpdates(d)
    period = 1.0 / 25_600.0
    times = np.arange(0, 3.0 * 25_600) * period
    rows = []
    for start in range(0, times.size, 256):
        rows += [start + r for r in truth.due_rows(times[start : start + 256])]
    published = times[rows]
    severity = np.clip(2.0 * (times - 0.5), 0.0, 3.0)
    assert published[0] == times[times > 0.5][0]  # the first sample with a severity
    assert severity[rows[-1]] == 3.0 and published[-1] == pytest.approx(2.0, abs=period)
    threshold = PUBLISH_FRACTION * 3.0
    assert len(rows) == pytest.approx(3.0 / threshold + 1, abs=1)
    # between publications, the truth never moves further than the rule allows
    held = np.maximum.accumulate(np.where(np.isin(np.arange(times.size), rows), severity, 0.0))
    assert np.max(np.abs(severity - held)) <= threshold + 1e-12
    assert np.max(np.diff(published)) < PUBLISH_PERIOD_S


def test_a_slow_growth_is_published_at_least_once_a_second():
    d = Defects(
        left=ShoeDefect(pivot_radius_change_pct=3.0),
        growth=(("pivot_radius_change", "left", Growth(0.0, "linear", rate_per_s=0.01)),),
    )
    truth = TruthUpdates(d)
    times = np.arange(0, 35 * 100) * 0.01
    rows = truth.due_rows(times)
    assert np.allclose(np.diff(times[rows]), PUBLISH_PERIOD_S)


def test_defects_present_from_the_start_publish_nothing_more():
    truth = TruthUpdates(load_scenario("case1_left_pivot_out").setup.defects)
    assert truth.due_rows(np.arange(0, 1000) * 0.01) == []
