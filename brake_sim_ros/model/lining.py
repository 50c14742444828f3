"""The service brake's lining contact, distributed over the lining's arc, compiled (numba).

The study brake touches the drum at one point, the lining point deepest in the drum, with
a Hertzian line contact (:mod:`brake_sim_ros.model.contact`). A bedded lining touches over
its arc: here it is an elastic (Winkler) foundation, a bed of independent springs and
dampers, pressing with ``p(beta) = k_w delta + c_w delta'`` (Pa) wherever it penetrates the
drum (``delta > 0``; never pulling), ``k_w = E / t`` the lining's compressive modulus over
its thickness (Pa/m) and ``c_w = tau k_w``.

Quadrature. The arc (half angle ``beta_0`` about its middle, seen from its centre ``C``)
is cut into :data:`NODES` equal cells; each cell's springs sit at its middle, a material
point of the shoe (midpoint rule), with the stiffness ``k_w b r (2 beta_0 / N)`` (N/m,
layout.P_LINING_NODE_STIFFNESS; ``b`` the lining's width, ``r`` its radius) and the damping
``tau`` times it. ``delta_i`` is the node's radial penetration into the drum's local radius
at its polar angle, the drum's runout and flat included (:func:`.contact.drum_radius`):
``delta_i = |X_i| - r(psi_i)``. A drum feature is seen only through the nodes it passes:
a raised-cosine flat of half width ``w`` is summed exactly (its Fourier transform vanishes
at every alias of a node spacing ``Delta <= w``: the sum of the node samples is
``d w / Delta`` whatever the flat's phase) while ``Delta <= w``; a feature shorter than the
spacing slips between nodes and is felt at most by one node, as a ripple. With
:data:`NODES` = 32 on the 80 deg arc the spacing is 2.5 deg, the half width of the
catalogue's default flat (5 deg wide): every flat of the catalogue is resolved.

Each node's force on the shoe is ``-f_i grad g_i`` (``g_i = |X| - r(psi)``, its gradient
``e_r - (r'/|X|) e_t``) plus its smoothed Coulomb friction ``mu f_i tanh(v_i / v_s)``
along the drum surface's tangent at the sliding speed ``v_i`` there (at standstill the
static share of its capacity, as the point contact's); the node being a material point,
the moments these apply on the shoe and on the drum are the exact gradients of the
foundation's elastic energy ``sum k_i delta_i^2 / 2``, so the energy books close as for
the point contact (analysis/energy.py, :func:`stored_energy_rows`).

What is recorded in the point contact's columns (:func:`shoe_contact`): the normal force is
the arc's total normal load ``sum f_i`` (what a pressure gauge under the lining would sum;
the magnitude of the vector resultant is smaller, ``sin(beta_0) / beta_0`` = 0.92 of it on
the 80 deg arc under a uniform pressure); the friction force is ``sum ff_i`` (the drum's
friction torque over the drum radius on a round drum); the indentation is the largest
node penetration ``max delta_i`` and its rate that node's; the contact point is the
lining point at the centre of pressure (the pressure-weighted mean arc angle), the deepest
node's while nothing presses; the sliding speed the pressure-weighted mean. The pivot
reaction (what the sensors read) follows from the resultants of all node forces.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from brake_sim_ros.model import contact
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.compiled import JIT, JIT_ALLOCATING

# Nodes of the arc's quadrature (midpoint rule): a spacing of 2.5 deg on the 80 deg
# lining, the half width of the catalogue's default flat (see the module notes).
NODES = 32


@njit(inline="always", **JIT)
def node_angle(p, base, i):
    """Arc angle (rad) of node ``i`` from the lining's middle, seen from its centre."""
    half = p[base + L.S_LINING_HALF_ANGLE]
    return half * ((2.0 * i + 1.0) / NODES - 1.0)


@njit(inline="always", **JIT)
def first_node(p, base):
    """cos and sin of node 0's arc angle and of the nodes' spacing (rad): node ``i + 1``'s
    are node ``i``'s turned by the spacing (two products, no trigonometry per node)."""
    spacing = 2.0 * p[base + L.S_LINING_HALF_ANGLE] / NODES
    beta = node_angle(p, base, 0)
    return math.cos(beta), math.sin(beta), math.cos(spacing), math.sin(spacing)


@njit(inline="always", **JIT)
def lining_point(p, base, c, sn, cb, sb):
    """The lining point at arc angle ``beta`` from its middle (cos ``cb``, sin ``sb``), for
    the shoe turned by ``phi`` (cos ``c``, sin ``sn``): (x, y), m."""
    cx, cy = contact.arc_centre(p, base, c, sn)
    m0x = p[base + L.S_LINING_MID_COS]
    m0y = p[base + L.S_LINING_MID_SIN]
    ux0 = cb * m0x - sb * m0y
    uy0 = sb * m0x + cb * m0y
    r = p[base + L.S_LINING_RADIUS]
    return cx + r * (c * ux0 - sn * uy0), cy + r * (sn * ux0 + c * uy0)


@njit(inline="always", **JIT)
def node_depth(p, base, c, sn, w, cb, sb, drum_angle, drum_speed):
    """One node's penetration, the first part of :func:`node_state`: (delta m, delta' m/s,
    node x m, node y m, its radial unit vector x and y, r' m/rad, its distance from the
    drum centre m, d delta / d phi m/rad). What a node that presses nothing needs."""
    px = p[base + L.S_PIVOT_X]
    py = p[base + L.S_PIVOT_Y]
    x, y = lining_point(p, base, c, sn, cb, sb)
    dist = math.sqrt(x * x + y * y)
    nx = x / dist
    ny = y / dist
    if p[L.P_DRUM_WAVE_COUNT] <= 0.0 and p[L.P_FLAT_DEPTH] <= 0.0:  # a round drum
        radius = p[L.P_DRUM_RADIUS]
        slope = 0.0
    else:
        radius, slope = contact.drum_radius(p, math.atan2(y, x) - drum_angle)
    delta = dist - radius
    arm_r = (x - px) * ny - (y - py) * nx
    if slope == 0.0:  # no tilt: d_phi is arm_r (the expression below with tilt 0)
        d_phi = arm_r
    else:
        arm_t = (x - px) * nx + (y - py) * ny
        d_phi = arm_r - slope / dist * arm_t
    return delta, w * d_phi + slope * drum_speed, x, y, nx, ny, slope, dist, d_phi


@njit(inline="always", **JIT)
def node_tail(p, base, w, drum_speed, x, y, nx, ny, slope, dist):
    """The rest of :func:`node_state` from :func:`node_depth`'s node: (grad g x, grad g y,
    tangent x, tangent y, friction arm m, sliding speed m/s)."""
    px = p[base + L.S_PIVOT_X]
    py = p[base + L.S_PIVOT_Y]
    if slope == 0.0:  # no tilt: the expressions below with tilt 0 (the same values)
        gx = nx
        gy = ny
        tx = -gy
        ty = gx
        arm = dist
    else:
        tilt = slope / dist
        gx = nx + tilt * ny
        gy = ny - tilt * nx
        norm = math.sqrt(1.0 + tilt * tilt)
        tx = -gy / norm
        ty = gx / norm
        arm = dist / norm
    vt = tx * (-w * (y - py)) + ty * (w * (x - px))
    return gx, gy, tx, ty, arm, drum_speed * arm - vt


@njit(inline="always", **JIT)
def node_state(p, base, c, sn, w, cb, sb, drum_angle, drum_speed):
    """One node's contact at arc angle ``beta`` (cos ``cb``, sin ``sb``) of the shoe
    turned by ``phi`` (cos ``c``, sin ``sn``) at ``w`` = d(phi)/dt rad/s, the drum at
    ``drum_angle`` turning at ``drum_speed`` (rad): (delta m, delta' m/s, grad g x,
    grad g y, tangent x, tangent y, friction arm m, sliding speed m/s, node x m, node y
    m, r' m/rad, d delta / d phi m/rad).
    """
    delta, delta_dot, x, y, nx, ny, slope, dist, d_phi = node_depth(
        p, base, c, sn, w, cb, sb, drum_angle, drum_speed
    )
    gx, gy, tx, ty, arm, v = node_tail(p, base, w, drum_speed, x, y, nx, ny, slope, dist)
    return delta, delta_dot, gx, gy, tx, ty, arm, v, x, y, slope, d_phi


@njit(**JIT)
def shoe_contact(p, base, theta, omega, drum_speed, actuation, mode, stuck, share, drum_angle):
    """:func:`.contact.shoe_eval` of the distributed lining: the :data:`.contact.N_EVAL`
    slots for the shoe at ``theta`` rad turning at ``omega`` rad/s (outward), the drum at
    ``drum_angle`` turning at ``drum_speed`` rad/s, the net tip force ``actuation`` N,
    the contact mode ``mode`` (CONTACT_OFF: no node presses; else each node while it
    penetrates and pushes), ``stuck``/``share`` as for the point contact. The recorded
    slots' meaning: the module notes."""
    s = p[base + L.S_SIGN]
    px = p[base + L.S_PIVOT_X]
    py = p[base + L.S_PIVOT_Y]
    phi = s * theta
    c = math.cos(phi)
    sn = math.sin(phi)
    w = s * omega
    enabled = p[base + L.S_ENABLED] > 0.0
    pressing = enabled and mode != L.CONTACT_OFF
    k = p[L.P_LINING_NODE_STIFFNESS]
    cd = p[L.P_LINING_NODE_DAMPING]
    mu = p[base + L.S_FRICTION_COEFFICIENT]
    fx = 0.0
    fy = 0.0
    moment = 0.0
    torque = 0.0
    fn_sum = 0.0
    p_friction = 0.0
    p_loss = 0.0
    elastic = 0.0  # the nodes' elastic force, N (the wear's loss: contact.wear_loss)
    m_centre = 0.0
    v_sum = 0.0
    eps = -math.inf
    eps_dot = 0.0
    # the deepest node's arc angle (its place and sliding speed are computed again, once,
    # where nothing presses and they are recorded)
    cb_deep = 1.0
    sb_deep = 0.0
    cb, sb, cd_, sd_ = first_node(p, base)
    for _ in range(NODES):
        d, d_dot, x, y, nx, ny, slope, dist, _ = node_depth(
            p, base, c, sn, w, cb, sb, drum_angle, drum_speed
        )
        if d > eps:
            eps = d
            eps_dot = d_dot
            cb_deep = cb
            sb_deep = sb
        cb, sb = cb * cd_ - sb * sd_, sb * cd_ + cb * sd_
        if d <= 0.0:
            # presses nothing: no force, and its damper's loss (f - k max(d, 0)) d' and
            # elastic force are zeros (the sums below skip them)
            continue
        gx, gy, tx, ty, arm, v = node_tail(p, base, w, drum_speed, x, y, nx, ny, slope, dist)
        f = 0.0
        if pressing and d > 0.0:
            f = k * d + cd * d_dot
            if f < 0.0:
                f = 0.0
        if enabled:
            # the node's damper loss: power in less the rate of its elastic energy
            spring = k * max(d, 0.0)
            p_loss += (f - spring) * d_dot
            elastic += spring
        if f <= 0.0:
            continue
        ff = share * mu * f if stuck else contact.sliding_friction(p, base, f, v)
        fcx = -f * gx + ff * tx
        fcy = -f * gy + ff * ty
        fx += fcx
        fy += fcy
        moment += (x - px) * fcy - (y - py) * fcx
        torque -= ff * arm + f * slope
        fn_sum += f
        p_friction += ff * v
        m_centre += x * fcy - y * fcx
        v_sum += f * v
    fn_rec, ff_rec, xr, yr = _equivalent(fx, fy, m_centre, p[L.P_DRUM_RADIUS])
    if fn_sum > 0.0:
        v_rec = v_sum / fn_sum
    elif eps > -math.inf:  # nothing presses: the deepest node's place and sliding speed
        deep = node_state(p, base, c, sn, w, cb_deep, sb_deep, drum_angle, drum_speed)
        v_rec, xr, yr = deep[7], deep[8], deep[9]
    else:
        v_rec, xr, yr = 0.0, 0.0, 0.0
    tdx = p[base + L.S_TIP_X] - px
    tdy = p[base + L.S_TIP_Y] - py
    tx = c * tdx - sn * tdy
    ty = sn * tdx + c * tdy
    fex = actuation * p[base + L.S_ACTUATION_DIR_X]
    fey = actuation * p[base + L.S_ACTUATION_DIR_Y]
    moment += tx * fey - ty * fex
    theta_ddot = s * moment / p[base + L.S_INERTIA] if enabled else 0.0
    p_act = fex * (-w * ty) + fey * (w * tx)
    return (
        theta_ddot,
        torque,
        eps,
        eps_dot,
        fn_rec,
        ff_rec,
        v_rec,
        xr,
        yr,
        fx + fex,
        fy + fey,
        p_friction,
        p_loss + contact.wear_loss(p, base, elastic, p_friction) if enabled else 0.0,
        p_act,
    )


@njit(inline="always", **JIT)
def _equivalent(fx, fy, moment, radius):
    """The point contact equivalent to the contact force ``(fx, fy)`` (N, on the shoe)
    whose moment about the drum centre is ``moment`` (N m): (normal force N, friction
    force N, point x m, point y m) of a point at ``radius`` (m) from the centre where a
    normal force along the inward radial and a friction force along the counter-clockwise
    tangent sum to that force with that moment (the resultant's line of action crosses the
    circle there, pressing): friction ``moment / radius``, normal
    ``sqrt(|F|^2 - friction^2)``. (0, 0, 0, 0) without a force."""
    size = math.sqrt(fx * fx + fy * fy)
    if size <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    ff = moment / radius
    ratio = max(-1.0, min(1.0, ff / size))
    fn = size * math.sqrt(1.0 - ratio * ratio)
    # the normal n = -(fn F + ff (z x F)) / |F|^2 (unit), so that -fn n + ff (z x n) = F
    nx = -(fn * fx - ff * fy) / (size * size)
    ny = -(fn * fy + ff * fx) / (size * size)
    return fn, ff, radius * nx, radius * ny


# Where the lining's circle stays this far (m) inside a round drum, no node can touch it:
# a node's computed penetration exceeds the circle's by rounding alone (2e-16 m where the
# lining is concentric with the drum, its rest; below 1e-15 m always).
CLEAR_MARGIN_M = 1e-9


@njit(**JIT)
def switching(p, base, theta, omega, drum_angle, drum_speed, signs_only):
    """(largest penetration m, switching function m) of the lining: ``max_i min(delta_i,
    delta_i + tau delta_i')`` is positive exactly when some node penetrates and pushes
    (:func:`shoe_contact`), and continuous in the state. A removed shoe: (-1, -1).

    ``signs_only``: for a step's end, which reads the two signs alone (the next step's
    contact modes, whether the shoe touches) besides an upper bound of the penetration (the
    free-ride bound's). Then, on a round drum whose lining's whole circle stays clear of it
    by more than :data:`CLEAR_MARGIN_M` (``|C| + r - R``: ``C`` the arc's centre, ``r`` its
    radius, ``R`` the drum's), both are that clearance less the margin (m, negative: an
    upper bound of both whatever the nodes' rounding), without a node. The location of a
    switch inside a step reads the values (False)."""
    if p[base + L.S_ENABLED] <= 0.0:
        return -1.0, -1.0
    s = p[base + L.S_SIGN]
    phi = s * theta
    c = math.cos(phi)
    sn = math.sin(phi)
    if signs_only and p[L.P_DRUM_WAVE_COUNT] <= 0.0 and p[L.P_FLAT_DEPTH] <= 0.0:
        cx, cy = contact.arc_centre(p, base, c, sn)
        reach = math.sqrt(cx * cx + cy * cy) + p[base + L.S_LINING_RADIUS] - p[L.P_DRUM_RADIUS]
        if reach < -CLEAR_MARGIN_M:
            return reach + CLEAR_MARGIN_M, reach + CLEAR_MARGIN_M
    tau = p[L.P_LINING_NODE_DAMPING] / p[L.P_LINING_NODE_STIFFNESS]
    eps = -math.inf
    h = -math.inf
    cb, sb, cd_, sd_ = first_node(p, base)
    for _ in range(NODES):
        d, d_dot, _, _, _, _, _, _, _ = node_depth(
            p, base, c, sn, s * omega, cb, sb, drum_angle, drum_speed
        )
        cb, sb = cb * cd_ - sb * sd_, sb * cd_ + cb * sd_
        eps = max(eps, d)
        h = max(h, min(d, d + tau * d_dot))
    return eps, h


@njit(**JIT)
def hold(p, base, theta, drum_angle):
    """What the lining of the shoe at ``theta`` (rad, at rest) does on a held drum at
    ``drum_angle``: (the torque its normal forces put on the drum N m, ``-sum f_i r'_i``;
    its static capacity N m, ``sum mu f_i arm_i``)."""
    if p[base + L.S_ENABLED] <= 0.0:
        return 0.0, 0.0
    phi = p[base + L.S_SIGN] * theta
    c = math.cos(phi)
    sn = math.sin(phi)
    k = p[L.P_LINING_NODE_STIFFNESS]
    mu = p[base + L.S_FRICTION_COEFFICIENT]
    torque = 0.0
    capacity = 0.0
    cb, sb, cd_, sd_ = first_node(p, base)
    for _ in range(NODES):
        d, _, x, y, nx, ny, slope, dist, _ = node_depth(
            p, base, c, sn, 0.0, cb, sb, drum_angle, 0.0
        )
        cb, sb = cb * cd_ - sb * sd_, sb * cd_ + cb * sd_
        if d > 0.0:
            f = k * d
            torque -= f * slope
            capacity += mu * f * node_tail(p, base, 0.0, 0.0, x, y, nx, ny, slope, dist)[4]
    return torque, capacity


@njit(inline="always", **JIT)
def shoe_energy(p, base, theta, drum_angle):
    """Elastic energy of the lining foundation of the shoe at ``base`` at the shoe angle
    ``theta`` and the drum angle ``drum_angle`` (rad), ``sum k_i max(delta_i, 0)^2 / 2``,
    J; 0 for a shoe removed from the model."""
    if p[base + L.S_ENABLED] <= 0.0:
        return 0.0
    k = p[L.P_LINING_NODE_STIFFNESS]
    phi = p[base + L.S_SIGN] * theta
    c = math.cos(phi)
    sn = math.sin(phi)
    cb, sb, cd_, sd_ = first_node(p, base)
    energy = 0.0
    for _ in range(NODES):
        d = node_depth(p, base, c, sn, 0.0, cb, sb, drum_angle, 0.0)[0]
        cb, sb = cb * cd_ - sb * sd_, sb * cd_ + cb * sd_
        if d > 0.0:
            energy += 0.5 * k * d * d
    return energy


@njit(**JIT_ALLOCATING)
def stored_energy_rows(p, left_angle, right_angle, drum_angle):
    """Elastic energy of both linings' foundations (J, :func:`shoe_energy`) at each row of
    shoe and drum angles (rad, arrays of one length)."""
    out = np.zeros(left_angle.shape[0])
    for row in range(left_angle.shape[0]):
        out[row] = shoe_energy(p, L.P_SHOE_BASE, left_angle[row], drum_angle[row])
        out[row] += shoe_energy(p, L.P_SHOE_BASE + L.SHOE_STRIDE, right_angle[row], drum_angle[row])
    return out
