"""Largest fixed step the current parameters allow, from the stiffest linearised mode.

Two operating points bound the stiffness of the model:

* sliding: both shoes pressed by the largest actuation force, the drum turning at the
  lock speed (sliding speed = friction smoothing width), where the friction law is
  steepest before the brake locks;
* locked: the drum held at rest, the shoes still free to move on it, where the smoothed
  friction acts on the shoes as a viscous damper of slope mu Fn / v_s.

On the service brake, its shoes at rest on their stops and its tyre (model/tyre.py) where
it is stiffest: rolling with the wheel (the tread's presliding damper between drum and
flywheel) and a locked wheel sliding at :data:`TYRE_TOP_SPEED_RAD_S`.

At each, the Jacobian of the right-hand side (central differences, contact held on) gives
the eigenvalues ``lambda``. The step must keep every ``lambda dt`` inside the RK4
stability region (for symplectic Euler: the spectral radius of its one-step matrix of the
linearised system at most 1), with a 10 % margin, and must resolve the fastest oscillation with at
least ``STEPS_PER_PERIOD`` steps: past that, RK4 stays bounded but gives false impacts and
wrong stopping times long before anything diverges.

The service brake's line pressure is held at the source pressure of the forces in the
Jacobian (each piston then pushes what the ideal source would): the circuit's own rate
``1 / (R C)`` is tens per second, and its stiffness at a tip ``A^2 / C`` is a fraction of
a percent of the lining contact's, so it moves no eigenvalue that limits the step
(tests/model/test_hydraulics.py measures it with the pressure in the Jacobian).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from brake_sim_ros.model import kernel, lining, service, tyre
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import indentation_at, pack

STEPS_PER_PERIOD = 16
STABILITY_MARGIN = 0.9
# the service brake's tyre is linearised at this speed (rad/s): the largest initial speed
# a scenario may set (DrivelineParameters), where a locked tyre's deflection relaxes fastest
TYRE_TOP_SPEED_RAD_S = 400.0


@dataclass(frozen=True)
class StepLimit:
    """Step limit and where it comes from.

    Attributes:
        max_step_s: largest allowed fixed step, s.
        stability_step_s: RK4 stability limit alone (without the margin), s.
        resolution_step_s: limit from resolving the fastest oscillation, s.
        fastest_frequency_hz: fastest oscillatory mode, Hz.
        stiffest_rate_per_s: largest |lambda|, 1/s.
        reason: one sentence naming the limiting mode.
    """

    max_step_s: float
    stability_step_s: float
    resolution_step_s: float
    fastest_frequency_hz: float
    stiffest_rate_per_s: float
    reason: str


def _rk4_amplification(z: complex) -> float:
    return abs(1 + z + z * z / 2 + z**3 / 6 + z**4 / 24)


def rk4_stable_step(lam: complex) -> float:
    """Largest h with |R(lambda h)| <= 1 along the ray (inf for lambda with Re >= 0)."""
    if lam.real >= 0.0 or abs(lam) == 0.0:
        return math.inf
    lo, hi = 0.0, 3.0 / abs(lam)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if _rk4_amplification(lam * mid) <= 1.0:
            lo = mid
        else:
            hi = mid
    return lo


def _loaded_angle(p: np.ndarray, base: int, force_n: float, drum_speed: float) -> float:
    """Shoe angle where actuation, contact and sliding friction balance (rad)."""

    def eps(theta: float) -> float:
        return indentation_at(p, base, theta)

    hi = 0.5
    if eps(hi) <= 0.0:
        return 0.0
    onset = brentq(eps, -0.2, hi, xtol=1e-14) if eps(-0.2) < 0.0 else -0.2

    def moment(theta: float) -> float:
        if p[L.P_LINING_NODE_STIFFNESS] > 0.0:  # the service brake's lining over its arc
            return lining.shoe_contact(
                p, base, theta, 0.0, drum_speed, force_n, L.CONTACT_ON, 0, 0.0, 0.0
            )[0]
        return kernel.shoe_eval(p, base, theta, 0.0, drum_speed, force_n, L.CONTACT_ON)[0]

    if moment(onset) <= 0.0:  # a lining over its arc (its nodes, not the point) may hold it there
        return onset
    upper = onset + 1e-6
    while moment(upper) > 0.0 and upper < onset + 0.05:
        upper = onset + 2.0 * (upper - onset)
    if moment(upper) > 0.0:
        return upper  # self-locking: the contact never balances the actuation
    return brentq(moment, onset, upper, xtol=1e-15)


def _jacobian(
    y: np.ndarray,
    p: np.ndarray,
    fe: tuple[float, float],
    locked: int,
    modes: tuple[int, int],
    index: tuple[int, ...] = tuple(range(8)),
) -> np.ndarray:
    """Jacobian of the right-hand side at ``y`` over the states ``index`` (the angles and
    speeds by default; with the drum ``locked``, the shoes' only)."""
    n = len(index)
    jac = np.zeros((n, n))
    f_plus = np.zeros(y.shape[0])
    f_minus = np.zeros(y.shape[0])
    rows = list(index)
    for col, j in enumerate(index):
        h = 1e-7 * max(1.0, abs(y[j]))
        yp = y.copy()
        ym = y.copy()
        yp[j] += h
        ym[j] -= h
        kernel.rhs(yp, p, fe[0], fe[1], locked, modes[0], modes[1], f_plus)
        kernel.rhs(ym, p, fe[0], fe[1], locked, modes[0], modes[1], f_minus)
        jac[:, col] = (f_plus[rows] - f_minus[rows]) / (2 * h)
    if locked and n == 8:
        keep = [L.Y_LEFT_ANGLE, L.Y_RIGHT_ANGLE, L.Y_LEFT_SPEED, L.Y_RIGHT_SPEED]
        jac = jac[np.ix_(keep, keep)]
    return jac


def symplectic_euler_radius(jac: np.ndarray, dt: float) -> float:
    """Spectral radius of one symplectic-Euler step of ``y' = jac y``, y = (angles, speeds).

    Speeds first with the old state, then angles with the new speeds:
    ``v1 = v0 + dt (A x0 + B v0)``, ``x1 = x0 + dt (C x0 + D v1)``.
    """
    nv = jac.shape[0] // 2
    c, d = jac[:nv, :nv], jac[:nv, nv:]
    a, b = jac[nv:, :nv], jac[nv:, nv:]
    eye = np.eye(nv)
    m = np.block(
        [[eye + dt * c + dt * dt * d @ a, dt * d @ (eye + dt * b)], [dt * a, eye + dt * b]]
    )
    return float(max(abs(np.linalg.eigvals(m))))


def _symplectic_euler_radii(jac: np.ndarray, dts: np.ndarray) -> np.ndarray:
    """:func:`symplectic_euler_radius` of ``jac`` at each step of ``dts`` (s), from one
    stacked eigenvalue call (the scan of :func:`symplectic_euler_stable_step`)."""
    nv = jac.shape[0] // 2
    c, d = jac[:nv, :nv], jac[:nv, nv:]
    a, b = jac[nv:, :nv], jac[nv:, nv:]
    h = dts[:, None, None]
    eye = np.eye(nv)
    m = np.empty((dts.shape[0], 2 * nv, 2 * nv))
    m[:, :nv, :nv] = eye + h * c + (h * h * d) @ a
    m[:, :nv, nv:] = (h * d) @ (eye + h * b)
    m[:, nv:, :nv] = h * a
    m[:, nv:, nv:] = eye + h * b
    return np.abs(np.linalg.eigvals(m)).max(axis=1)


def symplectic_euler_stable_step(jacs: list[np.ndarray]) -> float:
    """Largest step (s) below which symplectic Euler is stable for every Jacobian in ``jacs``.

    Scanned upward from 1 ns in steps of 2 % (the first unstable step of that grid; the
    stable region need not be one interval) and refined by bisection. Rigid rotations give a
    double eigenvalue 1 of the one-step matrix, whose rounding moves it by ~1e-8: a radius
    up to 1 + 1e-6 counts as stable.
    """

    def stable(dt: float) -> bool:
        return all(symplectic_euler_radius(j, dt) <= 1.0 + 1e-6 for j in jacs)

    grid = [1e-9]
    while grid[-1] <= 1.0:
        grid.append(grid[-1] * 1.02)
    if not stable(grid[0]):
        return 0.0
    first_unstable = None
    chunk = 64  # grid steps a stacked call checks (the scan stops at its first unstable one)
    for start in range(1, len(grid), chunk):
        dts = np.array(grid[start : start + chunk])
        ok = np.ones(dts.shape[0], dtype=bool)
        for j in jacs:
            ok &= _symplectic_euler_radii(j, dts) <= 1.0 + 1e-6
        if not ok.all():
            first_unstable = start + int(np.argmin(ok))
            break
    if first_unstable is None or grid[first_unstable] > 1.0:
        return math.inf
    lo, hi = grid[first_unstable - 1], grid[first_unstable]
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo


def _state(p: np.ndarray, serviced: bool, fe: tuple[float, float]) -> np.ndarray:
    """A zero state of the run's size; a service brake's line at the source pressure of
    the actuation forces ``fe`` (N), so that each piston pushes its ``fe``."""
    if not serviced:
        return np.zeros(L.N_STATE)
    y = np.zeros(L.N_STATE_SERVICE)
    y[L.Y_LINE_PRESSURE] = service.line_source.py_func(p, fe[0], fe[1])
    return y


def _tyre_jacobians(p: np.ndarray, direction: float) -> list[np.ndarray]:
    """The service brake's tyre (model/tyre.py), linearised where it is stiffest: rolling
    with the wheel (the tread's presliding spring and damper between drum and flywheel,
    over their speeds and the deflection), and a locked wheel sliding at
    :data:`TYRE_TOP_SPEED_RAD_S` (the deflection relaxing at ``sigma0 |v_r| / g``, over
    the flywheel speed and the deflection)."""
    rolling = np.zeros(L.N_STATE_SERVICE)
    rolling[L.Y_FLYWHEEL_SPEED] = rolling[L.Y_DRUM_SPEED] = direction * TYRE_TOP_SPEED_RAD_S
    off = (L.CONTACT_OFF, L.CONTACT_OFF)
    index = (L.Y_FLYWHEEL_SPEED, L.Y_DRUM_SPEED, L.Y_TYRE_DEFLECTION)
    sliding = rolling.copy()
    sliding[L.Y_DRUM_SPEED] = 0.0
    slip = -direction * TYRE_TOP_SPEED_RAD_S * p[L.P_WHEEL_RADIUS]
    g = tyre.stribeck.py_func(
        slip,
        p[L.P_TYRE_SLIDING],
        p[L.P_TYRE_PEAK],
        p[L.P_TYRE_STRIBECK_SPEED],
        p[L.P_TYRE_STRIBECK_EXPONENT],
    )
    sliding[L.Y_TYRE_DEFLECTION] = math.copysign(g, slip) / p[L.P_TYRE_STIFFNESS]
    return [
        _jacobian(rolling, p, (0.0, 0.0), 0, off, index),
        _jacobian(sliding, p, (0.0, 0.0), 1, off, (L.Y_FLYWHEEL_SPEED, L.Y_TYRE_DEFLECTION)),
    ]


def _euler_stable_step(eigs: np.ndarray) -> float:
    """Largest step (s) keeping ``|1 + lambda h| <= 1`` for every eigenvalue: the
    explicit Euler update symplectic Euler gives the states beyond angles and speeds."""
    steps = [-2.0 * lam.real / abs(lam) ** 2 for lam in eigs if lam.real < 0.0]
    return min(steps, default=math.inf)


def step_limit(
    setup,
    max_actuation_n: float,
    *,
    packed: np.ndarray | None = None,
    scheme: str = "rk4",
) -> StepLimit:
    """Step limit for ``setup`` (a BrakeSetup) when actuation never exceeds ``max_actuation_n``.

    ``scheme``: "rk4" and "rk4-located" share RK4's stability region; "semi-implicit-euler"
    (symplectic Euler) has its own, computed from its one-step matrix.
    """
    p = pack(setup.params, setup.defects, setup.options) if packed is None else packed
    radius = p[L.P_DRUM_RADIUS]
    v_lock = p[L.P_FRICTION_SMOOTHING_SPEED]
    direction = 1.0 if setup.params.driveline.initial_speed_rad_s >= 0.0 else -1.0
    drum_speed = direction * v_lock / radius
    # a pulsating actuation peaks at (1 + its amplitude) times the force
    gains = tuple(
        p[b + L.S_ACTUATION_GAIN] * (1.0 + p[b + L.S_PULSATION_AMPLITUDE])
        for b in (L.P_SHOE_BASE, L.P_SHOE_BASE + L.SHOE_STRIDE)
    )
    # a weakened return spring adds the preload it lost (model/actuation.py spring_release)
    fe = tuple(
        max_actuation_n * g + p[b + L.S_SPRING_RELEASE]
        for g, b in zip(gains, (L.P_SHOE_BASE, L.P_SHOE_BASE + L.SHOE_STRIDE), strict=True)
    )
    serviced = p[L.P_SERVICE] > 0.0
    y = _state(p, serviced, fe)
    bases = (L.P_SHOE_BASE, L.P_SHOE_BASE + L.SHOE_STRIDE)
    for i, base in enumerate(bases):
        # a small load still engages the contact stiffness
        y[L.Y_LEFT_ANGLE + i] = _loaded_angle(p, base, max(fe[i], 1.0), 100.0 * direction)
    y[L.Y_DRUM_SPEED] = y[L.Y_FLYWHEEL_SPEED] = drum_speed
    on = (L.CONTACT_ON, L.CONTACT_ON)
    jacs = [_jacobian(y, p, fe, 0, on), _jacobian(y, p, fe, 1, on)]
    tyre_jacs = _tyre_jacobians(p, direction) if serviced else []
    if serviced:  # a service brake's shoes at rest on their stops (model/service.py)
        rest = _state(p, serviced, (0.0, 0.0))
        rest[L.Y_DRUM_SPEED] = rest[L.Y_FLYWHEEL_SPEED] = drum_speed
        for i, side in enumerate(L.SIDES):
            rest[L.Y_LEFT_ANGLE + i] = math.radians(getattr(setup.defects, side).initial_angle_deg)
        off = (L.CONTACT_OFF, L.CONTACT_OFF)
        jacs.append(_jacobian(rest, p, (0.0, 0.0), 0, off))
    tyre_eigs = np.concatenate([np.linalg.eigvals(j) for j in tyre_jacs or [np.zeros((0, 0))]])
    eigs = np.concatenate([*(np.linalg.eigvals(j) for j in jacs), tyre_eigs])
    if scheme == "semi-implicit-euler":
        stable = min(symplectic_euler_stable_step(jacs), _euler_stable_step(tyre_eigs))
        scheme_name = "symplectic Euler"
    else:
        stable = min((rk4_stable_step(complex(lam)) for lam in eigs), default=math.inf)
        scheme_name = "RK4"
    fastest = max(abs(lam.imag) for lam in eigs)
    resolution = 2.0 * math.pi / (STEPS_PER_PERIOD * fastest) if fastest > 0 else math.inf
    stiffest = max(abs(lam) for lam in eigs)
    limit = min(STABILITY_MARGIN * stable, resolution)
    if limit == resolution:
        stiffness = (
            f"lining nodes {lining.NODES} x {p[L.P_LINING_NODE_STIFFNESS]:.3g} N/m"
            if p[L.P_LINING_NODE_STIFFNESS] > 0.0
            else f"contact stiffness {p[L.P_CONTACT_STIFFNESS]:.3g} N/m"
        )
        reason = (
            f"the fastest oscillation ({fastest / (2 * math.pi):.0f} Hz, {stiffness}) needs at"
            f" least {STEPS_PER_PERIOD} steps per period"
        )
    else:
        reason = (
            f"{scheme_name} stability (with a {100 * (1 - STABILITY_MARGIN):.0f} % margin) of the"
            f" stiffest mode, rate {stiffest:.3g} 1/s: friction smoothed over"
            f" {v_lock:g} m/s under {max_actuation_n:g} N of actuation, and contact damping"
            f" {p[L.P_CONTACT_DAMPING]:g} N s/m"
        )
    return StepLimit(
        max_step_s=limit,
        stability_step_s=stable,
        resolution_step_s=resolution,
        fastest_frequency_hz=fastest / (2 * math.pi),
        stiffest_rate_per_s=stiffest,
        reason=reason,
    )
