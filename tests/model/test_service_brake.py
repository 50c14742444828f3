"""The service brake (``brake = "service"``): return springs holding each shoe on its rest
stop, the service running clearance, a weakened spring acting through the spring. Each
figure a test expects is derived by hand from the parameters (model/service.py's laws,
written again here in numpy from the documented formulas), never read off a run."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from brake_sim_ros.analysis.energy import energy_balance
from brake_sim_ros.errors import ScenarioError
from brake_sim_ros.model.assembly import contact_arms
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.placement import place_shoe
from brake_sim_ros.model.service_parameters import (
    SERVICE_RUNNING_CLEARANCE_M,
    ServiceBrakeParameters,
)
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.stream.build import stepper_for

SIDES = ("left", "right")
# each application ramps 0 -> 1000 N over 50 ms from here; 0.6 s apart, so that the line
# has come back to its residual pressure (8 R C after the shoe lands on its stop) before
# the next: the springs return the shoes by pushing the fluid back through the line
APPLY_S = (0.10, 0.70, 1.30)
HOLD_S = 0.10  # held this long after the ramp, then released to 0 in RELEASE_RAMP_S
RELEASE_RAMP_S = 0.02
FORCE_N = 1000.0


# the service brake's lining contact: the point contact (its default) or the lining over its
# arc (``distributed_lining``, model/lining.py); the release and its hand figures hold for both
CONTACTS = ("point", "arc")
ARC = "[parameters.service]\ndistributed_lining = true\n"


def _three_applications(contact: str = "point") -> str:
    times, forces = [0.0], [0.0]
    for t0 in APPLY_S:
        t_full = t0 + 0.05
        t_off = t_full + HOLD_S
        times += [t0, t_full, t_off, t_off + RELEASE_RAMP_S]
        forces += [0.0, FORCE_N, FORCE_N, 0.0]
    knots = f"times_s = {times}\nforces_n = {forces}\n"
    return (
        'name = "three_applications"\nbrake = "service"\nduration_s = 1.9\n'
        '[actuation]\nprofile = "piecewise"\n'
        f"[actuation.left]\n{knots}[actuation.right]\n{knots}" + (ARC if contact == "arc" else "")
    )


IDLE = 'name = "idle"\nbrake = "service"\nduration_s = 1.5\n[actuation]\npeak_force_n = 0.0\n'


def _run(text: str, defects: Defects | None = None):
    scenario = parse_scenario(text)
    if defects is not None:
        scenario = scenario.with_defects(defects)
    stepper = stepper_for(scenario)
    return scenario, stepper, stepper.run(scenario.duration_s)


@pytest.fixture(scope="module", params=CONTACTS)
def three(request):
    return _run(_three_applications(request.param))


@pytest.fixture(scope="module")
def weak_three(three):
    """The three applications with the left spring weakened by 50 % (below its hold point:
    it still holds the shoe on its stop), on ``three``'s contact."""
    return _run(
        _three_applications(_contact(three[0])),
        Defects(left=ShoeDefect(return_spring_weakening_pct=50.0)),
    )


def _contact(scenario) -> str:
    """The scenario's lining contact (:data:`CONTACTS`)."""
    return "arc" if scenario.setup.params.service.distributed_lining else "point"


# --- the geometry and laws, from the documentation (not from the kernel) ----------------


class Tip:
    """A shoe's tip on its cylinder axis: its outward travel ``u`` (m) and arm ``du/dtheta``
    (m/rad) as the shoe turns about its pivot, from the assembled placement."""

    def __init__(self, params: BrakeParameters, side: str, defect: ShoeDefect) -> None:
        s = place_shoe(params, side, defect)
        self.sign = s.sign
        self.pivot = np.array(s.pivot_xy_m)
        self.tip = np.array(s.tip_xy_m)
        self.axis = np.array(s.actuation_dir)
        self.inertia = s.inertia_about_pivot_kg_m2

    def at(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Tip travel (m), arm (m/rad) and the turned tip's offset from the pivot (2, n)."""
        phi = self.sign * np.asarray(theta, float)
        c, sn = np.cos(phi), np.sin(phi)
        d = self.tip - self.pivot
        tx, ty = c * d[0] - sn * d[1], sn * d[0] + c * d[1]
        ex, ey = self.axis
        travel = (tx - d[0]) * ex + (ty - d[1]) * ey
        arm = self.sign * (tx * ey - ty * ex)
        return travel, arm, np.array([tx, ty])


def _spec() -> ServiceBrakeParameters:
    return ServiceBrakeParameters()


def _stop_travel(rest: float) -> float:
    """Where the healthy shoe's stop engages: it carries preload - residual at rest."""
    spec = _spec()
    return (
        rest + (spec.return_spring_preload_n - spec.residual_force_n) / spec.stop_stiffness_n_per_m
    )


def _tip_mass(tip: Tip, theta: float = 0.0) -> float:
    """The shoe's inertia seen at the tip along the cylinder axis: I / (du/dtheta)^2, kg."""
    _u, arm, _ = tip.at(np.array([theta]))
    return tip.inertia / float(arm[0]) ** 2


def _leave_window(cylinder: float, soft_tip_n_per_m: float) -> tuple[float, float]:
    """Hand bounds on the instant (s after the release starts) both shoes leave the drum
    together, when the line pressure on the piston has fallen to ``cylinder`` N (the
    spring's pull there). The release ramps the source from ``FORCE_N`` to the residual
    force in ``RELEASE_RAMP_S`` (clamped there); the pressure follows it through the
    circuit's first-order lag ``R C`` (exact for a piecewise-linear source, as
    actuation.shaped's lag). Earliest: no fluid from the tips; latest: the tips' contacts
    relaxing push fluid back, a compliance of at most ``2 A^2 / k_tip`` besides ``C``
    (``soft_tip_n_per_m``: the softer shoe's contact stiffness seen at its tip)."""
    spec = _spec()
    residual = spec.residual_force_n
    area, c = spec.piston_area_m2, spec.line_compliance_m3_per_pa
    rho = FORCE_N / RELEASE_RAMP_S
    ramp = (FORCE_N - residual) / rho
    bounds = []
    for tau in (
        spec.line_time_constant_s,
        spec.line_time_constant_s * (1.0 + 2.0 * area**2 / (c * soft_tip_n_per_m)),
    ):
        lagged = FORCE_N - rho * (ramp - tau * (1.0 - math.exp(-ramp / tau)))
        bounds.append(ramp + tau * math.log((lagged - residual) / (cylinder - residual)))
    return bounds[0], bounds[1]


def _flight(spring: float, preload: float, rate: float, tips: int) -> float:
    """Hand flight from the drum to the stop, s: the spring pushes the fluid back through
    the line, the tip's inertia left out (:func:`_inertia_time`). With the pistons' force
    ``A p`` equal to the spring's ``F_s = preload + rate u`` at every instant and ``tips``
    tips in flight together (the same spring each), the volume balance ``C p' = (p_r - p)
    / R - tips A u'`` gives ``u' = -(F_s - F_r) / (R (C k + tips A^2))``: ``F_s - F_r`` falls
    exponentially with ``R (C + tips A^2 / k)``, from ``spring - F_r`` at the drum (the
    spring's force at the tip's travel where the lining leaves: the hand's state is the
    travel; the piston's force differs from it there by the tip's inertial force, a tenth
    of a newton that moves the logarithm by 1-3 %) to ``preload + rate (P - F_r) / k_st -
    F_r`` where the stop engages."""
    spec = _spec()
    residual = spec.residual_force_n
    tau = spec.line_resistance_pa_s_per_m3 * (
        spec.line_compliance_m3_per_pa + tips * spec.piston_area_m2**2 / rate
    )
    at_stop = preload + rate * (
        (spec.return_spring_preload_n - residual) / spec.stop_stiffness_n_per_m
    )
    return tau * math.log((spring - residual) / (at_stop - residual))


def _soft_tip(scenario) -> float:
    """The point contact's stiffness seen at the leading shoe's tip, N/m: ``k_c d (d - mu
    h) / q^2`` (its self-servo ``d - mu h`` makes it the softer shoe). The lining over its
    arc is far stiffer (tests/model/test_lining.py: 17 times radially), so that it pushes
    back less fluid and this is a late bound for it too."""
    params = scenario.setup.params
    arms = contact_arms(stepper_for(scenario).packed_parameters, 12, 0.0)
    d, h, q = arms.normal_arm_m, arms.friction_arm_m, arms.actuation_arm_m
    mu = params.friction.coefficient
    return params.contact_stiffness_n_per_m * d * (d - mu * h) / q**2


def _inertia_time(mass: float) -> float:
    """The time in which a tip of ``mass`` (kg, :func:`_tip_mass`) takes the flow's speed
    through the line, ``m / (A^2 R)`` (0.2 ms), s: how far its start from the speed it has
    where the lining leaves can move its flight from the hand one, either way."""
    spec = _spec()
    return mass / (spec.piston_area_m2**2 * spec.line_resistance_pa_s_per_m3)


# besides that, the hand flight leaves out the fluid the other shoe's contact still pushes
# while it unloads: at most 2 % longer
FLIGHT_ALLOWANCE = 1.02


# --- the tests ---------------------------------------------------------------------------


def test_the_service_brake_has_its_clearance_and_springs_and_study_stays_default():
    study = parse_scenario('name = "s"\n').setup.params
    assert study == BrakeParameters() and study.brake == "study" and study.service is None
    assert (
        parse_scenario('name = "s"\nbrake = "study"\n').setup
        == parse_scenario('name = "s"\n').setup
    )
    service = parse_scenario('name = "s"\nbrake = "service"\n').setup.params
    assert service.brake == "service"
    assert service.shoe.running_clearance_m == SERVICE_RUNNING_CLEARANCE_M == 0.0003
    assert study.shoe.running_clearance_m == 0.00363
    # a scenario's own parameters still override the brake's defaults
    text = 'name = "s"\nbrake = "service"\n[parameters.shoe]\nrunning_clearance_m = 0.0005\n'
    assert parse_scenario(text).setup.params.shoe.running_clearance_m == 0.0005
    assert parse_scenario(text).setup.params.service == ServiceBrakeParameters()


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ('name = "s"\nbrake = "parking"\n', "key 'brake' = 'parking' is invalid: allowed one of"),
        ('name = "s"\nbrake = 1\n', "key 'brake' = 1 is invalid: allowed a string"),
        (
            'name = "s"\nbrake = "service"\n[needs]\noutputs = ["stop_time"]\n',
            'no [needs] with brake = "service"',
        ),
    ],
)
def test_a_bad_brake_choice_is_refused_in_one_line(text, words):
    with pytest.raises(ScenarioError) as caught:
        parse_scenario(text)
    message = str(caught.value)
    assert words in message and "\n" not in message


def test_a_healthy_shoe_rests_on_its_stop_without_moving():
    """No actuation: the spring holds each shoe on its stop against the residual force; it
    stays at its rest angle (the stop carries preload - residual there), no friction."""
    _scenario, _stepper, block = _run(IDLE)
    for side in SIDES:
        assert np.all(block[f"{side}_normal_force_n"] == 0.0)
        assert np.abs(block[f"{side}_angle_rad"]).max() < 1e-12
        assert np.all(block[f"{side}_actuation_force_n"] == _spec().residual_force_n)


def _flights(block, params: BrakeParameters, side: str, defect: ShoeDefect):
    """Per release: (instant the lining leaves the drum s, the tip's travel to its stop
    then m, the cylinder force then N, the spring's force then N (``defect``'s spring),
    instant the shoe first presses its stop s, instant from which it presses it at every
    sample until the next application s)."""
    tip = Tip(params, side, defect)
    theta = block[f"{side}_angle_rad"]
    travel, _arm, _ = tip.at(theta)
    kept = 1.0 - defect.return_spring_weakening_pct / 100.0
    spec = params.service
    spring = kept * (spec.return_spring_preload_n + spec.return_spring_rate_n_per_m * travel)
    rest = float(tip.at(np.array([math.radians(defect.initial_angle_deg)]))[0][0])
    on_stop = travel < _stop_travel(rest)
    touching = block[f"{side}_normal_force_n"] > 0.0
    t = block.time_s
    out = []
    for k, t0 in enumerate(APPLY_S):
        release = t0 + 0.05 + HOLD_S
        end = APPLY_S[k + 1] if k + 1 < len(APPLY_S) else t[-1]
        window = np.flatnonzero((t >= release) & (t < end))
        leave = window[np.flatnonzero(~touching[window])[0]]
        land = window[np.flatnonzero(on_stop[window])[0]]
        off = window[~on_stop[window]]
        settled = (off[-1] + 1) if off.size else window[0]
        cylinder = float(block[f"{side}_actuation_force_n"][leave])
        gap = float(travel[leave] - _stop_travel(rest))
        out.append((t[leave], gap, cylinder, float(spring[leave]), t[land], t[settled]))
    return out, tip


def _settle_bound(mass: float, travel: float, flight: float) -> float:
    """Hand bound on the time from leaving the drum to resting on the stop for good, s:
    the flight, then the bounces. The shoe lands at most at ``v = sqrt(2 a_max travel)``
    (the strongest push, preload + rate travel - residual); the stop returns ``e v``
    (``e = exp(-zeta pi / sqrt(1 - zeta^2))``, ``zeta`` its damping ratio on the tip's
    mass); each flight under at least ``preload - residual`` takes ``2 e^n v / a_min``
    (their sum ``2 e v / (a_min (1 - e))``) and each stay on the stop half its period,
    counted for the bounces until the flights are shorter than one sample."""
    spec = _spec()
    a_max = (
        spec.return_spring_preload_n
        + spec.return_spring_rate_n_per_m * travel
        - spec.residual_force_n
    ) / mass
    a_min = (spec.return_spring_preload_n - spec.residual_force_n) / mass
    k, c = spec.stop_stiffness_n_per_m, spec.stop_damping_n_s_per_m
    zeta = c / (2.0 * math.sqrt(k * mass))
    e = math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta**2))
    v = math.sqrt(2.0 * a_max * travel)
    half_period = math.pi / (math.sqrt(k / mass) * math.sqrt(1.0 - zeta**2))
    bounces = math.ceil(math.log(a_min * 39e-6 / (2.0 * v)) / math.log(e))
    return flight + 2.0 * e * v / (a_min * (1.0 - e)) + (bounces + 1) * half_period


def test_after_each_release_every_shoe_is_back_on_its_stop_within_the_hand_time(three):
    """Both shoes leave the drum within the hand window of the line pressure's lag on the
    release; each flies to its stop in the hand flight of its spring pushing the fluid of
    both tips back through the line (the tip's inertia left out: within its inertia time
    shorter, 2 % longer), and rests on its stop within the flight and bounce bound; the same
    after every release, on either contact."""
    scenario, _stepper, block = three
    spec, dt = _spec(), scenario.sample_period_s
    soft = _soft_tip(scenario)
    for side in SIDES:
        flights, tip = _flights(block, scenario.setup.params, side, ShoeDefect())
        mass = _tip_mass(tip)
        for k, (leave, travel, cylinder, spring, land, settled) in enumerate(flights):
            release = APPLY_S[k] + 0.05 + HOLD_S
            early, late = _leave_window(cylinder, soft)
            assert early - dt <= leave - release <= late + dt, (side, k, early, leave, late)
            hand = _flight(spring, spec.return_spring_preload_n, spec.return_spring_rate_n_per_m, 2)
            flight = land - leave
            low = hand - _inertia_time(mass) - 2 * dt
            assert low <= flight <= FLIGHT_ALLOWANCE * hand + 2 * dt, (side, k, hand, flight)
            slow = FLIGHT_ALLOWANCE * hand
            assert settled - leave <= _settle_bound(mass, travel, slow) + 2 * dt, (side, k)


def test_a_weak_spring_retracts_its_shoe_later_and_slower_by_the_hand_window(three, weak_three):
    """Half the spring (30 N preload against the 20 N residual force) lets the shoe leave
    the drum later (the line must fall further) and return in the flight of a 10 N push
    through the line, alone (the healthy shoe is back on its stop by then): its own hand
    flight, over 1.5 times the healthy one's. The healthy shoe now flies alone too (the
    weak one still on the drum): its flight is the one-tip hand flight, shorter than with
    both tips pushing fluid: the shared line couples the shoes' returns."""
    scenario, _stepper, block = weak_three
    weak = ShoeDefect(return_spring_weakening_pct=50.0)
    spec, dt = _spec(), scenario.sample_period_s
    flights, tip = _flights(block, scenario.setup.params, "left", weak)
    lag = _inertia_time(_tip_mass(tip)) + 2 * dt
    healthy, _ = _flights(three[2], three[0].setup.params, "left", ShoeDefect())
    right, _ = _flights(block, scenario.setup.params, "right", ShoeDefect())
    paired = _flights(three[2], three[0].setup.params, "right", ShoeDefect())[0][0]
    paired_flight = paired[4] - paired[0]  # the healthy right shoe's beside a healthy left
    for (leave, _travel, _cylinder, spring, land, _settled), healthy_flight, other in zip(
        flights, healthy, right, strict=True
    ):
        hand = _flight(
            spring, 0.5 * spec.return_spring_preload_n, 0.5 * spec.return_spring_rate_n_per_m, 1
        )
        assert other[4] < leave  # the healthy shoe is on its stop before the weak one leaves
        assert hand - lag <= land - leave <= FLIGHT_ALLOWANCE * hand + 2 * dt
        h_leave, h_land = healthy_flight[0], healthy_flight[4]
        assert land - leave > 1.5 * (h_land - h_leave)
        assert leave > h_leave
        o_leave, o_land, o_spring = other[0], other[4], other[3]
        assert o_land - o_leave < paired_flight  # alone, faster than beside a healthy partner
        alone = _flight(o_spring, spec.return_spring_preload_n, spec.return_spring_rate_n_per_m, 1)
        assert alone - lag <= o_land - o_leave <= FLIGHT_ALLOWANCE * alone + 2 * dt


def test_each_application_first_touches_the_drum_as_soon_as_the_first(three):
    """The shoe returns to the same stop after every release, so the first contact of each
    application comes the same time after it (within two samples: the study brake's free
    shoe took 17.9, 9.5 and 9.5 ms)."""
    scenario, _stepper, block = three
    t, dt = block.time_s, scenario.sample_period_s
    for side in SIDES:
        touching = block[f"{side}_normal_force_n"] > 0.0
        delays = []
        for t0 in APPLY_S:
            after = np.flatnonzero(touching & (t >= t0))
            delays.append(t[after[0]] - t0)
        assert delays[0] > 0.0
        assert max(delays) - min(delays) <= 2 * dt, (side, delays)


@pytest.mark.parametrize("contact", CONTACTS)
@pytest.mark.parametrize("weakening_pct", [100.0, 85.0])
def test_a_spring_weakened_past_its_hold_point_drags_with_the_lost_preload(weakening_pct, contact):
    """Past ``1 - residual/preload`` (67 %) the residual force wins: the shoe crosses its
    clearance and presses on the drum with ``F = residual - kept (preload + rate u_c)``
    at the tip (``u_c`` its travel at the drum). The leading shoe's balance ``Fn (d - mu h)
    = F q`` gives the friction ``mu F q / (d - mu h)``; the trailing one stays on its stop.
    The lining over its arc presses where it first touches, the point contact's place (its
    arms ``d``, ``h``), under a load too light to spread it: the same figure."""
    spec = _spec()
    assert spec.hold_weakening_pct == pytest.approx(100.0 * (1.0 - 20.0 / 60.0))
    defects = Defects(left=ShoeDefect(return_spring_weakening_pct=weakening_pct))
    scenario, stepper, block = _run(IDLE + (ARC if contact == "arc" else ""), defects)
    p = stepper.packed_parameters
    arms = contact_arms(p, 12, 0.0)  # the left shoe's block (layout.P_SHOE_BASE)
    tip = Tip(scenario.setup.params, "left", ShoeDefect())
    travel = float(tip.at(np.array([arms.onset_angle_rad]))[0][0])
    kept = 1.0 - weakening_pct / 100.0
    push = spec.residual_force_n - kept * (
        spec.return_spring_preload_n + spec.return_spring_rate_n_per_m * travel
    )
    mu = scenario.setup.params.friction.coefficient
    d, h, q = arms.normal_arm_m, arms.friction_arm_m, arms.actuation_arm_m
    expected = mu * push * q / (d - mu * h)
    w = block.time_s > 1.0
    assert block["left_friction_force_n"][w].mean() == pytest.approx(expected, rel=0.03)
    assert np.all(block["right_friction_force_n"] == 0.0)
    assert block["drum_speed_rad_s"][-1] < block["drum_speed_rad_s"][0]


def test_a_spring_weakened_short_of_its_hold_point_holds_its_shoe_off():
    held = Defects(left=ShoeDefect(return_spring_weakening_pct=60.0))
    _scenario, _stepper, block = _run(IDLE, held)
    assert np.all(block["left_normal_force_n"] == 0.0)
    assert np.all(block["drum_speed_rad_s"] == block["drum_speed_rad_s"][0])


def _tip_forces(block, params: BrakeParameters, side: str, tip: Tip):
    """Net outward force at the tip from the documented laws, N: the cylinder (recorded,
    never below the residual) less the spring plus the stop; and the stop's force, N."""
    spec = params.service
    theta = block[f"{side}_angle_rad"]
    travel, arm, _ = tip.at(theta)
    rate = arm * block[f"{side}_speed_rad_s"]
    cylinder = block[f"{side}_actuation_force_n"]
    assert np.all(cylinder >= spec.residual_force_n)
    spring = spec.return_spring_preload_n + spec.return_spring_rate_n_per_m * travel
    press = _stop_travel(0.0) - travel
    stop = np.where(
        press > 0.0,
        np.maximum(spec.stop_stiffness_n_per_m * press - spec.stop_damping_n_s_per_m * rate, 0.0),
        0.0,
    )
    return cylinder - spring + stop, stop


@pytest.mark.parametrize("three", ["point"], indirect=True)
def test_each_shoe_obeys_its_equation_of_motion_at_every_sample(three):
    """``I theta'' = s (moment of contact, friction and the tip's net force about the
    pivot)`` between consecutive samples (trapezoidal rule). A Kelvin-Voigt contact's force
    jumps by ``c eps'`` where it starts and kinks where it ends, which no rule through two
    samples integrates: the intervals where the lining's or the stop's contact switches
    are left out (48 of 33 279 here). Everywhere else within 1 % of the largest moment,
    and off the drum within 1 % of the moment there or of the spring's preload moment
    ``P q`` (17 N m), whichever is larger (so that a missing or wrong spring or stop term
    shows: either is tens of N m). The point contact: the lining over its arc rings at 2.5
    kHz, where the trapezoidal rule's own error at 25.6 kHz is 1.1 %; its test samples at
    102.4 kHz (tests/model/test_lining.py)."""
    scenario, _stepper, block = three
    params = scenario.setup.params
    spec = params.service
    for side in SIDES:
        tip = Tip(params, side, ShoeDefect())
        theta = block[f"{side}_angle_rad"]
        _travel, arm, offset = tip.at(theta)
        x, y = block[f"{side}_contact_x_m"], block[f"{side}_contact_y_m"]
        r = np.hypot(x, y)
        nx, ny = x / r, y / r
        fn, ff = block[f"{side}_normal_force_n"], block[f"{side}_friction_force_n"]
        fcx, fcy = -fn * nx - ff * ny, -fn * ny + ff * nx
        ax, ay = x - tip.pivot[0], y - tip.pivot[1]
        f_tip, stop = _tip_forces(block, params, side, tip)
        moment = ax * fcy - ay * fcx + f_tip * (offset[0] * tip.axis[1] - offset[1] * tip.axis[0])
        generalised = tip.sign * moment
        w = block[f"{side}_speed_rad_s"]
        lhs = tip.inertia * np.diff(w) / np.diff(block.time_s)
        residual = lhs - 0.5 * (generalised[1:] + generalised[:-1])
        lining, stopped = fn > 0.0, stop > 0.0
        smooth = (lining[1:] == lining[:-1]) & (stopped[1:] == stopped[:-1])
        assert smooth.sum() > 0.99 * smooth.size
        assert np.abs(residual[smooth]).max() < 0.01 * np.abs(generalised).max()
        off = smooth & ~lining[1:] & ~lining[:-1]
        assert off.sum() > 0.5 * off.size
        preload_moment = spec.return_spring_preload_n * np.abs(arm).mean()
        local = np.maximum(np.abs(generalised[1:]), np.abs(generalised[:-1]))
        scale = np.maximum(local, preload_moment)
        assert np.all(np.abs(residual[off]) < 0.01 * scale[off]), side


def test_energy_closes_through_the_springs_and_stops(three):
    """Kinetic + coupling + contact + spring + stop energy, cylinders' work and every loss
    (the stops' dampers in the contact loss) close to 1e-6 of the turnover; the books
    refuse a service brake without its packed parameters."""
    scenario, stepper, block = three
    books = energy_balance(block, scenario.setup.params, packed=stepper.packed_parameters)
    assert abs(books.residual_j) < 1e-6 * books.turnover_j
    with pytest.raises(ValueError, match="packed="):
        energy_balance(block, scenario.setup.params)


# a stop stiff enough to ring above every other mode of the contact: 2.03 kHz with the point
# contact, 6.4 kHz with the lining over its arc (whose own mode is 1.75 kHz under 1000 N)
STIFF_STOPS = {"point": 1e8, "arc": 1e9}


@pytest.mark.parametrize("contact", CONTACTS)
def test_the_step_limit_resolves_the_rest_stop_mode(contact):
    """A stiff stop (:data:`STIFF_STOPS`) rings at ``sqrt(k_st / m) / 2 pi`` with the
    shoe's inertia at the tip ``m = I/q^2``, above every other mode: the step limit sees it
    (the brake linearised at rest on its stops) and resolves it with 16 steps."""
    from brake_sim_ros.model.run_setup import BrakeSetup
    from brake_sim_ros.solvers.stability import STEPS_PER_PERIOD, step_limit

    base = BrakeParameters.of_brake("service")
    base = dataclasses.replace(
        base,
        service=dataclasses.replace(base.service, distributed_lining=contact == "arc"),
    )
    k_stop = STIFF_STOPS[contact]
    stiff = dataclasses.replace(
        base, service=dataclasses.replace(base.service, stop_stiffness_n_per_m=k_stop)
    )
    setup = BrakeSetup(params=stiff)
    mass = _tip_mass(Tip(stiff, "left", ShoeDefect()))
    expected_hz = math.sqrt(k_stop / mass) / (2 * math.pi)
    limit = step_limit(setup, 1000.0)
    assert limit.fastest_frequency_hz == pytest.approx(expected_hz, rel=0.02)
    assert limit.max_step_s <= 1.0 / (STEPS_PER_PERIOD * expected_hz) * 1.02
    # the default stop (1e7 N/m) rings at 644 Hz: the stiffer stop is what lowered the step
    # (the default's limit is set by other modes: friction and tyre, or the arc's)
    default = step_limit(BrakeSetup(params=base), 1000.0)
    assert default.fastest_frequency_hz < expected_hz / 3.0
    assert default.max_step_s > 1.5 * limit.max_step_s


def test_a_parameter_change_keeps_the_scenarios_brake():
    """The node and re-simulation rebuild the model from flat parameter values (which hold
    no brake choice): the service brake's springs stay."""
    from brake_sim_ros.stream.parameters import changed_setup, model_values

    setup = parse_scenario(IDLE).setup
    values = model_values(setup.params, setup.defects)
    values["friction.coefficient"] = 0.3
    changed = changed_setup(setup, values)
    assert changed.params.service == setup.params.service is not None
    assert changed.params.friction.coefficient == 0.3
