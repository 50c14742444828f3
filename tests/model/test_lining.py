"""The service brake's lining contact distributed over its arc (model/lining.py): a Winkler
foundation ``p = (E/t) delta`` integrated over the lining by a fixed quadrature. Each
figure a test expects is a hand integral of the documented law over the documented
geometry (model/placement.py's arc, evaluated here in numpy at a resolution far above
the model's), never read off a run."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from brake_sim_ros.analysis.energy import energy_balance
from brake_sim_ros.model import contact, lining
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import pack
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.placement import place_shoe
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.stream.build import stepper_for

BASE = L.P_SHOE_BASE  # the left (leading) shoe
DEPTH_M = 50e-6  # uniform penetration of the concentric tests


def _service() -> BrakeParameters:
    """The service brake with its lining over the arc."""
    params = BrakeParameters.of_brake("service")
    return dataclasses.replace(
        params, service=dataclasses.replace(params.service, distributed_lining=True)
    )


def _concentric(params: BrakeParameters, depth: float) -> tuple[np.ndarray, object]:
    """The service brake packed, its left lining moved to be concentric with the drum at
    its rest angle and ``depth`` m into it all along: a uniform penetration."""
    p = pack(params, Defects())
    p[BASE + L.S_LINING_CENTRE_X] = 0.0
    p[BASE + L.S_LINING_CENTRE_Y] = 0.0
    p[BASE + L.S_LINING_RADIUS] = params.shoe.drum_radius_m + depth
    return p, place_shoe(params, "left", ShoeDefect())


def _foundation(params: BrakeParameters) -> float:
    """``k_w b r``: the foundation's force per metre of penetration per radian of arc, N/m
    (the area the packing shares among the nodes is the worn-free lining's, radius
    drum radius less the running clearance)."""
    g = params.shoe
    return (
        params.service.lining_foundation_pa_per_m
        * g.lining_width_m
        * (g.drum_radius_m - g.running_clearance_m)
    )


def _arc(shoe) -> np.ndarray:
    """Polar angles across the lining of a concentric shoe, 20 001 points, rad."""
    return np.linspace(
        shoe.lining_mid_rad - shoe.lining_half_rad,
        shoe.lining_mid_rad + shoe.lining_half_rad,
        20001,
    )


def _eval(p, theta=0.0, drum_angle=0.0):
    return lining.shoe_contact(p, BASE, theta, 0.0, 0.0, 0.0, L.CONTACT_AUTO, 0, 0.0, drum_angle)


def test_the_arcs_static_force_and_stiffness_match_the_winkler_integrals():
    """Concentric lining ``delta0`` into the drum: the resultant is ``k_w b r delta0 2
    sin(beta0)`` along the arc's middle, its moment about the pin ``k_w b r delta0
    [-px cos - py sin]`` over the arc, and the moment's stiffness in the shoe's turn
    ``k_w b r a^2 int sin^2(alpha - alpha_p)`` (``a``, ``alpha_p``: the pin's radius and
    polar angle); each within 1 % (the midpoint rule on 32 nodes errs by about 3e-4). The
    arc is then 17 times stiffer radially than the study's point contact."""
    params = _service()
    p, shoe = _concentric(params, DEPTH_M)
    kb = _foundation(params)
    half, mid = shoe.lining_half_rad, shoe.lining_mid_rad
    out = _eval(p)
    force = kb * DEPTH_M * 2.0 * math.sin(half)
    fx, fy = out[contact.E_APPLIED_X], out[contact.E_APPLIED_Y]
    assert math.hypot(fx, fy) == pytest.approx(force, rel=0.01)
    assert math.atan2(-fy, -fx) == pytest.approx(mid, abs=1e-3)
    assert out[contact.E_EPS] == pytest.approx(DEPTH_M, rel=1e-9)
    px, py = shoe.pivot_xy_m
    alpha = _arc(shoe)
    moment = (
        kb
        * DEPTH_M
        * (
            (-px * math.cos(alpha[-1]) - py * math.sin(alpha[-1]))
            - (-px * math.cos(alpha[0]) - py * math.sin(alpha[0]))
        )
    )
    inertia = p[BASE + L.S_INERTIA]
    sign = p[BASE + L.S_SIGN]
    assert sign * out[contact.E_THETA_DDOT] * inertia == pytest.approx(moment, rel=0.01)
    a, alpha_p = math.hypot(px, py), math.atan2(py, px)
    u = alpha - alpha_p
    stiffness = (
        kb * a**2 * ((u[-1] / 2 - math.sin(2 * u[-1]) / 4) - (u[0] / 2 - math.sin(2 * u[0]) / 4))
    )
    step = 1e-6
    slope = (_eval(p, step)[contact.E_THETA_DDOT] - _eval(p, -step)[contact.E_THETA_DDOT]) / (
        2 * step
    )
    assert -slope * inertia == pytest.approx(stiffness, rel=0.01)
    # the radial stiffness of the arc against the point contact's Hertz line
    assert force / DEPTH_M > 15.0 * params.contact_stiffness_n_per_m


def _with_flat(p: np.ndarray, depth: float, centre: float, width_deg: float) -> np.ndarray:
    flat = p.copy()
    flat[L.P_FLAT_DEPTH] = depth
    flat[L.P_FLAT_CENTRE] = centre
    flat[L.P_FLAT_HALF_WIDTH] = math.radians(0.5 * width_deg)
    return flat


@pytest.mark.parametrize("offset", [0.0, 0.25, 0.5, 0.8])
def test_a_short_flat_is_bridged_by_the_share_of_the_arc_it_covers(offset):
    """A flat of the catalogue's default width (5 deg) and depth ``d`` = 20 um under the
    middle of the concentric lining, at any place between two nodes (``offset`` of a node
    spacing): the normal force changes by ``k_w b r int d (1 + cos(pi x / w)) / 2 cos x dx``
    (hand quadrature) within 2 %, a share ``d w / (2 delta0 sin beta0)`` of the force
    (8.8 % at ``delta0`` = 50 um): the point contact under the same flat changes by
    ``d / delta0`` of its own (40 %), in full."""
    params = _service()
    p, shoe = _concentric(params, DEPTH_M)
    kb = _foundation(params)
    spacing = 2.0 * shoe.lining_half_rad / lining.NODES
    depth, width_deg = 20e-6, 5.0
    centre = shoe.lining_mid_rad + offset * spacing
    flat = _with_flat(p, depth, centre, width_deg)
    before = _eval(p)[contact.E_FN]
    after = _eval(flat)[contact.E_FN]
    w = math.radians(0.5 * width_deg)
    x = np.linspace(-w, w, 20001)
    bump = depth * (1 + np.cos(np.pi * x / w)) / 2 * np.cos(x + centre - shoe.lining_mid_rad)
    hand = kb * float(np.sum((bump[1:] + bump[:-1]) / 2 * np.diff(x)))
    assert after - before == pytest.approx(hand, rel=0.02)
    share = (after - before) / before
    assert share == pytest.approx(
        depth * w / (2 * DEPTH_M * math.sin(shoe.lining_half_rad)), rel=0.03
    )
    # the study's point contact, at the same pose (deepest point: the arc's middle)
    point = p.copy()
    point[L.P_LINING_NODE_STIFFNESS] = 0.0
    pflat = _with_flat(point, depth, shoe.lining_mid_rad, width_deg)
    k_c = params.contact_stiffness_n_per_m
    f0 = contact.shoe_eval(point, BASE, 0.0, 0.0, 0.0, 0.0, L.CONTACT_AUTO)[contact.E_FN]
    f1 = contact.shoe_eval(pflat, BASE, 0.0, 0.0, 0.0, 0.0, L.CONTACT_AUTO)[contact.E_FN]
    assert f0 == pytest.approx(k_c * DEPTH_M, rel=1e-9)
    assert (f1 - f0) / f0 == pytest.approx(depth / DEPTH_M, rel=1e-6)
    assert share < 0.25 * (f1 - f0) / f0


def test_the_recorded_point_carries_the_resultant_and_its_moment():
    """On a sliding drum the recorded normal and friction forces at the recorded point
    (inward radial and counter-clockwise tangent there) sum to the resultant of every
    node's force, with its moment about the drum centre: the pivot's balance and the drum's
    torque follow from the columns as from the point contact's."""
    params = _service()
    p, _shoe = _concentric(params, DEPTH_M)
    out = lining.shoe_contact(p, BASE, 1e-4, 0.0, 50.0, 0.0, L.CONTACT_AUTO, 0, 0.0, 0.0)
    x, y = out[contact.E_CONTACT_X], out[contact.E_CONTACT_Y]
    r = math.hypot(x, y)
    nx, ny = x / r, y / r
    fn, ff = out[contact.E_FN], out[contact.E_FF]
    fx, fy = -fn * nx - ff * ny, -fn * ny + ff * nx
    assert fx == pytest.approx(out[contact.E_APPLIED_X], rel=1e-9)
    assert fy == pytest.approx(out[contact.E_APPLIED_Y], rel=1e-9)
    assert -ff * r == pytest.approx(out[contact.E_DRUM_TORQUE], rel=1e-3)
    assert ff > 0.0 and fn > 0.0


# --- the service brake in motion ----------------------------------------------------------


def _application(duration: float = 0.25, rate_hz: float = 25600.0) -> str:
    knots = "times_s = [0.0, 0.02, 0.07]\nforces_n = [0.0, 0.0, 1000.0]\n"
    return (
        f'name = "apply"\nbrake = "service"\nduration_s = {duration}\n'
        f"sample_rate_hz = {rate_hz}\n"
        '[actuation]\nprofile = "piecewise"\n'
        f"[actuation.left]\n{knots}[actuation.right]\n{knots}"
    )


def _run(distributed: bool, text: str | None = None):
    scenario = parse_scenario(text or _application())
    params = scenario.setup.params
    service = dataclasses.replace(params.service, distributed_lining=distributed)
    setup = dataclasses.replace(scenario.setup, params=dataclasses.replace(params, service=service))
    scenario = dataclasses.replace(scenario, setup=setup)
    stepper = stepper_for(scenario)
    return scenario, stepper, stepper.run(scenario.duration_s)


@pytest.fixture(scope="module")
def lined():
    return _run(True)


def test_the_lining_is_packed_as_documented_and_the_default_keeps_the_point_contact():
    """Each node carries ``(E/t) b r (2 beta0 / N)`` and ``tau`` times it as damping; the
    service brake's default (``distributed_lining`` False) packs none: its point contact."""
    params = _service()
    p = pack(params, Defects())
    g, spec = params.shoe, params.service
    arc = math.radians(g.lining_end_deg - g.lining_start_deg)
    node = _foundation(params) * arc / lining.NODES
    assert p[L.P_LINING_NODE_STIFFNESS] == pytest.approx(node, rel=1e-12)
    assert p[L.P_LINING_NODE_DAMPING] == pytest.approx(spec.lining_damping_time_s * node, rel=1e-12)
    assert pack(BrakeParameters.of_brake("service"), Defects())[L.P_LINING_NODE_STIFFNESS] == 0.0


def _landings(block, side: str) -> int:
    touching = block[f"{side}_normal_force_n"] > 0.0
    return int(np.count_nonzero(touching[1:] & ~touching[:-1]))


def test_energy_closes_with_the_lining(lined):
    """Kinetic, spring, stop, circuit and the arc's foundation energy, the cylinders' work
    and every loss (the foundation's dampers in the contact loss) close to 1e-6."""
    scenario, stepper, block = lined
    books = energy_balance(block, scenario.setup.params, packed=stepper.packed_parameters)
    assert abs(books.residual_j) < 1e-6 * books.turnover_j


def test_energy_closes_with_the_lining_on_a_drum_with_a_flat():
    """The same books on a drum with a flat (the nodes' moments on the drum included)."""
    text = _application(0.3) + "\n[defects.drum]\nflat_depth_um = 40.0\nflat_width_deg = 5.0\n"
    scenario, stepper, block = _run(True, text)
    books = energy_balance(block, scenario.setup.params, packed=stepper.packed_parameters)
    assert abs(books.residual_j) < 1e-6 * books.turnover_j
    assert block["left_normal_force_n"].max() > 500.0


def test_the_step_limit_sees_the_shoe_on_its_whole_arc():
    """Under 20 kN the whole lining presses: the step limit's fastest mode is the shoe on
    its arc, ``sqrt(K / I) / 2 pi`` with the Winkler moment stiffness about the pin ``K =
    k_w b r a^2 int sin^2(alpha - alpha_p)`` of the concentric arc (2.56 kHz) within 5 %
    (the loaded arc is 0.3 mm off concentric), 3.9 times the point contact's mode."""
    from brake_sim_ros.model.run_setup import BrakeSetup
    from brake_sim_ros.solvers.stability import step_limit

    params = _service()
    shoe = place_shoe(params, "left", ShoeDefect())
    px, py = shoe.pivot_xy_m
    alpha = _arc(shoe)
    u0, u1 = alpha[0] - math.atan2(py, px), alpha[-1] - math.atan2(py, px)
    integral = (u1 / 2 - math.sin(2 * u1) / 4) - (u0 / 2 - math.sin(2 * u0) / 4)
    stiffness = _foundation(params) * (px**2 + py**2) * integral
    inertia = pack(params, Defects())[BASE + L.S_INERTIA]
    hand_hz = math.sqrt(stiffness / inertia) / (2 * math.pi)
    limit = step_limit(BrakeSetup(params=params), 20000.0)
    assert limit.fastest_frequency_hz == pytest.approx(hand_hz, rel=0.05)
    point = step_limit(BrakeSetup(params=BrakeParameters.of_brake("service")), 20000.0)
    assert limit.fastest_frequency_hz > 3.0 * point.fastest_frequency_hz


@pytest.mark.parametrize(
    ("field", "value"),
    [("lining_modulus_pa", 0.0), ("lining_thickness_m", 0.5), ("lining_damping_time_s", -1e-6)],
)
def test_a_bad_lining_parameter_is_refused_in_one_line(field, value):
    from brake_sim_ros.errors import ParameterError
    from brake_sim_ros.model.service_parameters import ServiceBrakeParameters

    with pytest.raises(ParameterError, match=field) as info:
        ServiceBrakeParameters(**{field: value})
    assert "\n" not in str(info.value)


def _node_pattern(p: np.ndarray, block, side: str) -> np.ndarray:
    """Which of the shoe's nodes penetrate the drum at each sample (n, NODES), from the
    recorded shoe and drum angles."""
    base = L.P_SHOE_BASE + L.SIDES.index(side) * L.SHOE_STRIDE
    theta, drum = block[f"{side}_angle_rad"], block["drum_angle_rad"]
    sign = p[base + L.S_SIGN]
    out = np.zeros((len(theta), lining.NODES), dtype=bool)
    for row in range(len(theta)):
        c, sn = math.cos(sign * theta[row]), math.sin(sign * theta[row])
        for i in range(lining.NODES):
            beta = lining.node_angle(p, base, i)
            cb, sb = math.cos(beta), math.sin(beta)
            state = lining.node_state(p, base, c, sn, 0.0, cb, sb, drum[row], 0.0)
            out[row, i] = state[0] > 0.0
    return out


def test_each_shoe_obeys_its_equation_of_motion_at_every_sample():
    """``I theta'' = s (moment of the recorded contact force at the recorded point and of
    the tip's net force about the pivot)`` between consecutive samples (trapezoidal rule),
    as tests/model/test_service_brake.py checks the point contact: the intervals where any
    node's contact or the stop's switches are left out (a node's force jumps by ``c
    delta'`` there); everywhere else within 1 % of the largest moment. Sampled at 102.4
    kHz: the trapezoidal rule's own error on the shoe's 2.5 kHz mode on its arc,
    ``(omega h)^2 / 12``, is 1.1 % at the default 25.6 kHz (0.07 % here)."""
    from tests.model.test_service_brake import Tip, _tip_forces

    scenario, stepper, block = _run(True, _application(0.15, 102400.0))
    params = scenario.setup.params
    for side in L.SIDES:
        tip = Tip(params, side, ShoeDefect())
        _travel, _arm, offset = tip.at(block[f"{side}_angle_rad"])
        x, y = block[f"{side}_contact_x_m"], block[f"{side}_contact_y_m"]
        r = np.hypot(x, y)
        nx, ny = x / r, y / r
        fn, ff = block[f"{side}_normal_force_n"], block[f"{side}_friction_force_n"]
        fcx, fcy = -fn * nx - ff * ny, -fn * ny + ff * nx
        ax, ay = x - tip.pivot[0], y - tip.pivot[1]
        f_tip, stop = _tip_forces(block, params, side, tip)
        moment = ax * fcy - ay * fcx + f_tip * (offset[0] * tip.axis[1] - offset[1] * tip.axis[0])
        generalised = tip.sign * moment
        lhs = tip.inertia * np.diff(block[f"{side}_speed_rad_s"]) / np.diff(block.time_s)
        residual = lhs - 0.5 * (generalised[1:] + generalised[:-1])
        nodes = _node_pattern(stepper.packed_parameters, block, side)
        pushing = fn > 0.0
        stopped = stop > 0.0
        smooth = (
            np.all(nodes[1:] == nodes[:-1], axis=1)
            & (pushing[1:] == pushing[:-1])
            & (stopped[1:] == stopped[:-1])
        )
        assert smooth.sum() > 0.98 * smooth.size
        assert np.abs(residual[smooth]).max() < 0.01 * np.abs(generalised).max(), side


@settings(max_examples=150, deadline=None, derandomize=True)
@given(
    theta=st.floats(-0.01, 0.01),
    omega=st.floats(-50.0, 50.0),
    drum_angle=st.floats(-10.0, 10.0),
    drum_speed=st.floats(-120.0, 120.0),
)
def test_the_switching_bound_keeps_every_sign_and_bounds_the_depth(
    theta, omega, drum_angle, drum_speed
):
    """A step's end reads the lining's switching function for its signs and an upper bound
    of its indentation (``signs_only``): where the lining's circle is clear of the round
    drum it skips the nodes and returns that clearance, an upper bound of both with their
    signs; elsewhere the nodes' exact values."""
    p = pack(_service(), Defects())
    for base in (BASE, BASE + L.SHOE_STRIDE):
        args = (p, base, theta, omega, drum_angle, drum_speed)
        eps, h = lining.switching(*args, False)
        bound_eps, bound_h = lining.switching(*args, True)
        if (bound_eps, bound_h) != (eps, h):
            assert bound_eps == bound_h < 0.0
            assert eps < bound_eps and h < bound_h
        assert (bound_eps > 0.0) == (eps > 0.0) and (bound_h > 0.0) == (h > 0.0)


def test_the_switching_bound_skips_the_nodes_only_where_the_lining_is_clear():
    """At rest (0.3 mm clear) the bound is the clearance, -0.3 mm (less the margin: the
    lining is concentric with the drum there, where the nodes' rounding makes one 2e-16 m
    deeper than the circle); pressing (3 mrad out) or on a drum with a flat it is the
    nodes' own value."""
    p = pack(_service(), Defects())
    rest = lining.switching(p, BASE, 0.0, 0.0, 0.0, 100.0, True)
    assert rest[0] == rest[1] == pytest.approx(-0.3e-3 + lining.CLEAR_MARGIN_M, abs=1e-15)
    assert rest != lining.switching(p, BASE, 0.0, 0.0, 0.0, 100.0, False)
    pressed = (p, BASE, 0.003, 0.0, 0.0, 100.0)
    assert lining.switching(*pressed, True) == lining.switching(*pressed, False)
    flat = _with_flat(p, 1e-4, 0.0, 5.0)
    at_rest = (flat, BASE, 0.0, 0.0, 0.0, 100.0)
    assert lining.switching(*at_rest, True) == lining.switching(*at_rest, False)
