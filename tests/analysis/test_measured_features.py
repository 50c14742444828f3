"""The features of the measured backing-plate acceleration and the rule that says when one
separates a defect case from the symmetric brake (analysis/measured_features.py), shared
by ``brake-sim bench sensors`` and the validation report."""

from __future__ import annotations

import math
import time

import pytest

from brake_sim_ros.analysis import measured_features as mf
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.stream.run import run_scenario

RATE_HZ = 25_600.0


def test_rule_needs_every_floor():
    band = mf.SeparationRule(spread_factor=3.0, min_relative=0.05)
    assert band.separates(106.0, 100.0, 1.0)  # 6 > 3 x 1 and > 5 % of 100
    assert band.separates(94.0, 100.0, 1.0)  # either direction
    assert not band.separates(104.0, 100.0, 0.1)  # above the spread, below 5 %
    assert not band.separates(110.0, 100.0, 4.0)  # above 5 %, below 3 spreads (12)
    assert not band.separates(100.0, 100.0, 0.0)
    first = mf.SeparationRule(min_absolute=0.078)
    assert first.separates(220.5, 221.17, 0.0)
    assert not first.separates(221.1, 221.17, 0.0)  # 0.07 ms: less than two samples
    for bad in (math.inf, math.nan):  # a feature missing on one side is not judged
        assert not band.separates(bad, 100.0, 1.0)
        assert not band.separates(100.0, bad, 1.0)
        assert not band.separates(200.0, 100.0, bad)


def test_rules_of_the_features():
    rules = mf.separation_rules(1.0 / RATE_HZ)
    assert rules[mf.FIRST_IMPACT].min_absolute == pytest.approx(1e3 * 2 / RATE_HZ)
    assert rules[mf.FIRST_IMPACT].min_relative == 0.0
    for k in mf.BAND_RMS:
        assert rules[k].min_relative == mf.BAND_REPEATABILITY
        assert rules[k].spread_factor == mf.SPREAD_FACTOR
    assert mf.CLIPPED not in rules  # reported, not judged


def test_compare_cases_uses_the_largest_seed_spread_of_all_cases():
    def rows(*values: float) -> list[dict[str, float]]:
        return [{"a": v, "b": 1.0} for v in values]

    rules = {"a": mf.SeparationRule(min_relative=0.01)}
    # std over seeds: base 0, "near" 0, "noisy" 5: the spread is 5 for every case
    per_seed = {
        "base": rows(100.0, 100.0),
        "near": rows(110.0, 110.0),  # 10 < 3 x 5: not separated, though its own std is 0
        "far": rows(120.0, 120.0),  # 20 > 15
        "noisy": rows(95.0, 105.0),  # mean 100: no difference
    }
    out = mf.compare_cases(per_seed, "base", rules)
    assert set(out) == {"near", "far", "noisy"}
    assert {c: out[c]["a"].spread for c in out} == dict.fromkeys(out, 5.0)
    assert [out[c]["a"].separates for c in ("near", "far", "noisy")] == [False, True, False]
    assert out["far"]["a"].relative == pytest.approx(0.2)
    assert out["far"]["a"].difference == pytest.approx(20.0)
    assert out["far"]["b"].separates is None  # no rule: not judged
    # without the noisy case the spread is 0 and the 1 % floor decides
    del per_seed["noisy"]
    out = mf.compare_cases(per_seed, "base", rules)
    assert out["near"]["a"].separates and out["far"]["a"].separates


def test_measured_acceleration_separates_a_tilted_shoe_and_not_the_brake_from_itself():
    """Case 5 (left shoe tilted 2 deg) has the largest change of the measured band levels
    (about +100 % on x in the bench): measured by the default sensors over a short stop it
    separates from the symmetric brake; the symmetric brake's own samples, under another
    name, separate on nothing."""
    t0 = time.perf_counter()
    duration = mf.IMPACT_WINDOW_S[1] + 0.02
    samples = {
        name: run_scenario(load_scenario(name), duration_s=duration).samples
        for name in ("symmetric", "case5_left_tilted")
    }
    samples["symmetric again"] = samples["symmetric"]
    result = mf.measure_cases(samples, "symmetric", sample_rate_hz=RATE_HZ, seeds=(0, 1))
    tilted = result.comparisons["case5_left_tilted"]
    x = tilted["band rms x"]
    assert x.separates and x.relative > 0.5, x
    assert "band rms x" in result.separating("case5_left_tilted")
    assert result.verdict("case5_left_tilted").startswith("separated by")
    assert result.separating("symmetric again") == []
    assert "not separated" in result.verdict("symmetric again")
    # the noise differs between seeds (a spread exists), yet stays far below the band level
    rows = result.per_seed["symmetric"]
    assert rows[0]["band rms x"] != rows[1]["band rms x"]
    assert 0 < x.spread < 0.01 * x.base_mean
    assert all(r[mf.FIRST_IMPACT] < 1e3 * mf.IMPACT_WINDOW_S[1] for r in rows)
    assert time.perf_counter() - t0 < 20.0


def test_features_refuse_a_stop_too_short_for_the_window():
    samples = {"symmetric": run_scenario(load_scenario("symmetric"), duration_s=0.3).samples}
    samples["other"] = samples["symmetric"]
    with pytest.raises(ValueError, match="need"):
        mf.measure_cases(samples, "symmetric", sample_rate_hz=RATE_HZ, seeds=(0, 1))
    with pytest.raises(ValueError, match="two"):
        mf.measure_cases(samples, "symmetric", sample_rate_hz=RATE_HZ, seeds=(0,))


def test_validation_section_names_the_separating_features_or_says_none():
    """The report's section on synthetic figures: a verdict for every case, the separating
    features named, a case that nothing separates said to be not separated."""
    from brake_sim_ros.studies.validation_report import measured_markdown

    def row(first: float, x: float, y: float) -> dict[str, float]:
        return {mf.FIRST_IMPACT: first, "band rms x": x, "band rms y": y, mf.CLIPPED: 3.0}

    per_seed = {
        "symmetric": [row(221.0, 50.0, 80.0), row(221.0, 50.01, 80.01)],
        "case_a": [row(219.0, 50.0, 80.0), row(219.0, 50.01, 80.01)],  # first impact only
        "case_b": [row(221.0, 51.0, 81.0), row(221.0, 51.01, 81.01)],  # 2 %: below the floor
    }
    period = 1.0 / RATE_HZ
    result = mf.CaseSeparation(
        "symmetric",
        (0, 1),
        {c: 0.03 for c in mf.AXES_CHANNELS},
        period,
        0.6,
        per_seed,
        mf.compare_cases(per_seed, "symmetric", mf.separation_rules(period)),
    )
    contacts = {"left": 221.0, "right": 221.0}
    fig = {
        "cases": {"1": {"scenario": "case_a"}, "2": {"scenario": "case_b"}},
        "measured": {"first_contact_ms": dict.fromkeys(("symmetric", "1", "2"), contacts)},
    }
    text = "\n".join(measured_markdown(result, fig))
    assert "* 1 (case_a): separated by first impact\n" in text
    assert "* 2 (case_b): **not separated** by any feature" in text
    assert "1 of 2 cases are separated by at least one feature; not separated: 2 (case_b)." in text
    assert text.count("| 1 (case_a) |") == len(mf.FEATURES)
