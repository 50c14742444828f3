"""The service brake's self-adjuster and the seized adjuster (model/adjuster.py): the
clearance at rest, the symptom through its cause (a later first contact, by the fluid the
extra travel takes through the line), the study brake's refusal, the energy books.

Expected values come from the documented mechanism and the parameters (the step, the
piston area, the line's resistance), never read off a run."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq

from brake_sim_ros.analysis.energy import energy_balance, line_pressure_pa
from brake_sim_ros.errors import ParameterError, ScenarioError
from brake_sim_ros.model import growth as growth_update
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.adjuster import takeup_m
from brake_sim_ros.model.assembly import indentation_at, pack
from brake_sim_ros.model.catalogue import KIND_BY_NAME, brake_kinds
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.growth_law import Growth
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.placement import place_shoe
from brake_sim_ros.model.service_parameters import SERVICE_RUNNING_CLEARANCE_M
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.stream.build import stepper_for

SERVICE = BrakeParameters.of_brake("service")
SPEC = SERVICE.service
STEP_M = SPEC.adjuster_step_m
LEFT = L.P_SHOE_BASE  # the left shoe's block in the packed vector
# the applied force: a step (1 ms ramp) at APPLY_S to FORCE_N a shoe, held
APPLY_S = 0.05
RAMP_S = 0.001
FORCE_N = 2000.0
SEVERITIES_MM = (0.0, 0.25, 0.5, 1.0)


def _gap_at_rest(defects: Defects) -> float:
    """The left lining's gap to the round drum at rest (m): minus the indentation of the
    packed shoe at its rest angle."""
    return -indentation_at(pack(SERVICE, defects), LEFT, 0.0)


@pytest.mark.parametrize("wear_mm", [0.3, 0.77, 1.0, 2.5])
def test_a_healthy_adjuster_holds_the_clearance_within_one_step_of_the_adjusted(wear_mm):
    """A lining worn from the start: the healthy adjuster has taken the wear up in whole
    steps, so the clearance at rest is the new lining's 0.3 mm plus less than one step
    (0.05 mm at the lining), not 0.3 mm + the wear; the lining's wear itself (its label,
    the contact's radius less the takeup) stays."""
    gap = _gap_at_rest(Defects(left=ShoeDefect(lining_wear_mm=wear_mm)))
    assert SERVICE_RUNNING_CLEARANCE_M - 1e-12 <= gap < SERVICE_RUNNING_CLEARANCE_M + STEP_M
    # the residual is the part of the wear short of a whole step (the ratchet's)
    residual = wear_mm * 1e-3 - STEP_M * math.floor(wear_mm * 1e-3 / STEP_M + 1e-9)
    assert gap - SERVICE_RUNNING_CLEARANCE_M == pytest.approx(residual, abs=1e-12)
    p = pack(SERVICE, Defects(left=ShoeDefect(lining_wear_mm=wear_mm)))
    assert p[L.P_LINING_BASE + L.LN_WEAR] == pytest.approx(wear_mm * 1e-3)


@pytest.mark.parametrize("wear_mm", [0.3, 1.0, 2.5])
def test_a_seized_adjuster_leaves_the_whole_wear_in_the_clearance(wear_mm):
    """Seized before any of the wear: the clearance at rest is 0.3 mm + the wear (as the
    lining without an adjuster, the study brake's), to 1e-9 m (rounding of the radius)."""
    defects = Defects(left=ShoeDefect(lining_wear_mm=wear_mm, adjuster_seized_mm=wear_mm))
    gap = _gap_at_rest(defects)
    assert gap == pytest.approx(SERVICE_RUNNING_CLEARANCE_M + wear_mm * 1e-3, abs=1e-9)
    # seized part way: the wear before it taken up in steps, the rest left open
    part = Defects(left=ShoeDefect(lining_wear_mm=wear_mm, adjuster_seized_mm=0.2))
    assert _gap_at_rest(part) == pytest.approx(
        SERVICE_RUNNING_CLEARANCE_M
        + 0.2e-3
        + (wear_mm - 0.2) * 1e-3
        - takeup_m((wear_mm - 0.2) * 1e-3, 0.0, STEP_M),
        abs=1e-9,
    )


@pytest.mark.parametrize(
    ("growth", "taken_mm"),
    [
        (Growth(law="linear", rate_per_s=2.0), 0.0),  # from 0 at the start: nothing yet
        (Growth(law="exponential", doubling_time_s=0.5, start=0.52), 0.5),  # 0.52 at t = 0
        (Growth(law="friction_work", wear_rate_mm_per_mj=1.0), 0.0),  # a state from 0
    ],
)
def test_a_wear_that_grows_in_the_run_starts_taken_up_as_it_was_at_the_start(growth, taken_mm):
    """When the run starts the adjuster has taken up the wear the run starts with, in
    whole steps; the growth alone (without the ratchet's steps within the run, which the
    stepper takes at applications: tests/model/test_adjuster_ratchet.py) opens the
    clearance to the final wear less that takeup. Its ratchet is packed to step within the
    run (its step and free play)."""
    defects = Defects(
        left=ShoeDefect(lining_wear_mm=1.0), growth=(("lining_wear", "left", growth),)
    )
    p = pack(SERVICE, defects)
    assert p[L.P_ADJUSTER_STEP] == STEP_M and p[L.P_ADJUSTER_STEP + 1] == 0.0
    assert p[L.P_ADJUSTER_FREE_PLAY] == SERVICE.shoe.running_clearance_m
    unworn = SERVICE.shoe.drum_radius_m - SERVICE_RUNNING_CLEARANCE_M
    assert p[L.P_LINING_BASE + L.LN_RADIUS] == pytest.approx(unworn + taken_mm * 1e-3, abs=1e-12)
    if growth.follows_time:  # the radius the growth writes at the end: final wear applied
        pw = growth_update.working_copy(p)
        growth_update.apply(p, pw, 10.0, np.zeros(L.N_STATE_WEAR), growth_update.ALL_ENTRIES)
        radius = pw[L.P_SHOE_BASE + L.S_LINING_RADIUS]
        assert radius == pytest.approx(unworn + taken_mm * 1e-3 - 1e-3, abs=1e-12)


def test_the_ratchet_takes_up_only_whole_steps():
    """The takeup is a whole number of steps, never more than the wear, and nothing for a
    wear short of one step or for wear the adjuster failed to follow."""
    assert takeup_m(0.9 * STEP_M, 0.0, STEP_M) == 0.0
    assert takeup_m(STEP_M, 0.0, STEP_M) == STEP_M
    assert takeup_m(3.5 * STEP_M, 0.0, STEP_M) == pytest.approx(3 * STEP_M)
    assert takeup_m(3.5 * STEP_M, 1.0 * STEP_M, STEP_M) == pytest.approx(2 * STEP_M)
    assert takeup_m(1e-3, 2e-3, STEP_M) == 0.0
    for wear in np.linspace(0.0, 5e-3, 101):
        taken = takeup_m(float(wear), 0.0, STEP_M)
        assert 0.0 <= wear - taken < STEP_M + 1e-15


def test_the_seized_adjuster_is_the_service_brakes_only():
    """The study brake has no adjuster: a seized one is refused in one line, by the
    assembly and by a scenario; the study brake's kinds leave it out, the service's carry
    it; a healthy severity packs the study brake as before."""
    study = BrakeParameters()
    with pytest.raises(ParameterError, match=r"adjuster_seized_mm=0\.5 is invalid on the study"):
        pack(study, Defects(left=ShoeDefect(adjuster_seized_mm=0.5)))
    text = 'name = "s"\n[defects.right]\nadjuster_seized_mm = 0.5\n'
    with pytest.raises(ScenarioError, match=r"\[defects.right\].*service") as info:
        parse_scenario(text)
    assert "\n" not in str(info.value)
    assert "adjuster_seized" not in {k.name for k in brake_kinds(False)}
    assert "adjuster_seized" in {k.name for k in brake_kinds(True)}
    assert KIND_BY_NAME["adjuster_seized"].service_only
    wear = Defects(left=ShoeDefect(lining_wear_mm=1.0))
    worn_gap = -indentation_at(pack(study, wear), LEFT, 0.0)
    assert worn_gap == pytest.approx(study.shoe.running_clearance_m + 1e-3, abs=1e-12)


# --- the symptom through its cause: a run ----------------------------------------------


def _application() -> str:
    times = [0.0, APPLY_S, APPLY_S + RAMP_S, 0.25]
    forces = [0.0, 0.0, FORCE_N, FORCE_N]
    knots = f"times_s = {times}\nforces_n = {forces}\n"
    return (
        'name = "application"\nbrake = "service"\nduration_s = 0.25\n'
        '[actuation]\nprofile = "piecewise"\n'
        f"[actuation.left]\n{knots}[actuation.right]\n{knots}"
    )


@pytest.fixture(scope="module")
def runs():
    """One application per seized severity (left shoe), healthy first."""
    out = {}
    for mm in SEVERITIES_MM:
        scenario = parse_scenario(_application())
        scenario = scenario.with_defects(Defects(left=ShoeDefect(adjuster_seized_mm=mm)))
        stepper = stepper_for(scenario)
        out[mm] = (scenario, stepper, stepper.run(scenario.duration_s))
    return out


def _first_contact_s(block) -> float:
    t = block.time_s
    touching = np.flatnonzero(block["left_normal_force_n"] > 0.0)
    return float(t[touching[0]])


def _tip_travel_to_contact(defects: Defects) -> float:
    """The left tip's outward travel (m) from rest to the lining's first touch of the round
    drum: the shoe angle where the packed shoe's indentation crosses 0, turned into the
    tip's travel along the cylinder axis from the placement."""
    p = pack(SERVICE, defects)
    theta = brentq(lambda th: indentation_at(p, LEFT, th), 0.0, 0.2, xtol=1e-14)
    s = place_shoe(SERVICE, "left", ShoeDefect())
    pivot, tip, axis = np.array(s.pivot_xy_m), np.array(s.tip_xy_m), np.array(s.actuation_dir)
    d = tip - pivot
    c, sn = math.cos(s.sign * theta), math.sin(s.sign * theta)
    turned = np.array([c * d[0] - sn * d[1], sn * d[0] + c * d[1]])
    return float((turned - d) @ axis)


def _left_tip(block, row: int) -> tuple[float, float, float]:
    """The left tip's travel (m), outward speed (m/s) and mass seen along the cylinder
    axis (kg, ``I / (du/dtheta)^2``) at ``row`` of ``block``, from the placement."""
    s = place_shoe(SERVICE, "left", ShoeDefect())
    pivot, tip, axis = np.array(s.pivot_xy_m), np.array(s.tip_xy_m), np.array(s.actuation_dir)
    d = tip - pivot
    phi = s.sign * float(block["left_angle_rad"][row])
    c, sn = math.cos(phi), math.sin(phi)
    tx, ty = c * d[0] - sn * d[1], sn * d[0] + c * d[1]
    travel = float((np.array([tx, ty]) - d) @ axis)
    arm = s.sign * (tx * axis[1] - ty * axis[0])
    speed = arm * float(block["left_speed_rad_s"][row])
    return travel, speed, s.inertia_about_pivot_kg_m2 / arm**2


def _hand_arrival_s(start: tuple[float, float, float, float], target: float) -> float:
    """When the left tip reaches ``target`` (m) after ``start`` = (travel m, speed m/s,
    line pressure Pa, tip mass kg), its piston alone taking the fluid (the right shoe on
    the drum): the documented circuit ``C p' = (p_s - p) / R - A u'`` with the tip's
    ``m u'' = A p - P - k u`` (no stop, no drum), a linear system solved in closed form
    (matrix exponential) at the held source pressure ``p_s``."""
    u, v, pressure, mass = start
    area, c = SPEC.piston_area_m2, SPEC.line_compliance_m3_per_pa
    r, k = SPEC.line_resistance_pa_s_per_m3, SPEC.return_spring_rate_n_per_m
    source = FORCE_N / area
    # x = (u, v, p, 1): x' = M x
    m = np.zeros((4, 4))
    m[0, 1] = 1.0
    m[1, 0], m[1, 2], m[1, 3] = -k / mass, area / mass, -SPEC.return_spring_preload_n / mass
    m[2, 1], m[2, 2], m[2, 3] = -area / c, -1.0 / (r * c), source / (r * c)
    x0 = np.array([u, v, pressure, 1.0])
    step = 1e-6
    grow = expm(m * step)
    x, t = x0, 0.0
    while x[0] < target:
        x, t = grow @ x, t + step
        assert t < 0.05, "the tip never arrives"
    return t


def test_the_seized_adjuster_delays_first_contact_by_the_fluid_its_gap_takes(runs):
    """The extra gap makes the tip travel ``du`` further before the lining touches, and its
    piston takes ``A du`` more fluid, which comes through the line's ``R`` into its ``C``
    at the applied source pressure: the first contact comes later than the healthy
    shoe's. Both runs are the same until the healthy shoes touch (together); from there
    the hand model (:func:`_hand_arrival_s`) carries the seized shoe's tip to its extra
    travel. Not the flow-limited ``A du R / p_s`` alone: the tip's 0.6 kg on the circuit's
    compliance is a mode of ``A / sqrt(m C)`` = 408 rad/s (65 Hz, a quarter period of 3.9
    ms, as long as the delays), which R (``1 / (2 R C)`` = 17 1/s) hardly damps: the
    shoe first lags the flow, then outruns it on the fluid the compliance gives back.
    Within 3 % and one sample: the hand model holds the right piston still on its drum
    (its contact yields about 1 % of ``C``) and the tip's lever at its value at the
    healthy touch."""
    healthy_block = runs[0.0][2]
    dt = runs[0.0][0].sample_period_s
    touch = _first_contact_s(healthy_block)
    row = int(np.flatnonzero(healthy_block.time_s >= touch)[0])
    assert healthy_block["right_normal_force_n"][row] > 0.0  # both touch together
    u, v, mass = _left_tip(healthy_block, row)
    pressure = float(line_pressure_pa(healthy_block, runs[0.0][1].packed_parameters)[row])
    u0 = _tip_travel_to_contact(Defects())
    for mm in SEVERITIES_MM[1:]:
        du = _tip_travel_to_contact(Defects(left=ShoeDefect(adjuster_seized_mm=mm))) - u0
        assert du > 1.5 * mm * 1e-3  # the tip's lever on the lining: about 2
        hand = _hand_arrival_s((u, v, pressure, mass), u0 + du)
        delay = _first_contact_s(runs[mm][2]) - touch
        assert abs(delay - hand) <= 0.03 * hand + dt, (mm, delay, hand)


def test_the_symptoms_grow_monotonically_with_the_severity(runs):
    """The larger the wear left in the clearance, the later the first contact, the later
    the line pressure reaches half its source, the harder the first contact (the shoe
    arrives faster and later into a higher pressure: the largest normal force within
    2 ms of the touch) and the more fluid the circuit takes (the piston's travel at the
    touch)."""
    contact, half, hit = [], [], []
    for mm in SEVERITIES_MM:
        _scenario, stepper, block = runs[mm]
        t = block.time_s
        first = _first_contact_s(block)
        contact.append(first)
        pressure = line_pressure_pa(block, stepper.packed_parameters)
        half.append(float(t[np.flatnonzero(pressure >= 0.5 * FORCE_N / SPEC.piston_area_m2)[0]]))
        w = (t >= first) & (t < first + 0.002)
        hit.append(float(block["left_normal_force_n"][w].max()))
    assert all(np.diff(contact) > 0.0), contact
    assert all(np.diff(half) > 0.0), half
    assert all(np.diff(hit) > 0.0), hit


def test_the_energy_books_close_with_a_seized_adjuster(runs):
    """The shoe's springs, stop, circuit and contact books close to 1e-6 of the turnover
    with the largest severity, as the healthy brake's (tests/model/test_service_brake.py)."""
    scenario, stepper, block = runs[SEVERITIES_MM[-1]]
    books = energy_balance(block, scenario.setup.params, packed=stepper.packed_parameters)
    assert abs(books.residual_j) < 1e-6 * books.turnover_j
