"""Shoe-drum contact, compiled (numba): geometry, the contact law, friction and the shoe's
moment balance. Each rule is written here once; the fixed-step kernel, the reference
solver (through :mod:`brake_sim_ros.model.kernel`), the quasi-static contact-regime model,
the step-limit analysis and the assembly checks all call these functions.

Contact geometry. A shoe is rigid and turns by ``phi = sign * theta`` about its pivot
``P``. Its lining is an arc of radius ``r`` around the point ``C`` (see
:func:`brake_sim_ros.model.placement.place_shoe` for where ``C`` sits in the assembled
brake). The lining point farthest from the drum centre is on the ray from the origin
through ``C`` when that ray crosses the arc, otherwise at the arc end angularly nearest to
it; its distance from the centre minus ``R_d`` is the indentation ``eps`` (m, positive =
penetration). The normal is the drum's outward normal there. An out-of-round drum
(:func:`drum_radius`) puts its local radius in place of ``R_d`` and tilts the normal by its
slope (:func:`kinematics`).

Contact law. Kelvin-Voigt, ``Fn = k_c eps + c_c eps_dot`` while in contact, never
negative (a contact never pulls). Friction: Coulomb, smoothed ``Ff = mu Fn tanh(v / v_s)``
while the drum slides; while the drum sticks at standstill, the static friction that holds
it (see :mod:`brake_sim_ros.model.standstill`), a share ``lambda`` in [-1, 1] of each shoe's
capacity ``mu Fn``.

Frames and signs: the backing-plate frame (x right, y up, z out of the wheel); forces in N
on the shoe; the friction force acts along the drum's counter-clockwise tangent
``(-ny, nx)`` and its torque on the drum is ``-Ff * dist`` (on an out-of-round drum
``-Ff`` times the tangent's arm, plus the normal force's ``-Fn dr/dpsi``).
"""

from __future__ import annotations

import math

from numba import njit

from brake_sim_ros.model import layout as L
from brake_sim_ros.model.compiled import JIT
from brake_sim_ros.model.smooth_sign import smooth_sign

# Largest surface slope of the drum, ``sum_k k a_k / R0`` (rad): the contact geometry tilts
# the normal by the local slope at one contact point, a small-slope model; 0.05 (a tilt of
# 2.9 deg) is far above service runouts (150 um of order 2 on a 180 mm drum: 0.0017).
MAX_DRUM_SLOPE = 0.05

# shoe_eval result slots (named so that callers never write a bare index)
E_THETA_DDOT = 0  # shoe angular acceleration, rad/s^2 (positive outward)
E_DRUM_TORQUE = 1  # torque of this shoe's friction on the drum, N m
E_EPS = 2  # indentation, m
E_EPS_DOT = 3  # indentation rate, m/s
E_FN = 4  # normal force, N
E_FF = 5  # friction force, N
E_V_SLIDE = 6  # sliding speed of the drum surface relative to the shoe, m/s
E_CONTACT_X = 7  # contact point, m
E_CONTACT_Y = 8
E_APPLIED_X = 9  # contact + friction + actuation force on the shoe, N
E_APPLIED_Y = 10
E_FRICTION_POWER = 11  # W, dissipated by friction
E_CONTACT_POWER = 12  # W, dissipated by the Kelvin-Voigt damper (and by the wear: wear_loss)
E_ACTUATION_POWER = 13  # W, supplied by the actuator
N_EVAL = 14


@njit(inline="always", **JIT)
def arc_centre(p, base, c, sn):
    """Centre of the lining's arc for the shoe at ``base`` turned about its pivot by phi
    (cos ``c``, sin ``sn``): (x, y), m."""
    px = p[base + L.S_PIVOT_X]
    py = p[base + L.S_PIVOT_Y]
    dx = p[base + L.S_LINING_CENTRE_X] - px
    dy = p[base + L.S_LINING_CENTRE_Y] - py
    return px + c * dx - sn * dy, py + sn * dx + c * dy


@njit(inline="always", **JIT)
def contact_point(p, base, c, sn):
    """Lining point farthest from the drum centre for a shoe turned by phi (cos c, sin sn).

    Returns (x, y, distance from the drum centre, unit normal x, unit normal y, turn rate):
    m, m, m, 1, 1, and ``d(alpha)/d(phi)`` (1), the rate at which the point's polar angle
    ``alpha`` turns with the shoe (on the ray through the arc centre ``C`` the point slides
    along the lining: ``C.(C - P) / |C|^2``; at an arc end it is a material point:
    ``X.(X - P) / |X|^2``).
    """
    px = p[base + L.S_PIVOT_X]
    py = p[base + L.S_PIVOT_Y]
    cx, cy = arc_centre(p, base, c, sn)
    m0x = p[base + L.S_LINING_MID_COS]
    m0y = p[base + L.S_LINING_MID_SIN]
    mx = c * m0x - sn * m0y
    my = sn * m0x + c * m0y
    r = p[base + L.S_LINING_RADIUS]
    ce = math.sqrt(cx * cx + cy * cy)
    if ce > 1e-300:
        ux = cx / ce
        uy = cy / ce
    else:
        ux = mx
        uy = my
    if ux * mx + uy * my >= p[base + L.S_LINING_HALF_COS]:
        # the ray from the drum centre through the arc centre crosses the lining
        turn = (cx * (cx - px) + cy * (cy - py)) / (ce * ce) if ce > 1e-150 else 0.0
        return cx + r * ux, cy + r * uy, ce + r, ux, uy, turn
    hc = p[base + L.S_LINING_HALF_COS]
    hs = p[base + L.S_LINING_HALF_SIN]
    if mx * uy - my * ux < 0.0:
        hs = -hs
    ex = hc * mx - hs * my
    ey = hs * mx + hc * my
    xx = cx + r * ex
    xy = cy + r * ey
    dist = math.sqrt(xx * xx + xy * xy)
    return xx, xy, dist, xx / dist, xy / dist, (xx * (xx - px) + xy * (xy - py)) / (dist * dist)


@njit(inline="always", **JIT)
def drum_radius(p, psi):
    """Radius of the drum at the angle ``psi`` of its own frame (rad) and its slope.

    ``r(psi) = R0 + sum_k a_k cos(k psi + phi_k)`` over the packed harmonics
    (layout.P_DRUM_WAVE_*; :class:`brake_sim_ros.model.defects.DrumDefect`), less a local
    flat (layout.P_FLAT_*; :class:`brake_sim_ros.model.defects.DrumFlat`): a dip of depth
    ``d`` and half width ``w`` about the angle ``c``, ``d (1 + cos(pi x / w)) / 2`` for
    ``|x| < w`` (``x = psi - c`` wrapped to [-pi, pi)), whose slope is continuous. Returns
    (r m, dr/dpsi m/rad).
    """
    r = p[L.P_DRUM_RADIUS]
    slope = 0.0
    for j in range(int(p[L.P_DRUM_WAVE_COUNT])):
        b = L.P_DRUM_WAVE_BASE + j * L.DRUM_WAVE_STRIDE
        k = p[b + L.W_ORDER]
        a = p[b + L.W_AMPLITUDE]
        arg = k * psi + p[b + L.W_PHASE]
        r += a * math.cos(arg)
        slope -= k * a * math.sin(arg)
    depth = p[L.P_FLAT_DEPTH]
    if depth > 0.0:
        x = psi - p[L.P_FLAT_CENTRE]
        x -= 2.0 * math.pi * math.floor(x / (2.0 * math.pi) + 0.5)
        half = p[L.P_FLAT_HALF_WIDTH]
        if abs(x) < half:
            arg = math.pi * x / half
            r -= 0.5 * depth * (1.0 + math.cos(arg))
            slope += 0.5 * depth * math.pi / half * math.sin(arg)
    return r, slope


@njit(inline="always", **JIT)
def kinematics(p, base, theta, omega, drum_angle, drum_speed):
    """Contact kinematics of a shoe at angle ``theta`` (rad) turning at ``omega`` (rad/s)
    against a drum at ``drum_angle`` (rad) turning at ``drum_speed`` (rad/s, about +z).

    Returns (eps m, eps_dot m/s, tangential speed of the shoe's material point at the
    contact along the drum's tangent (-ny, nx) m/s, contact x m, contact y m, friction arm
    m, normal x, normal y, cos phi, sin phi, contact-force direction x, y, wave arm m):

    * round drum (no harmonics nor flat packed): ``eps = |X| - R0`` at the lining point ``X``
      farthest from the centre, the normal and the contact-force direction are the radial
      unit vector, the friction arm is ``|X|`` and the wave arm 0.
    * out-of-round drum (harmonics, a flat): ``eps = g = |X| - r(psi)``, the radial
      penetration of ``X`` into
      the drum's local radius (``psi = alpha - drum_angle``, ``alpha`` the polar angle of
      ``X``). The normal is the drum surface's, tilted by its slope:
      ``grad g = e_r - (r'/|X|) e_t`` normalised; friction acts along its tangent, whose
      arm about the drum centre is ``|X| / |grad g|``. The contact force on the shoe is
      ``-f q`` for the Kelvin-Voigt force ``f``, with ``q`` chosen so that the moments it
      applies are exactly the gradients of the contact's elastic energy ``k g^2 / 2``:
      on the drum ``-f r'`` (the wave arm ``r'``: a non-round drum turning under a
      pressed shoe works against the normal force), on the shoe ``-f dg/dphi``. ``q`` is
      ``grad g`` plus a radial term of order ``r'/|P|`` from the contact point sliding
      along the lining as the shoe turns (:func:`contact_point`); the energy books
      (analysis/energy.py) then close exactly as for the round drum.
    """
    s = p[base + L.S_SIGN]
    px = p[base + L.S_PIVOT_X]
    py = p[base + L.S_PIVOT_Y]
    phi = s * theta
    c = math.cos(phi)
    sn = math.sin(phi)
    xx, xy, dist, nx, ny, turn = contact_point(p, base, c, sn)
    w = s * omega
    # velocity of the shoe's material point at the contact
    vx = -w * (xy - py)
    vy = w * (xx - px)
    if p[L.P_DRUM_WAVE_COUNT] <= 0.0 and p[L.P_FLAT_DEPTH] <= 0.0:
        eps = dist - p[L.P_DRUM_RADIUS]
        eps_dot = nx * vx + ny * vy
        vt = -ny * vx + nx * vy
        return eps, eps_dot, vt, xx, xy, dist, nx, ny, c, sn, nx, ny, 0.0
    # a call, not inlined into every kinematics of the round drum's path
    return _out_of_round(
        p, px, py, xx, xy, dist, nx, ny, turn, vx, vy, w, c, sn, drum_angle, drum_speed
    )


@njit(**JIT)
def kinematics_pair(p, y, drum_speed):
    """Both shoes' :func:`kinematics` for the state ``y`` (layout ``Y_*``) with the drum
    turning at ``drum_speed`` (rad/s). A call, not inlined, where a kernel needs them
    afresh (a step's start after a switch or a lock, or on a path that holds nothing; the
    energy a growing defect's step moves): each inlined copy compiles on its own."""
    wa = y[L.Y_DRUM_ANGLE]
    bl = L.P_SHOE_BASE
    br = L.P_SHOE_BASE + L.SHOE_STRIDE
    kin_l = kinematics(p, bl, y[L.Y_LEFT_ANGLE], y[L.Y_LEFT_SPEED], wa, drum_speed)
    kin_r = kinematics(p, br, y[L.Y_RIGHT_ANGLE], y[L.Y_RIGHT_SPEED], wa, drum_speed)
    return kin_l, kin_r


@njit(**JIT)
def _out_of_round(p, px, py, xx, xy, dist, nx, ny, turn, vx, vy, w, c, sn, drum_angle, drum_speed):
    """:func:`kinematics` on an out-of-round drum (harmonics, a flat), from the lining point
    ``X`` = (``xx``, ``xy``) at ``dist`` from the centre, its radial unit vector
    (``nx``, ``ny``) and turn rate ``turn`` (:func:`contact_point`), the pin (``px``,
    ``py``), the material point's velocity (``vx``, ``vy``), the shoe's turn rate ``w``
    (rad/s, outward) and ``cos``/``sin`` of its angle (``c``, ``sn``)."""
    radius, r_slope = drum_radius(p, math.atan2(xy, xx) - drum_angle)
    eps = dist - radius
    tilt = r_slope / dist
    norm = math.sqrt(1.0 + tilt * tilt)
    # grad g = e_r - tilt e_t, e_t = (-ny, nx)
    gx = nx + tilt * ny
    gy = ny - tilt * nx
    # moment arms about the pivot of the radial and tangential directions at X
    arm_r = (xx - px) * ny - (xy - py) * nx
    arm_t = (xx - px) * nx + (xy - py) * ny
    # dg/dphi = arm_r - r' turn; dg/d(drum angle) = r'
    eps_dot = w * (arm_r - r_slope * turn) + r_slope * drum_speed
    # q = q_r e_r - tilt e_t: tangential part fixed by the drum's moment (X x q = -r'),
    # radial part by the shoe's ((X - P) x q = dg/dphi)
    q_r = 1.0 - r_slope * (turn - arm_t / dist) / arm_r
    qx = q_r * nx + tilt * ny
    qy = q_r * ny - tilt * nx
    tx = -gy / norm
    ty = gx / norm
    vt = tx * vx + ty * vy
    return eps, eps_dot, vt, xx, xy, dist / norm, gx / norm, gy / norm, c, sn, qx, qy, r_slope


@njit(inline="always", **JIT)
def normal_force(p, base, eps, eps_dot, mode):
    """Kelvin-Voigt normal force, N: on while ``eps > 0`` (``CONTACT_AUTO``) or as forced by
    ``mode``; never negative; zero for a shoe removed from the model."""
    in_contact = eps > 0.0 if mode == L.CONTACT_AUTO else mode == L.CONTACT_ON
    if not (in_contact and p[base + L.S_ENABLED] > 0.0):
        return 0.0
    fn = p[L.P_CONTACT_STIFFNESS] * eps + p[L.P_CONTACT_DAMPING] * eps_dot
    return fn if fn > 0.0 else 0.0


@njit(inline="always", **JIT)
def switching_function(p, base, theta, omega, drum_angle, drum_speed):
    """Indentation ``eps`` and switching function ``h`` of one shoe, both in m (shoe and
    drum angles and speeds as for :func:`kinematics`).

    ``h = min(eps, eps + (c_c / k_c) eps_dot)``: the Kelvin-Voigt force of
    :func:`normal_force` is on exactly when ``h > 0`` (the lining penetrates and the force
    would push). Both arguments of the min are lengths, so ``h`` is continuous in the state
    and its zero is the switching instant: ``eps = 0`` at an onset (where the force jumps
    from 0 to ``c_c eps_dot``), ``k_c eps + c_c eps_dot = 0`` at a separation (where it
    reaches 0 continuously, with a kink). A removed shoe returns (-1, -1): never on.
    """
    if p[base + L.S_ENABLED] <= 0.0:
        return -1.0, -1.0
    return switching_of(p, kinematics(p, base, theta, omega, drum_angle, drum_speed))


@njit(inline="always", **JIT)
def switching_of(p, kin):
    """:func:`switching_function` (``eps`` and ``h``, m) of a shoe in the model from its
    contact kinematics ``kin`` (:func:`kinematics`)."""
    eps = kin[0]
    g = eps + p[L.P_CONTACT_DAMPING] / p[L.P_CONTACT_STIFFNESS] * kin[1]
    return eps, min(eps, g)


@njit(inline="always", **JIT)
def sliding_friction(p, base, fn, v_slide):
    """Smoothed Coulomb friction force while the drum slides, N: ``mu Fn tanh(v / v_s)``
    with ``mu`` the lining's of the shoe at ``base`` (a friction-change defect sets it)."""
    if fn <= 0.0:
        return 0.0
    mu = p[base + L.S_FRICTION_COEFFICIENT]
    return mu * fn * smooth_sign(v_slide / p[L.P_FRICTION_SMOOTHING_SPEED])


@njit(inline="always", **JIT)
def tip_load(p, base, c, sn, actuation):
    """The actuation ``actuation`` (N, along the cylinder axis, a fixed world direction)
    on the tip of the shoe turned by phi (cos ``c``, sin ``sn``): (the tip's place from the
    pivot x and y m, the force's x and y components N)."""
    tdx = p[base + L.S_TIP_X] - p[base + L.S_PIVOT_X]
    tdy = p[base + L.S_TIP_Y] - p[base + L.S_PIVOT_Y]
    tx = c * tdx - sn * tdy
    ty = sn * tdx + c * tdy
    return (
        tx,
        ty,
        actuation * p[base + L.S_ACTUATION_DIR_X],
        actuation * p[base + L.S_ACTUATION_DIR_Y],
    )


@njit(inline="always", **JIT)
def free_acceleration(p, base, actuation, c, sn):
    """:func:`shoe_forces`' angular acceleration (rad/s^2, outward) of a shoe turned by phi
    (cos ``c``, sin ``sn``) whose lining exerts nothing (normal and
    friction force 0.0): the tip's ``actuation`` (N) alone, by the same expressions. The
    contact's moment is then a zero, which :func:`shoe_forces` adds to the tip's: the same
    bits, but for the sign of a zero where the tip's moment is an exact zero (a zero adds to
    the state as the other does)."""
    if p[base + L.S_ENABLED] <= 0.0:
        return 0.0
    tx, ty, fex, fey = tip_load(p, base, c, sn, actuation)
    moment = 0.0 + tx * fey - ty * fex
    return p[base + L.S_SIGN] * moment / p[base + L.S_INERTIA]


@njit(inline="always", **JIT)
def shoe_forces(p, base, omega, actuation, kin, fn, ff, v_slide):
    """Moment balance of one shoe given its contact kinematics ``kin`` (from
    :func:`kinematics`), normal force ``fn`` and friction force ``ff`` (N), and the
    sliding speed ``v_slide`` (m/s) against which friction works. The drum torque is the
    friction's (``-ff`` times its arm) plus, on an out-of-round drum, the normal force's
    (``-fn`` times the wave arm ``dr/dpsi``).

    Returns the :data:`N_EVAL` slots of :func:`shoe_eval`.
    """
    eps, eps_dot, _vt, xx, xy, arm, nx, ny, c, sn, qx, qy, wave_arm = kin
    s = p[base + L.S_SIGN]
    px = p[base + L.S_PIVOT_X]
    py = p[base + L.S_PIVOT_Y]
    enabled = p[base + L.S_ENABLED] > 0.0
    w = s * omega
    fcx = -fn * qx - ff * ny
    fcy = -fn * qy + ff * nx
    tx, ty, fex, fey = tip_load(p, base, c, sn, actuation)
    moment = (xx - px) * fcy - (xy - py) * fcx + tx * fey - ty * fex
    theta_ddot = s * moment / p[base + L.S_INERTIA] if enabled else 0.0
    p_contact = 0.0
    if enabled:
        # Kelvin-Voigt loss: power into the contact minus the rate of the elastic energy
        # k max(eps, 0)^2 / 2 that the balance counts (also while the force is off: with
        # fn = 0 that elastic energy is lost, not returned). Not gated on eps > 0: a located
        # onset sits at eps == 0.0 exactly, where the force already pushes with c eps_dot.
        elastic = p[L.P_CONTACT_STIFFNESS] * max(eps, 0.0)
        p_contact = (fn - elastic) * eps_dot + wear_loss(p, base, elastic, ff * v_slide)
    p_act = fex * (-w * ty) + fey * (w * tx)
    return (
        theta_ddot,
        -ff * arm - fn * wave_arm,
        eps,
        eps_dot,
        fn,
        ff,
        v_slide,
        xx,
        xy,
        fcx + fex,
        fcy + fey,
        ff * v_slide,
        p_contact,
        p_act,
    )


@njit(inline="always", **JIT)
def wear_loss(p, base, elastic_force, friction_power):
    """Power (W) that a lining's wear takes out of its contact's elastic energy: the worn
    layer leaves with the strain it held, ``F_el dw/dt`` for the elastic force ``F_el`` (N,
    ``k max(eps, 0)``; a lining over its arc: its nodes' sum) and the wear rate ``dw/dt``,
    the shoe's wear per joule (layout.LN_WEAR_RATE) times its ``friction_power`` (W), as
    the wear state integrates it (kernel._wear_rates). 0 but for a lining that wears
    with its friction work. The indentation falls by the wear (the lining's radius is the
    unworn one less it), exactly where the deepest point lies between the lining's ends."""
    shoe = (base - L.P_SHOE_BASE) // L.SHOE_STRIDE
    rate = p[L.P_LINING_BASE + shoe * L.LINING_STRIDE + L.LN_WEAR_RATE]
    return elastic_force * rate * friction_power if rate > 0.0 else 0.0


@njit(inline="always", **JIT)
def sliding_speed(kin, drum_speed):
    """Sliding speed of the drum surface relative to the shoe at the contact, m/s."""
    return drum_speed * kin[5] - kin[2]


@njit(inline="always", **JIT)
def shoe_eval(
    p, base, theta, omega, drum_speed, actuation, mode, stuck=0, share=0.0, drum_angle=0.0
):
    """Forces on one shoe and what they do.

    Args:
        p: packed parameters. base: index of this shoe's block.
        theta, omega: shoe angle (rad) and speed (rad/s), positive outward.
        drum_speed: drum angular speed about +z, rad/s (0 while the drum sticks).
        actuation: actuation force on the tip, N (gain already applied).
        mode: CONTACT_AUTO (contact while eps > 0), CONTACT_OFF or CONTACT_ON.
        stuck: != 0 while the drum sticks at standstill: the friction force is the static
            share ``share`` (in [-1, 1]) of this shoe's capacity ``mu Fn``
            (:func:`brake_sim_ros.model.standstill.stuck_share`), not the sliding law.

    Returns:
        The :data:`N_EVAL` slots ``E_*``: (theta_ddot rad/s^2, drum torque N m, eps m,
        eps_dot m/s, Fn N, Ff N, sliding speed m/s, contact x m, contact y m, net applied
        force x N, net applied force y N, friction power W, contact loss power W,
        actuation power W). The net applied force is contact + friction + actuation.
    """
    kin = kinematics(p, base, theta, omega, drum_angle, drum_speed)
    fn = normal_force(p, base, kin[0], kin[1], mode)
    v_slide = sliding_speed(kin, drum_speed)
    mu = p[base + L.S_FRICTION_COEFFICIENT]
    ff = share * mu * fn if stuck else sliding_friction(p, base, fn, v_slide)
    return shoe_forces(p, base, omega, actuation, kin, fn, ff, v_slide)
