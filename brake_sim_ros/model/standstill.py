"""Stick and slip of the drum at standstill: the one rule, compiled (numba).

The smoothed friction law ``mu Fn tanh(v / v_s)`` never truly sticks: below ``v_s`` it is a
viscous damper, and a twisted coupling spring would then drive the drum backwards (creep
reversal). The model therefore switches the drum between two states:

* **slipping** (the drum turns): friction follows the sliding law;
* **sticking** (the drum is held by static friction): the drum's speed is zero and its
  angle fixed; the friction at the shoes carries exactly the torque the coupling applies
  to the drum, ``K_s (th_f - th_d) + C_s (w_f - 0)``, shared between the shoes in
  proportion to their capacities ``mu Fn R`` (each shoe is loaded to the same fraction of
  what it can hold: the statically indeterminate split is resolved by the one rule that
  needs no further parameter). The flywheel keeps integrating its own equation,
  ``I_f w_f' = -K_s (th_f - th_d) - C_s w_f``: the vehicle rocks on the tyre and hub
  compliance while the wheel is held.

Transitions, evaluated at the end of every step (the same rule in every fidelity level and
in the reference solver, which locates them as events):

* slip -> stick when the drum's surface speed has fallen to ``v_s`` or below while not
  rising, and the static capacity ``mu (Fn_l r_l + Fn_r r_r)`` holds the coupling torque.
  The drum's remaining kinetic energy (at most ``I_d (v_s / R)^2 / 2``, 2.5e-4 J for the
  nominal brake) is booked as ``lock_loss_j``. With a rigid coupling (flywheel and drum
  one body) the whole rotor stops and its kinetic energy is booked.
* stick -> slip when the coupling torque exceeds the capacity: when the actuation is
  released, or a hard stop winds the coupling up beyond what the brake holds. Slipping
  starts from rest; the sliding law takes over.

The static coefficient equals the sliding one (``mu``): the model has no separate
breakaway friction.

Wheel lock and vehicle stop. The drum is light: in a hard stop it sticks within
milliseconds while the flywheel (the vehicle) still moves, winds the coupling up and
breaks the drum loose again. The first stick is the *wheel lock*. The *vehicle stop* is
the first instant the drum is held and the rotor's remaining energy, flywheel kinetic
plus coupling spring, ``I_f w_f^2 / 2 + K_s (th_f - th_d)^2 / 2``, is at most
``C^2 / (2 K_s)`` with ``C`` the static capacity: the rocking of the vehicle on the
coupling that follows can then never exceed what the brake holds (the coupling damper only
shrinks it). With a rigid coupling both instants coincide. On the study brake a wheel
lock holds the tyre, it does not skid.

The service brake couples flywheel and drum by its tyre (model/tyre.py) instead: the
torque the shoes hold is the tyre's on the drum (:func:`rotor_coupling`), and a locked
wheel whose tyre slides is the drum held by the shoes while the vehicle slides on, its
tyre's force limited by the road. Its vehicle stop: the drum held and the vehicle's kinetic
energy plus the tread's, ``I_f w_f^2 / 2 + sigma0 F_z z^2 / 2``, at most ``T^2 / (2 K)``
with ``K = sigma0 F_z R^2`` the tread's torsional stiffness and ``T`` the smaller of the
static capacity and the tyre's grip ``mu_s F_z R``: the vehicle settling on its tread can
then neither slide the tyre nor break the drum loose.
"""

from __future__ import annotations

from numba import njit

from brake_sim_ros.model import contact, lining, tyre
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.compiled import JIT


@njit(inline="always", **JIT)
def coupling_torque(p, flywheel_angle, drum_angle, flywheel_speed, drum_speed):
    """Torque of the torsional coupling on the drum, N m (positive counter-clockwise):
    ``K_s (th_f - th_d) + C_s (w_f - w_d)`` (rad, rad/s); 0 with a rigid coupling."""
    if p[L.P_RIGID_COUPLING] > 0.0:
        return 0.0
    twist = flywheel_angle - drum_angle
    slip = flywheel_speed - drum_speed
    return p[L.P_COUPLING_STIFFNESS] * twist + p[L.P_COUPLING_DAMPING] * slip


@njit(inline="always", **JIT)
def rotor_coupling(p, y, drum_speed):
    """(torque on the drum N m, positive counter-clockwise; the power the rotors give the
    tyre W, or 0 (the kernel books the coupling damper's loss itself); the tyre's
    deflection rate m/s, or 0) of
    what couples flywheel and drum in the state ``y`` at the drum speed ``drum_speed``
    (rad/s, 0 while it is held): the service brake's tyre (:func:`.tyre.coupling`), else
    the study brake's torsional coupling (:func:`coupling_torque`)."""
    if p[L.P_SERVICE] > 0.0:
        return tyre.coupling(p, y[L.Y_TYRE_DEFLECTION], y[L.Y_FLYWHEEL_SPEED], drum_speed)
    torque = coupling_torque(
        p, y[L.Y_FLYWHEEL_ANGLE], y[L.Y_DRUM_ANGLE], y[L.Y_FLYWHEEL_SPEED], drum_speed
    )
    return torque, 0.0, 0.0


@njit(inline="always", **JIT)
def static_capacity(p, fn_left, dist_left, fn_right, dist_right):
    """Largest torque the pressed shoes hold on the drum, N m: ``mu_l Fn_l r_l + mu_r Fn_r
    r_r`` (``r``: the friction arms about the drum centre, m; ``mu``: each lining's)."""
    mu_l = p[L.P_SHOE_BASE + L.S_FRICTION_COEFFICIENT]
    mu_r = p[L.P_SHOE_BASE + L.SHOE_STRIDE + L.S_FRICTION_COEFFICIENT]
    if mu_l == mu_r:  # factored: the same rounding as before linings could differ
        return mu_l * (fn_left * dist_left + fn_right * dist_right)
    return mu_l * fn_left * dist_left + mu_r * fn_right * dist_right


@njit(inline="always", **JIT)
def stuck_share(coupling, capacity):
    """Fraction (in [-1, 1]) of each shoe's capacity ``mu Fn`` that static friction uses to
    hold the drum against ``coupling`` (N m); 0 without capacity."""
    if capacity <= 0.0:
        return 0.0
    share = coupling / capacity
    if share > 1.0:
        return 1.0
    if share < -1.0:
        return -1.0
    return share


@njit(inline="always", **JIT)
def held_torque(coupling, fn_left, kin_left, fn_right, kin_right):
    """Torque static friction must hold on the drum, N m: the coupling's plus, on an
    out-of-round drum, the normal forces' (``-Fn dr/dpsi`` each, the wave arm of
    :func:`brake_sim_ros.model.contact.kinematics`; 0 on a round drum)."""
    return coupling - (fn_left * kin_left[12] + fn_right * kin_right[12])


@njit(inline="always", **JIT)
def hold_torques(p, y):
    """(torque to hold N m, static capacity N m) of the state ``y`` with the drum held:
    the coupling's torque on the drum (plus the normal forces' on an out-of-round drum,
    :func:`held_torque`) and what the pressed shoes can hold."""
    bl = L.P_SHOE_BASE
    br = L.P_SHOE_BASE + L.SHOE_STRIDE
    wa = y[L.Y_DRUM_ANGLE]
    if p[L.P_LINING_NODE_STIFFNESS] > 0.0:
        return _lined_hold_torques(p, y)
    kl = contact.kinematics(p, bl, y[L.Y_LEFT_ANGLE], y[L.Y_LEFT_SPEED], wa, 0.0)
    kr = contact.kinematics(p, br, y[L.Y_RIGHT_ANGLE], y[L.Y_RIGHT_SPEED], wa, 0.0)
    fnl = contact.normal_force(p, bl, kl[0], kl[1], L.CONTACT_AUTO)
    fnr = contact.normal_force(p, br, kr[0], kr[1], L.CONTACT_AUTO)
    capacity = static_capacity(p, fnl, kl[5], fnr, kr[5])
    coupling = rotor_coupling(p, y, 0.0)[0]
    return held_torque(coupling, fnl, kl, fnr, kr), capacity


@njit(**JIT)
def hold_torques_call(p, y):
    """:func:`hold_torques` as a call, for the tests made near or at a standstill only
    (:func:`sticks`, :func:`at_rest`); a held drum's step inlines it once
    (:func:`slips_held`, :func:`rests_held`). Each inlined copy (900 IR statements with
    the shoes' kinematics) compiles on its own: the fixed-step kernel's five copies were
    a fifth of its compile time."""
    return hold_torques(p, y)


@njit(**JIT)
def _lined_hold_torques(p, y):
    """:func:`hold_torques` of the service brake's lining over its arc (:func:`.lining.hold`).
    A call: the point contact's path stays as it was."""
    wa = y[L.Y_DRUM_ANGLE]
    tl, cl = lining.hold(p, L.P_SHOE_BASE, y[L.Y_LEFT_ANGLE], wa)
    tr, cr = lining.hold(p, L.P_SHOE_BASE + L.SHOE_STRIDE, y[L.Y_RIGHT_ANGLE], wa)
    return rotor_coupling(p, y, 0.0)[0] + tl + tr, cl + cr


@njit(inline="always", **JIT)
def sticks(p, y, surface_before):
    """Whether a slipping drum sticks at the end of a step that started with surface speed
    ``surface_before`` (m/s) and ended in state ``y``."""
    surface = abs(y[L.Y_DRUM_SPEED]) * p[L.P_DRUM_RADIUS]
    if surface > p[L.P_FRICTION_SMOOTHING_SPEED] or surface > surface_before:
        return False
    coupling, capacity = hold_torques_call(p, y)
    return capacity > 0.0 and abs(coupling) <= capacity


@njit(inline="always", **JIT)
def slips(p, y):
    """Whether a sticking drum breaks away in state ``y``: the coupling torque exceeds what
    the shoes hold (with a rigid coupling: the shoes no longer hold at all)."""
    coupling, capacity = hold_torques(p, y)
    return slips_held(p, coupling, capacity)


@njit(inline="always", **JIT)
def slips_held(p, coupling, capacity):
    """:func:`slips` of the state whose :func:`hold_torques` are ``coupling`` and
    ``capacity`` (N m)."""
    if p[L.P_RIGID_COUPLING] > 0.0:
        return capacity <= 0.0
    return abs(coupling) > capacity


@njit(inline="always", **JIT)
def at_rest(p, y):
    """Whether the vehicle has come to rest in the state ``y`` of a held drum: the rotor's
    remaining energy fits in the coupling below the static capacity (see the module notes)."""
    _coupling, capacity = hold_torques_call(p, y)
    return rests_held(p, y, capacity)


@njit(inline="always", **JIT)
def rests_held(p, y, capacity):
    """:func:`at_rest` of the state ``y`` whose static capacity (:func:`hold_torques`) is
    ``capacity`` (N m)."""
    if p[L.P_RIGID_COUPLING] > 0.0:
        return capacity > 0.0
    if p[L.P_SERVICE] > 0.0:
        return _tyre_at_rest(p, y, capacity)
    k_s = p[L.P_COUPLING_STIFFNESS]
    twist = y[L.Y_FLYWHEEL_ANGLE] - y[L.Y_DRUM_ANGLE]
    energy = 0.5 * p[L.P_FLYWHEEL_INERTIA] * y[L.Y_FLYWHEEL_SPEED] ** 2 + 0.5 * k_s * twist**2
    return energy <= 0.5 * capacity * capacity / k_s


@njit(**JIT)
def _tyre_at_rest(p, y, capacity):
    """:func:`at_rest` on the service brake: the vehicle's kinetic energy plus the tread's
    (``I_f w_f^2 / 2 + sigma0 F_z z^2 / 2``, the tread a torsional spring of ``sigma0 F_z
    R^2`` N m/rad at the twist ``z / R``) fits below the smaller of the brake's capacity
    and the tyre's grip ``mu_s F_z R``: the tyre then never slides again nor the brake
    lets go as the vehicle settles on its tread."""
    k = tyre.torsional_stiffness(p)
    limit = min(capacity, tyre.grip_torque(p))
    energy = 0.5 * p[L.P_FLYWHEEL_INERTIA] * y[L.Y_FLYWHEEL_SPEED] ** 2 + tyre.stored_energy(
        p, y[L.Y_TYRE_DEFLECTION]
    )
    return energy <= 0.5 * limit * limit / k


@njit(inline="always", **JIT)
def stick(p, y):
    """Hold the drum (and, with a rigid coupling, the flywheel) in ``y``; returns the kinetic
    energy removed, J."""
    loss = 0.5 * p[L.P_DRUM_INERTIA] * y[L.Y_DRUM_SPEED] ** 2
    y[L.Y_DRUM_SPEED] = 0.0
    if p[L.P_RIGID_COUPLING] > 0.0:
        loss += 0.5 * p[L.P_FLYWHEEL_INERTIA] * y[L.Y_FLYWHEEL_SPEED] ** 2
        y[L.Y_FLYWHEEL_SPEED] = 0.0
    return loss


@njit(inline="always", **JIT)
def interpolated_stick_time(t, h, surface_before, surface_after, v_lock):
    """Instant (s) within the step ``[t, t + h]`` at which the surface speed reached
    ``v_lock``, linearly interpolated (the end of the step if it was already below)."""
    frac = 1.0
    if surface_before > surface_after:
        frac = (surface_before - v_lock) / (surface_before - surface_after)
        frac = min(max(frac, 0.0), 1.0)
    return t + frac * h
