"""Lining wear (catalogue ``lining_wear``): a worn lining opens the gap to the drum, and a
lining can wear with its own friction work (growth ``friction_work``, Archard-like)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from brake_sim_ros.analysis.energy import energy_balance
from brake_sim_ros.errors import FidelityError, ParameterError, ScenarioError
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import contact_arms, pack
from brake_sim_ros.model.catalogue import (
    DEFAULT_WEAR_RATE_MM_PER_MJ,
    KIND_BY_NAME,
    LINING_THICKNESS_MM,
    Growth,
    label_column,
)
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.fidelity import plan
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.stream import DEFECTS
from brake_sim_ros.stream.build import stepper_for
from brake_sim_ros.stream.ground_truth import recorded_wear
from brake_sim_ros.stream.offline import StreamSettings, offline_messages

WEAR = KIND_BY_NAME["lining_wear"]
BRAKING = 'name = "wear"\nduration_s = 0.3\n'


def _first_contact(block, side: str = "left") -> tuple[float, float]:
    """(shoe angle rad, actuation force N) where the lining first reaches the drum,
    interpolated linearly to indentation 0 between the samples around it."""
    eps = block[f"{side}_indentation_m"]
    i = int(np.flatnonzero(eps > 0.0)[0])
    f = -eps[i - 1] / (eps[i] - eps[i - 1])
    angle = block[f"{side}_angle_rad"]
    force = block[f"{side}_actuation_force_n"]
    return (
        float(angle[i - 1] + f * (angle[i] - angle[i - 1])),
        float(force[i - 1] + f * (force[i] - force[i - 1])),
    )


def _run(text: str, defects: Defects, duration_s: float | None = None):
    sc = parse_scenario(text).with_defects(defects)
    return stepper_for(sc).run(sc.duration_s if duration_s is None else duration_s)


def test_a_worn_lining_meets_the_drum_later_by_the_gap_it_opened():
    """Wear ``w`` moves the lining surface in by ``w``: the shoe must turn further by
    ``w / d`` (``d`` the normal force's arm about the pin at first contact: the rate at
    which the contact point moves toward the drum per radian). Before it touches, the shoe
    is free under the ramp ``F = k (t - t_0)``, so its angle grows as ``(t - t_0)^3``: the
    force at first contact grows as the cube root of the angle turned,
    ``F_w = F_0 ((theta_0 + w / d) / theta_0)^(1/3)``. The right shoe is untouched."""
    healthy = _run(BRAKING, Defects())
    theta0, force0 = _first_contact(healthy)
    params = parse_scenario(BRAKING).setup.params
    d = contact_arms(pack(params, Defects()), L.P_SHOE_BASE, 0.0).normal_arm_m
    forces = [force0]
    for wear_mm in (1.0, 2.0, 3.4):
        worn = _run(BRAKING, Defects(left=ShoeDefect(lining_wear_mm=wear_mm)))
        theta, force = _first_contact(worn)
        turn = wear_mm * 1e-3 / d
        assert theta - theta0 == pytest.approx(turn, rel=1e-3)
        assert force == pytest.approx(force0 * ((theta0 + turn) / theta0) ** (1 / 3), rel=1e-3)
        forces.append(force)
        assert _first_contact(worn, "right") == _first_contact(healthy, "right")
        assert np.all(worn["left_lining_wear_m"] == wear_mm * 1e-3)
    assert forces == sorted(forces) and forces[-1] > 1.2 * forces[0]


def _wearing(
    k_w: float,
    final_mm: float = 5.0,
    onset_s: float = 0.0,
    duration: float = 1.2,
    brake: str = "study",
):
    text = f"""name = "wearing"
brake = "{brake}"
duration_s = {duration}
[defects.left.lining_wear_mm]
value = {final_mm}
growth = "friction_work"
wear_rate_mm_per_mj = {k_w}
onset_s = {onset_s}
[defects.right.lining_wear_mm]
value = {final_mm}
growth = "friction_work"
wear_rate_mm_per_mj = {k_w}
onset_s = {onset_s}
"""
    sc = parse_scenario(text)
    return sc, stepper_for(sc).run(sc.duration_s)


def _shoe_work(block, side: str) -> np.ndarray:
    """The shoe's friction work so far, J: its friction power (friction force times
    sliding speed) integrated over the samples by the trapezoid rule."""
    power = block[f"{side}_friction_force_n"] * block[f"{side}_sliding_speed_m_s"]
    dt = np.diff(block.time_s)
    return np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * dt)])


def test_wear_grows_with_each_shoes_friction_work_and_the_leading_shoe_wears_more():
    """``dw/dt = k_w P_f`` per shoe. Both wears together are ``k_w`` times the brake's
    friction work, which the model integrates on its own (the energy books' quadrature):
    equal to rounding. Each shoe's wear follows its own work (friction power from the
    samples, trapezoid: within 0.1 %), and the leading (left) shoe, self-energised, does
    about twice the trailing shoe's work, so it wears twice as fast."""
    k_w = 20.0  # mm/MJ: an accelerated test, to see the wear in one stop
    _sc, run = _wearing(k_w)
    wear = {s: run[f"{s}_lining_wear_m"] * 1e3 for s in ("left", "right")}  # mm
    total = run["friction_work_j"] * 1e-6 * k_w
    np.testing.assert_allclose(wear["left"] + wear["right"], total, rtol=1e-9, atol=1e-15)
    for side in ("left", "right"):
        expected = k_w * 1e-6 * _shoe_work(run, side)
        late = run.time_s > 0.5
        np.testing.assert_allclose(wear[side][late], expected[late], rtol=1e-3)
    ratio = wear["left"][-1] / wear["right"][-1]
    work_ratio = _shoe_work(run, "left")[-1] / _shoe_work(run, "right")[-1]
    assert ratio == pytest.approx(work_ratio, rel=1e-3)
    assert 1.5 < ratio < 3.0
    assert np.all(np.diff(wear["left"]) >= 0.0)


def test_wear_starts_at_its_onset_and_is_held_at_its_final_value():
    k_w, final = 50.0, 0.2
    sc, run = _wearing(k_w, final_mm=final, onset_s=0.6)
    left = run["left_lining_wear_m"] * 1e3
    assert np.all(left[run.time_s <= 0.6] == 0.0)
    after = (run.time_s > 0.6) & (left < final)
    work = _shoe_work(run, "left")
    at_onset = work[np.searchsorted(run.time_s, 0.6)]
    np.testing.assert_allclose(left[after], k_w * 1e-6 * (work[after] - at_onset), rtol=1e-3)
    assert left[-1] == final and run["right_lining_wear_m"][-1] * 1e3 == pytest.approx(final)
    labels = sc.setup.defects.label_series(run.time_s, recorded_wear(run))
    column = labels[label_column(WEAR, "left")]
    assert column[-1] == final  # exactly the final value once reached
    np.testing.assert_array_equal(column[left < final], left[left < final])


def test_the_ground_truth_carries_the_models_wear_at_each_published_sample():
    """DefectState messages of a wearing run (offline stream, as the node publishes it)
    carry the wear the model recorded at their sample, not one computed from time."""
    sc, run = _wearing(100.0, duration=1.5)
    settings = StreamSettings(publish_measured=False)
    states = [
        (ns, msg) for topic, msg, ns in offline_messages(sc, settings=settings) if topic is DEFECTS
    ]
    assert len(states) > 2
    period = sc.sample_period_s
    for ns, msg in states[1:]:
        row = round(ns * 1e-9 / period)
        by_loc = {d.location: d.severity for d in msg.defects if d.kind == "lining_wear"}
        assert by_loc["left"] == pytest.approx(run["left_lining_wear_m"][row] * 1e3, rel=1e-12)
        growth = next(d for d in msg.defects if d.kind == "lining_wear")
        assert growth.growth == "friction_work" and growth.growth_rate == 100.0


@pytest.mark.parametrize(
    ("defects", "message"),
    [
        (
            "[defects.left]\nlining_wear_mm = 5.5",
            "lining_wear_mm=5.5 is invalid: allowed 0 to 5 (a new lining is 5 mm thick",
        ),
        (
            "[defects.left]\nlining_wear_mm = -0.1",
            "lining_wear_mm=-0.1 is invalid: allowed 0 to 5",
        ),
        (
            '[defects.left]\nfriction_change_pct = {value = -20, growth = "friction_work"}',
            "growth 'friction_work' is invalid: allowed only for lining_wear_mm",
        ),
        (
            '[defects.left]\nlining_wear_mm = {value = 1, growth = "linear", rate_per_s = 1,'
            " wear_rate_mm_per_mj = 3}",
            "wear_rate_mm_per_mj' = 3 is invalid: allowed a value only with growth",
        ),
        (
            '[defects.left]\nlining_wear_mm = {value = 1, growth = "friction_work",'
            " wear_rate_mm_per_mj = 0}",
            "wear_rate_mm_per_mj' = 0.0 is invalid: allowed a number > 0 and <= 1000",
        ),
    ],
)
def test_an_impossible_wear_is_refused_in_one_line(defects, message):
    with pytest.raises((ScenarioError, ParameterError)) as info:
        parse_scenario(f'name = "bad"\n{defects}\n', "bad.toml")
    assert message in str(info.value)
    assert "\n" not in str(info.value)


def test_the_default_wear_rate_and_the_limits_are_the_catalogues():
    g = parse_scenario(
        'name = "w"\n[defects.left]\nlining_wear_mm = {value = 1, growth = "friction_work"}\n'
    ).setup.defects.growth_of("lining_wear", "left")
    assert g == Growth(law="friction_work", wear_rate_mm_per_mj=DEFAULT_WEAR_RATE_MM_PER_MJ)
    assert WEAR.maximum == LINING_THICKNESS_MM and 0 < WEAR.service_limit < WEAR.maximum
    with pytest.raises(ParameterError, match=re.escape("allowed 0 to 5 (a new lining")):
        ShoeDefect(lining_wear_mm=6.0)


def test_growing_wear_needs_an_impact_level_and_static_wear_runs_on_every_level():
    grow = (
        'name = "w"\n[needs]\noutputs = ["stop_time"]\nlevel = "contact_regime"\n'
        '[defects.left]\nlining_wear_mm = {value = 1, growth = "friction_work"}\n'
    )
    with pytest.raises((FidelityError, ScenarioError), match="changing during the run"):
        parse_scenario(grow, "w.toml")
    static = 'name = "w"\n[needs]\noutputs = ["stop_time"]\n[defects.left]\nlining_wear_mm = 1\n'
    assert plan(parse_scenario(static).needs).level.name == "contact_regime"


@pytest.mark.parametrize("brake", ["study", "service"])
def test_the_worn_layer_takes_its_strain_energy_and_the_energy_books_close(brake):
    """As a lining wears its surface recedes, and the contact's elastic energy
    ``k eps^2 / 2`` falls by ``k eps dw`` with no motion: the worn layer leaves with the
    strain it held. The model books ``F_el dw/dt`` (``contact.wear_loss``) in
    ``contact_loss_j``. Over a stop in which the linings wear 1.8-2.1 mm, that strain,
    ``sum k max(eps, 0) dw`` from the samples (trapezoid), is 6.4-8.5 J; the books close
    to under 1e-4 of it (measured 2.3e-5 and 4.0e-5: the geometry follows the wear at
    each step's start, the quadrature continuously). Before, they were short by all of it
    (downhill_wear's residual was 6.1 J)."""
    scenario, run = _wearing(k_w=200.0, duration=1.0, brake=brake)
    params = scenario.setup.params
    books = energy_balance(run, params, packed=stepper_for(scenario).packed_parameters)
    k = params.contact_stiffness_n_per_m
    taken = 0.0
    for side in ("left", "right"):
        force = k * np.maximum(run[f"{side}_indentation_m"], 0.0)
        worn = np.diff(run[f"{side}_lining_wear_m"])
        taken += float(np.sum(0.5 * (force[1:] + force[:-1]) * worn))
    assert taken > 5.0, (taken, books)
    assert abs(books.residual_j) < 1e-4 * taken, (taken, books)
