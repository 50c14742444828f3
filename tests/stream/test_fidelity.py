"""Fidelity levels: the planner's choices and refusals, and each level against the full model."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from brake_sim_ros.errors import FidelityError, ScenarioError
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.fidelity import LEVELS, OUTPUTS, Needs, plan
from brake_sim_ros.scenarios import load_scenario, parse_scenario
from brake_sim_ros.stream.run import run_scenario

# --- planner: pure logic ----------------------------------------------------------------


@pytest.mark.parametrize(
    ("outputs", "level"),
    [
        (("contact_regime_forces",), "contact_regime_rigid"),
        (("stop_time",), "contact_regime"),
        (("stop_time", "braking_torque", "contact_regime_forces"), "contact_regime"),
        (("friction_heat",), "contact_regime"),
        (("impacts",), "rigid"),
        (("impacts", "contact_regime_forces"), "rigid"),
        (("impacts", "stop_time"), "full"),
        (("torsional_vibration",), "full"),
        (("shoe_motion",), "full"),
        (("energy_balance",), "full"),
    ],
)
def test_planner_takes_the_cheapest_level_that_serves_every_output(outputs, level):
    chosen = plan(Needs(outputs=outputs))
    assert chosen.level.name == level
    assert set(outputs) <= chosen.level.outputs
    cheaper = [lv for lv in LEVELS if lv.dof < chosen.level.dof]
    assert all(not set(outputs) <= lv.outputs for lv in cheaper)


def test_no_needs_is_the_full_model_with_every_signal():
    chosen = plan(None)
    assert chosen.level.name == "full" and chosen.columns == L.COLUMNS
    assert chosen.shoes == ("left", "right")


def test_full_level_serves_everything_and_levels_are_ordered_by_cost():
    assert LEVELS[-1].outputs == frozenset(OUTPUTS)
    assert [lv.dof for lv in LEVELS] == sorted(lv.dof for lv in LEVELS)


def test_forced_level_that_cannot_deliver_is_refused_naming_output_and_levels():
    with pytest.raises(FidelityError) as exc:
        plan(Needs(outputs=("stop_time", "impacts"), level="contact_regime"))
    msg = str(exc.value)
    assert "'impacts'" in msg and "contact_regime" in msg and "['rigid', 'full']" in msg
    with pytest.raises(FidelityError, match=r"'stop_time'.*\['contact_regime', 'full'\]"):
        plan(Needs(outputs=("stop_time",), level="rigid"))
    # a forced level that can deliver is kept even when a cheaper one would do
    assert plan(Needs(outputs=("stop_time",), level="full")).level.name == "full"


def test_one_shoe_model_only_for_shoe_local_outputs():
    one = plan(Needs(outputs=("impacts",), shoes=("left",)))
    assert one.shoes == ("left",)
    assert all(not c.startswith("right_") for c in one.columns)
    # the stop time depends on both shoes: both stay in the model, one shoe's signals kept
    both = plan(Needs(outputs=("impacts", "stop_time"), shoes=("right",)))
    assert both.shoes == ("left", "right")
    assert all(not c.startswith("left_") for c in both.columns)


def test_asked_shoe_missing_from_a_one_shoe_brake_is_refused():
    with pytest.raises(FidelityError, match="has only"):
        plan(Needs(outputs=("impacts",), shoes=("right",)), model_shoes=("left",))


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"outputs": ()}, "non-empty"),
        ({"outputs": ("stopping",)}, "unknown: ['stopping']"),
        ({"outputs": ("impacts", "impacts")}, "distinct"),
        ({"outputs": ("impacts",), "shoes": ("middle",)}, "shoes"),
        ({"outputs": ("impacts",), "accuracy": "perfect"}, "accuracy"),
        ({"outputs": ("impacts",), "level": "medium"}, "level"),
    ],
)
def test_bad_needs_are_refused_with_what_is_allowed(kwargs, fragment):
    with pytest.raises(FidelityError, match="allowed") as exc:
        Needs(**kwargs)
    assert fragment in str(exc.value)


def test_needs_table_is_strict_and_checked_at_load():
    s = parse_scenario('name = "n"\n[needs]\noutputs = ["stop_time"]\naccuracy = "fast"\n')
    assert s.needs == Needs(outputs=("stop_time",), accuracy="fast")
    bad = [
        ('[needs]\noutputs = ["stop_time"]\nwhen = 1', "needs.when"),
        ('[needs]\nshoes = ["left"]', "needs.outputs"),
        ('[needs]\noutputs = "stop_time"', "needs.outputs"),
        ('[needs]\noutputs = ["impacts"]\nlevel = "contact_regime"', "cannot deliver"),
        ('[needs]\noutputs = ["impacts"]\naccuracy = "best"', "needs.accuracy"),
    ]
    for text, fragment in bad:
        with pytest.raises(ScenarioError, match="<t>") as exc:
            parse_scenario(f'name = "x"\n{text}\n', "<t>")
        assert fragment in str(exc.value)


# --- levels against the full model (symmetric brake) ---------------------------------------


def _run(outputs, level=None, shoes=("left", "right"), name="symmetric"):
    s = load_scenario(name)
    return run_scenario(
        dataclasses.replace(s, needs=Needs(outputs=outputs, shoes=shoes, level=level))
    )


def test_contact_regime_model_within_one_percent_of_the_full_model(symmetric_run):
    """Issue 5 item 3: stop time and contact-regime mean pivot force within 1 %."""
    r = _run(("stop_time", "contact_regime_forces", "braking_torque"))
    assert r.plan.level.name == "contact_regime" and r.method == "contact_regime"
    full = symmetric_run.metrics
    assert r.stop_time_s == pytest.approx(full.stop_time_s, rel=0.01)
    for side in ("left", "right"):
        assert r.metrics.shoe(side).contact_regime_force_n == pytest.approx(
            full.shoe(side).contact_regime_force_n, rel=0.01
        )
        assert r.metrics.shoe(side).n_impacts == 0  # no impacts invented
    # only the asked signals are kept
    assert "left_angle_rad" not in r.samples.columns
    assert r.memory_bytes < symmetric_run.memory_bytes / 20


def test_contact_regime_braking_torque_matches_full_model_while_riding(symmetric_run):
    """In steady contact both models satisfy the same shoe balance; over the impacting
    regime the torque impulse (what decelerates the drum) must agree too."""
    r = _run(("braking_torque",), level="contact_regime")
    fb = symmetric_run.samples
    arm = {s: np.hypot(fb[f"{s}_contact_x_m"], fb[f"{s}_contact_y_m"]) for s in ("left", "right")}
    full_torque = sum(fb[f"{s}_friction_force_n"] * arm[s] for s in ("left", "right"))
    t_full, t_qs = fb.time_s, r.samples.time_s
    riding = (t_qs > 1.0) & (t_qs < 6.0)
    np.testing.assert_allclose(
        r.samples["braking_torque_n_m"][riding],
        np.interp(t_qs[riding], t_full, full_torque),
        rtol=1e-3,
    )
    # impulse up to 1 s: impacts average out to the quasi-static torque
    imp_full = np.trapezoid(full_torque[t_full <= 1.0], t_full[t_full <= 1.0])
    m = t_qs <= 1.0
    imp_qs = np.trapezoid(r.samples["braking_torque_n_m"][m], t_qs[m])
    assert imp_qs == pytest.approx(imp_full, rel=0.01)


def test_rigid_coupling_keeps_impacts_and_contact_forces(symmetric_run):
    """The drum speed reaches the shoes only through friction saturated at these speeds,
    so removing the torsional mode leaves the impacts and the riding forces unchanged."""
    r = _run(("impacts", "contact_regime_forces"))
    assert r.plan.level.name == "rigid" and r.stop_time_s is None  # stop not delivered
    full = symmetric_run.metrics
    for side in ("left", "right"):
        a, b = r.metrics.shoe(side), full.shoe(side)
        assert a.n_impacts == b.n_impacts
        np.testing.assert_allclose(a.onsets_s, b.onsets_s, rtol=1e-9)
        assert a.first_impact_peak_n == pytest.approx(b.first_impact_peak_n, rel=1e-9)
        assert a.contact_regime_force_n == pytest.approx(b.contact_regime_force_n, rel=1e-6)
    # ... but the rigid model locks at a measurably different instant (coupling unwinding
    # through the pinned drum before the lock), which is why it does not deliver it
    assert not math.isclose(r.model_stop_time_s, full.stop_time_s, rel_tol=1e-3)


def test_one_shoe_model_gives_that_shoes_impacts_exactly(symmetric_run):
    r = _run(("impacts",), shoes=("left",))
    assert r.plan.shoes == ("left",)
    assert all(not c.startswith("right_") for c in r.samples.columns)
    a, b = r.metrics.left, symmetric_run.metrics.left
    # Not bit-equal: the located scheme also cuts a step at the other shoe's contact
    # switches, so the two runs differ by RK4 truncation error (below the scheme's own
    # 1e-5 error against the reference at this step; measured 1.2e-8 of an onset time).
    np.testing.assert_allclose(a.onsets_s, b.onsets_s, rtol=1e-6)
    np.testing.assert_allclose(a.impact_peaks_n, b.impact_peaks_n, rtol=1e-6)
    assert a.period_s == pytest.approx(b.period_s, rel=1e-6)


def test_one_shoe_brake_stops_as_its_torque_predicts(symmetric_run):
    """A brake with only the left shoe: momentum I w0 is removed by the left shoe's torque
    alone, which is the same as in the two-shoe brake while the drum turns fast."""
    s = load_scenario("symmetric")
    setup = dataclasses.replace(
        s.setup, options=dataclasses.replace(s.setup.options, shoes=("left",))
    )
    one = run_scenario(
        dataclasses.replace(
            s,
            setup=setup,
            duration_s=25.0,
            needs=Needs(outputs=("stop_time", "braking_torque"), shoes=("left",)),
        )
    )
    assert one.stop_time_s is not None
    b = symmetric_run.samples
    d = s.setup.params.driveline
    arm = np.hypot(b["left_contact_x_m"], b["left_contact_y_m"])
    torque = b["left_friction_force_n"] * arm
    held = (b.time_s > 1.0) & (b.time_s < 6.0)
    t_hold = float(np.mean(torque[held]))
    early = b.time_s <= 1.0
    impulse_early = np.trapezoid(torque[early], b.time_s[early])
    momentum = (d.flywheel_inertia_kg_m2 + d.drum_inertia_kg_m2) * d.initial_speed_rad_s
    predicted = 1.0 + (momentum - impulse_early) / t_hold
    assert one.stop_time_s == pytest.approx(predicted, rel=0.01)


def test_contact_regime_refuses_the_reference_method():
    s = load_scenario("symmetric")
    sc = dataclasses.replace(s, needs=Needs(outputs=("stop_time",)))
    with pytest.raises(FidelityError, match="reference"):
        run_scenario(sc, method="reference")
