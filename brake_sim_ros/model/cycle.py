"""Drive cycles: named segments of driving and braking, and their controller (compiled).

A cycle (scenario table ``[cycle]``) is a list of segments run in order:

* ``accelerate`` to ``kmh``: the drive torque follows the speed controller below until
  the speed is within :data:`SPEED_TOLERANCE` of the target;
* ``cruise`` at ``kmh`` (default: the last target) for ``duration_s``, by the drive;
* ``brake`` at ``pressure_bar`` (or ``force_n`` per shoe) until the speed has fallen to
  ``until_kmh``; ``until_kmh = 0`` ends when the vehicle has come to rest (the drum held
  by static friction and the rotor's energy within what the brake holds: the stop rule of
  :func:`brake_sim_ros.model.standstill.at_rest`);
* ``hold`` the brake (``pressure_bar``/``force_n``, default the last brake's) for
  ``duration_s``; a hold where the vehicle stands may change its load (``load_factor``,
  below);
* ``release`` the brake (force ramped to 0, no drive) for ``duration_s``;
* ``drag`` at ``kmh`` for ``duration_s``: the brake holds the speed (no drive), as on a
  descent; its force is a PI controller's, limited to ``max_force_n``.

After the last segment the cycle has ended (phase ``end``): no drive, the brake force
kept. The brake force ramps linearly to each segment's over ``brake_rise_s`` (a hydraulic
rise, TESTBED: under 0.1 s for the hydraulics, 0.36 s for the whole brake response);
pressure becomes force on the default wheel-cylinder piston of the line-pressure sensor
(:data:`~brake_sim_ros.sensing.sensors.DEFAULT_PISTON_DIAMETER_M`, 19.05 mm: 46 bar is the
published 1300 N; the scenario loader converts), the force each shoe gets before its
actuation gain, as the ``[actuation]`` profile's.

The speed controller (accelerate, cruise) asks the flywheel torque
``I_f (w_target - w_f) / tau + T_road(w_f)`` (a first-order approach of the target with time
constant ``tau = speed_time_constant_s``, the road load fed forward) and gets it clamped to
``[0, max_drive_torque_n_m]``: the drive never brakes. The drag controller turns the speed
error into brake force with a PI law tuned on the nominal brake's torque per newton
(:data:`NOMINAL_BRAKE_GAIN_N_M_PER_N`, a tuning figure, not a model parameter).

Vehicle load per stop: a hold that follows a brake to a stop (``until_kmh = 0``), or
follows such a hold, may set the vehicle's load factor (passengers or cargo in or out
while it stands): a number, or a range ``[low, high]`` drawn anew at each such hold as it
starts, within :data:`~brake_sim_ros.model.vehicle.LOAD_FACTOR_RANGE`. The factor is the
vehicle's mass over the mass the run's flywheel inertia stands for (its load at the
start: 1); it scales the flywheel inertia and the mass's road load
(:func:`.vehicle.scale_load`) from that hold on, across laps of a repeating cycle, until
another hold changes it. The draw is counter-based: the ``k``-th draw of the run (``k``
counted in the kernel's bookkeeping, over laps) is a hash (splitmix64) of the run's key
(:func:`load_key` of its seed) and ``k``, so it depends on the seed and the stop's number
only, never on how the run is cut into chunks. A change at speed would ask where the mass
comes from and how it gets the vehicle's speed (a coupling, a drop of cargo): not modelled,
so the key is refused on any other segment. The vehicle's speed is kept as the load
changes (it stands: only the coupling's residual oscillation moves the flywheel); the
kinetic energy the change brings, ``(I_new - I_old) w_f^2 / 2``, is booked
(``load_change_work_j``) so that the energy books close.

Live drive (:class:`LiveDrive`, the node's ``~/drive``): a run with a vehicle and no
cycle takes drive commands that hold until the next one: coast (no drive torque), a
constant drive torque, or a target speed held by the same speed controller as an
accelerate or cruise segment (:func:`speed_control_torque`), with the settings of the
run's vehicle (``[vehicle]`` ``max_drive_torque_n_m``, ``speed_time_constant_s``;
default :data:`DEFAULT_MAX_DRIVE_TORQUE_N_M`, :data:`DEFAULT_SPEED_TIME_CONSTANT_S` as a
cycle's): a torque command above the vehicle's largest drive torque is refused
(:func:`torque_refusal`). A run with a cycle takes none: its cycle drives. The brake
stays the actuation history's (live actuation commands), so a rig drives stops with both.

Determinism: the controller runs inside the compiled stepping
(:func:`brake_sim_ros.model.advance.fixed_step_advance`) at the start of every physics
step, from the state at that instant, and holds its drive torque over the step (a
zero-order hold at the physics step); its state (segment, segment start, brake ramp, drag
integrator, load factor and draw count) is carried between calls in the kernel's
bookkeeping arrays (layout.K_SEGMENT, K_LOAD_DRAWS, layout.F_*), like the drum's stick
state. So a run gives the same bits however it is cut into chunks; a different preset
(another physics step) samples the controller at another rate.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numba import njit

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model import actuation, standstill, vehicle
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.actuation import MAX_ACTUATION_FORCE_N
from brake_sim_ros.model.compiled import JIT

KMH_PER_M_S = 3.6
SPEED_TOLERANCE = 0.01  # an acceleration ends within 1 % of its target speed
# Brake torque per newton of actuation of the nominal brake riding on the drum, N m/N: the
# published stop (1300 N per shoe, 103.5 rad/s of 17.1 kg m^2 in about 6.4 s of full force)
# takes about 277 N m. Only the drag controller's gains use it.
NOMINAL_BRAKE_GAIN_N_M_PER_N = 0.21
MAX_SPEED_KMH = 250.0
MAX_DURATION_S = 86_400.0
MAX_SPEED_M_S = MAX_SPEED_KMH / KMH_PER_M_S
# The speed controller's settings of a [cycle] by default, and of a live drive (the
# vehicle's, model/vehicle.py)
DEFAULT_MAX_DRIVE_TORQUE_N_M = vehicle.DEFAULT_MAX_DRIVE_TORQUE_N_M
DEFAULT_SPEED_TIME_CONSTANT_S = vehicle.DEFAULT_SPEED_TIME_CONSTANT_S
# A live drive command's modes, in the order of DriveCommand's MODE_* (msg_defs/)
DRIVE_MODES = ("coast", "torque", "target_speed")


@dataclass(frozen=True)
class Segment:
    """One segment of a cycle (see the module doc).

    Attributes:
        kind: one of ``layout.SEGMENT_KINDS`` but ``end``.
        speed_kmh: the target speed (accelerate, cruise, drag) or the speed a brake
            segment brakes to (``until_kmh``), km/h.
        force_n: brake force per shoe (brake, hold), N; 0 for the others.
        duration_s: how long (cruise, hold, release, drag), s; 0 for the others.
        load_factor: the vehicle load factor ``(low, high)`` a standing hold draws from
            at each stop (``low == high``: that factor), dimensionless; None: the load is
            kept (see the module doc).
    """

    kind: str
    speed_kmh: float = 0.0
    force_n: float = 0.0
    duration_s: float = 0.0
    load_factor: tuple[float, float] | None = None


# the controller's settings: (low, high) each (the scenario's [cycle] keys)
LIMITS: dict[str, tuple[float, float]] = {
    **{name: (lo, hi) for name, lo, hi in vehicle.DRIVE_LIMITS},
    "brake_rise_s": (1e-3, 10.0),
    "max_force_n": (0.0, MAX_ACTUATION_FORCE_N),
}


@dataclass(frozen=True)
class Cycle:
    """A drive cycle: segments and the controller's settings.

    Attributes:
        segments: the segments, in order (1 to ``layout.MAX_CYCLE_SEGMENTS``).
        max_drive_torque_n_m: largest drive torque on the flywheel, N m (this brake's
            share of the traction: 120 N m gives the nominal 17.1 kg m^2 about 1.8 m/s^2).
        speed_time_constant_s: the speed controllers' time constant, s.
        brake_rise_s: time the brake force takes to reach each segment's, s.
        max_force_n: the drag controller's brake force limit per shoe, N.
        repeat: after the last segment, start again at the first (a cycle without end,
            for a continuous run); else the cycle ends there (no drive, the brake kept).
        seed: the run's seed, which keys the per-stop load draws (the scenario loader
            sets it, 0 to 2^63 - 1).
    """

    segments: tuple[Segment, ...]
    max_drive_torque_n_m: float = DEFAULT_MAX_DRIVE_TORQUE_N_M
    speed_time_constant_s: float = DEFAULT_SPEED_TIME_CONSTANT_S
    brake_rise_s: float = 0.2
    max_force_n: float = 3000.0
    repeat: bool = False
    seed: int = 0

    def __post_init__(self) -> None:
        n = len(self.segments)
        if not 1 <= n <= L.MAX_CYCLE_SEGMENTS:
            raise ParameterError(f"cycle with {n} segments: allowed 1 to {L.MAX_CYCLE_SEGMENTS}")
        for name, (lo, hi) in LIMITS.items():
            value = getattr(self, name)
            if not (math.isfinite(value) and lo <= value <= hi):
                raise ParameterError(f"cycle {name} {value!r}: allowed {lo:g} to {hi:g}")
        for i, s in enumerate(self.segments):
            if s.kind not in L.SEGMENT_KINDS[:-1]:
                raise ParameterError(
                    f"cycle segment {i} kind {s.kind!r}: allowed one of"
                    f" {list(L.SEGMENT_KINDS[:-1])}"
                )
            for name, value, hi in (
                ("speed_kmh", s.speed_kmh, MAX_SPEED_KMH),
                ("force_n", s.force_n, MAX_ACTUATION_FORCE_N),
                ("duration_s", s.duration_s, MAX_DURATION_S),
            ):
                if not (math.isfinite(value) and 0.0 <= value <= hi):
                    raise ParameterError(
                        f"cycle segment {i} ({s.kind}) {name} {value!r}: allowed 0 to {hi:g}"
                    )
            if s.load_factor is not None:
                self._check_load(i, s)
        if isinstance(self.seed, bool) or not isinstance(self.seed, int):
            raise ParameterError(f"cycle seed {self.seed!r}: allowed an integer")
        if not 0 <= self.seed < 2**63:
            raise ParameterError(f"cycle seed {self.seed!r}: allowed 0 to 2^63 - 1")

    def _check_load(self, i: int, s: Segment) -> None:
        """Refuse segment ``i``'s load factor unless it is a range of the model's on a hold
        where the vehicle stands (see the module doc)."""
        lo, hi = vehicle.LOAD_FACTOR_RANGE
        low, high = s.load_factor
        if not (math.isfinite(low) and math.isfinite(high) and lo <= low <= high <= hi):
            raise ParameterError(
                f"cycle segment {i} ({s.kind}) load_factor [{low!r}, {high!r}]: allowed"
                f" low <= high within [{lo:g}, {hi:g}]"
            )
        if not (s.kind == "hold" and self.standing(i)):
            raise ParameterError(
                f"cycle segment {i} ({s.kind}) load_factor: allowed only on a hold where the"
                " vehicle stands (right after a brake with until_kmh = 0, or after such a hold)"
            )

    def standing(self, i: int) -> bool:
        """Whether the vehicle stands when segment ``i`` starts: segment ``i - 1`` is a
        brake to a stop, or a hold that starts standing (the first segment: never)."""
        for before in reversed(self.segments[:i]):
            if before.kind == "brake":
                return before.speed_kmh == 0.0
            if before.kind != "hold":
                return False
        return False

    @property
    def loads(self) -> bool:
        """Whether a segment changes the vehicle's load."""
        return any(s.load_factor is not None for s in self.segments)

    @property
    def peak_force_n(self) -> float:
        """The largest brake force per shoe the cycle can command, N."""
        drag = any(s.kind == "drag" for s in self.segments)
        return max([s.force_n for s in self.segments] + [self.max_force_n if drag else 0.0])

    @property
    def kinds(self) -> tuple[str, ...]:
        return tuple(s.kind for s in self.segments)

    def phase_names(self, segment: np.ndarray) -> np.ndarray:
        """The phase label of each value of a ``cycle_segment`` column: the segment's kind
        and index, ``"<index>:<kind>"`` (``"<n>:end"`` after the last; ``"none"`` for -1,
        a run without a cycle)."""
        names = np.array(["none", *(f"{i}:{k}" for i, k in enumerate([*self.kinds, "end"]))])
        return names[np.asarray(segment, dtype=np.int64) + 1]


@dataclass(frozen=True)
class LiveDrive:
    """A live drive command (see the module doc), held from the sample it reaches the
    stepper until the next one.

    Attributes:
        mode: one of :data:`DRIVE_MODES`: ``coast`` (no drive torque), ``torque``
            (``drive_torque_n_m``, constant) or ``target_speed`` (the speed controller
            toward ``target_speed_m_s``).
        drive_torque_n_m: drive torque on the flywheel, N m, forward; 0 to the largest a
            vehicle may have (``vehicle.DRIVE_LIMITS``; the drive never brakes); a run
            refuses one above its vehicle's (:func:`torque_refusal`). Mode torque only.
        target_speed_m_s: vehicle speed (flywheel speed x rolling radius), m/s, forward;
            0 to :data:`MAX_SPEED_M_S`. Mode target_speed only.

    Raises:
        ParameterError: an unknown mode, or a non-finite or out-of-range value of the
            field the mode uses (the other is not read).
    """

    mode: str = "coast"
    drive_torque_n_m: float = 0.0
    target_speed_m_s: float = 0.0

    def __post_init__(self) -> None:
        if self.mode not in DRIVE_MODES:
            raise ParameterError(f"drive mode {self.mode!r}: allowed one of {list(DRIVE_MODES)}")
        if self.mode == "torque":
            name, value, hi, unit = (
                "drive_torque_n_m",
                self.drive_torque_n_m,
                LIMITS["max_drive_torque_n_m"][1],
                "N m (the drive never brakes)",
            )
        elif self.mode == "target_speed":
            name, value, hi, unit = "target_speed_m_s", self.target_speed_m_s, MAX_SPEED_M_S, "m/s"
        else:
            return
        if not (isinstance(value, float | int) and math.isfinite(value) and 0.0 <= value <= hi):
            raise ParameterError(
                f"{name}={value!r}: allowed a finite value from 0 to {hi:.4g} {unit}"
            )


def torque_refusal(drive: LiveDrive, car: vehicle.Vehicle) -> str | None:
    """Why ``car`` refuses ``drive`` (one line naming its limit), or None: a torque command
    above its ``max_drive_torque_n_m``; the rule, written once."""
    limit = car.max_drive_torque_n_m
    if drive.mode == "torque" and drive.drive_torque_n_m > limit:
        return (
            f"drive_torque_n_m={drive.drive_torque_n_m:g} N m exceeds this run's"
            f" max_drive_torque_n_m = {limit:g} N m: allowed 0 to {limit:g} N m"
        )
    return None


def pack_live_drive(p: np.ndarray, drive: LiveDrive, car: vehicle.Vehicle) -> None:
    """Write ``drive`` into the packed vector ``p`` of a run with vehicle ``car`` and no
    cycle (P_DRIVE_TORQUE, P_LIVE_*; the speed controller's settings, ``car``'s, in
    P_CYCLE_MAX_DRIVE_TORQUE and P_CYCLE_TIME_CONSTANT), its target speed as a flywheel
    speed for the wheel radius packed (:func:`vehicle.pack_vehicle`)."""
    speed = drive.mode == "target_speed"
    p[L.P_CYCLE_MAX_DRIVE_TORQUE] = car.max_drive_torque_n_m
    p[L.P_CYCLE_TIME_CONSTANT] = car.speed_time_constant_s
    p[L.P_LIVE_SPEED_CONTROL] = 1.0 if speed else 0.0
    p[L.P_LIVE_TARGET_SPEED] = drive.target_speed_m_s / p[L.P_WHEEL_RADIUS] if speed else 0.0
    p[L.P_DRIVE_TORQUE] = drive.drive_torque_n_m if drive.mode == "torque" else 0.0


def resolved(segments: Sequence[Segment]) -> tuple[Segment, ...]:
    """``segments`` with the defaults a segment takes from those before it: a cruise's or
    drag's speed (0: the last target), a hold's force (0: the last brake's)."""
    out = []
    target = 0.0
    force = 0.0
    for s in segments:
        if s.kind in ("accelerate",):
            target = s.speed_kmh
        elif s.kind in ("cruise", "drag"):
            target = s.speed_kmh if s.speed_kmh > 0.0 else target
            s = Segment(s.kind, target, s.force_n, s.duration_s)
        elif s.kind == "brake":
            force = s.force_n
        elif s.kind == "hold" and s.force_n == 0.0:
            s = Segment(s.kind, s.speed_kmh, force, s.duration_s, s.load_factor)
        out.append(s)
    return tuple(out)


def pack_cycle(p: np.ndarray, cycle: Cycle) -> None:
    """Write ``cycle`` into the packed vector ``p`` (layout.P_CYCLE_*), its speeds as
    flywheel speeds for the wheel radius already packed (:func:`vehicle.pack_vehicle`)."""
    radius = p[L.P_WHEEL_RADIUS]
    p[L.P_CYCLE_COUNT] = float(len(cycle.segments))
    p[L.P_CYCLE_MAX_DRIVE_TORQUE] = cycle.max_drive_torque_n_m
    p[L.P_CYCLE_TIME_CONSTANT] = cycle.speed_time_constant_s
    p[L.P_CYCLE_RISE] = cycle.brake_rise_s
    p[L.P_CYCLE_MAX_FORCE] = cycle.max_force_n
    p[L.P_CYCLE_REPEAT] = 1.0 if cycle.repeat else 0.0
    key = load_key(cycle.seed)
    p[L.P_CYCLE_LOAD_KEY] = float(key >> 32)
    p[L.P_CYCLE_LOAD_KEY + 1] = float(key & 0xFFFF_FFFF)
    for j, s in enumerate(resolved(cycle.segments)):
        b = L.P_CYCLE_BASE + j * L.CYCLE_STRIDE
        p[b + L.Q_KIND] = float(L.SEGMENT_KINDS.index(s.kind))
        p[b + L.Q_SPEED] = s.speed_kmh / KMH_PER_M_S / radius
        p[b + L.Q_FORCE] = s.force_n
        p[b + L.Q_DURATION] = s.duration_s
        p[b + L.Q_LOAD_LOW], p[b + L.Q_LOAD_HIGH] = s.load_factor or (0.0, 0.0)


LOAD_DOMAIN = "brake_sim_ros cycle load"


def load_key(seed: int) -> int:
    """The 64-bit key of a run's per-stop load draws: the first 8 bytes (big-endian) of
    SHA-256 of :data:`LOAD_DOMAIN` and ``seed``."""
    digest = hashlib.sha256(f"{LOAD_DOMAIN} {int(seed)}".encode()).digest()
    return int.from_bytes(digest[:8], "big")


@njit(**JIT)
def load_draw(p, number):
    """The ``number``-th per-stop load draw (0, 1, ...) of the run whose key ``p`` packs
    (P_CYCLE_LOAD_KEY): uniform in [0, 1), the top 53 bits of splitmix64's output for
    ``key + (number + 1) * golden`` (counter-based: no state but the count)."""
    key = (np.uint64(p[L.P_CYCLE_LOAD_KEY]) << np.uint64(32)) | np.uint64(p[L.P_CYCLE_LOAD_KEY + 1])
    z = key + np.uint64(number + 1) * np.uint64(0x9E3779B97F4A7C15)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z = z ^ (z >> np.uint64(31))
    return float(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@njit(inline="always", **JIT)
def speed_control_torque(p, flywheel_speed, target):
    """The speed controller's drive torque (accelerate, cruise, a live target speed), N m:
    ``I_f (target - w_f) / tau + T_road(w_f)`` clamped to ``[0, max drive torque]``
    (module doc), for the flywheel speed and target in rad/s; the rule, written once."""
    ask = p[L.P_FLYWHEEL_INERTIA] * (target - flywheel_speed) / p[
        L.P_CYCLE_TIME_CONSTANT
    ] + vehicle.road_load_torque(p, flywheel_speed)
    return min(max(ask, 0.0), p[L.P_CYCLE_MAX_DRIVE_TORQUE])


@njit(**JIT)
def live_control(p, y):
    """A live target speed's drive torque at the start of a physics step, from the state
    ``y`` then, into ``p`` (the kernel's working copy, P_DRIVE_TORQUE; held over the step
    as a cycle's)."""
    p[L.P_DRIVE_TORQUE] = speed_control_torque(p, y[L.Y_FLYWHEEL_SPEED], p[L.P_LIVE_TARGET_SPEED])


@njit(**JIT)
def _enter(p, base, seg, y, kstate, fstate, t):
    """Start segment ``seg`` at ``t``: its brake ramp from the force now to its own; a
    hold with a load draws its factor (``base``: the packed vector the factor scales)."""
    # the ramp's knots are interleaved in fstate (times at T0 and T1, forces at F0 and F1)
    f_now = actuation.pwl(
        t, fstate[L.F_RAMP_T0 : L.F_RAMP_T1 + 1 : 2], fstate[L.F_RAMP_F0 : L.F_RAMP_F1 + 1 : 2]
    )
    fstate[L.F_SEGMENT_START] = t
    n = int(p[L.P_CYCLE_COUNT])
    if seg >= n:  # ended: keep the force
        target = f_now
    else:
        b = L.P_CYCLE_BASE + seg * L.CYCLE_STRIDE
        target = p[b + L.Q_FORCE]
        if int(p[b + L.Q_KIND]) == L.SEG_DRAG:
            fstate[L.F_DRAG_FORCE] = f_now
            target = f_now
        high = p[b + L.Q_LOAD_HIGH]
        if high > 0.0:  # a standing hold that changes the load (Cycle checks where)
            low = p[b + L.Q_LOAD_LOW]
            factor = low + load_draw(p, kstate[L.K_LOAD_DRAWS]) * (high - low)
            kstate[L.K_LOAD_DRAWS] += 1
            inertia = base[L.P_FLYWHEEL_INERTIA]
            change = inertia * factor - inertia * fstate[L.F_LOAD_FACTOR]
            fstate[L.F_LOAD_CHANGE_WORK] += 0.5 * change * y[L.Y_FLYWHEEL_SPEED] ** 2
            fstate[L.F_LOAD_FACTOR] = factor
    fstate[L.F_RAMP_T0] = t
    fstate[L.F_RAMP_F0] = f_now
    fstate[L.F_RAMP_T1] = t + p[L.P_CYCLE_RISE]
    fstate[L.F_RAMP_F1] = target


@njit(**JIT)
def _finished(p, seg, y, kstate, fstate, t, dt):
    """Whether segment ``seg`` has reached its end in state ``y`` at ``t``."""
    b = L.P_CYCLE_BASE + seg * L.CYCLE_STRIDE
    kind = int(p[b + L.Q_KIND])
    w = y[L.Y_FLYWHEEL_SPEED]
    if kind == L.SEG_ACCELERATE:
        return w >= p[b + L.Q_SPEED] * (1.0 - SPEED_TOLERANCE)
    if kind == L.SEG_BRAKE:
        if p[b + L.Q_SPEED] > 0.0:
            return w <= p[b + L.Q_SPEED]
        return kstate[L.K_STUCK] != 0 and standstill.at_rest(p, y)
    # whole steps: the segment ends at the first step start at or past its duration
    return t - fstate[L.F_SEGMENT_START] >= p[b + L.Q_DURATION] - 0.5 * dt


@njit(**JIT)
def control(p, base, y, kstate, fstate, t, dt):
    """The controller at the start of a physics step at ``t`` (s, step ``dt``): advance
    the segment while the current one has ended (each segment at most once per step; a
    repeating cycle wraps from its last segment to its first), set the load in force
    (:func:`.vehicle.scale_load` of ``base``, the packed vector, into ``p``), then
    set the step's drive torque in ``p`` (the kernel's working copy, P_DRIVE_TORQUE) and
    the brake force ramp in ``fstate`` (F_RAMP_*). ``kstate[K_SEGMENT]`` < 0 before the
    first step: the first segment starts then, at the packed load."""
    n = int(p[L.P_CYCLE_COUNT])
    seg = kstate[L.K_SEGMENT]
    if seg < 0:
        seg = 0
        fstate[L.F_LOAD_FACTOR] = 1.0
        _enter(p, base, seg, y, kstate, fstate, t)
    advanced = 0
    while seg < n and advanced < n and _finished(p, seg, y, kstate, fstate, t, dt):
        seg += 1
        advanced += 1
        if seg == n and p[L.P_CYCLE_REPEAT] > 0.0:
            seg = 0  # again from the first segment
        _enter(p, base, seg, y, kstate, fstate, t)
    kstate[L.K_SEGMENT] = seg
    vehicle.scale_load(base, p, fstate[L.F_LOAD_FACTOR])
    drive = 0.0
    if seg < n:
        b = L.P_CYCLE_BASE + seg * L.CYCLE_STRIDE
        kind = int(p[b + L.Q_KIND])
        w = y[L.Y_FLYWHEEL_SPEED]
        target = p[b + L.Q_SPEED]
        tau = p[L.P_CYCLE_TIME_CONSTANT]
        if kind == L.SEG_ACCELERATE or kind == L.SEG_CRUISE:
            drive = speed_control_torque(p, w, target)
        elif kind == L.SEG_DRAG:
            # PI on the overspeed: proportional gain for a first-order approach with the
            # nominal brake gain, integral time 4 tau (N per rad/s, N per rad)
            k_p = p[L.P_FLYWHEEL_INERTIA] / (NOMINAL_BRAKE_GAIN_N_M_PER_N * tau)
            k_i = k_p / (4.0 * tau)
            limit = p[L.P_CYCLE_MAX_FORCE]
            error = w - target
            held = fstate[L.F_DRAG_FORCE] + dt * k_i * error
            held = min(max(held, 0.0), limit)
            fstate[L.F_DRAG_FORCE] = held
            force = min(max(held + k_p * error, 0.0), limit)
            fstate[L.F_RAMP_T0] = t
            fstate[L.F_RAMP_F0] = force
            fstate[L.F_RAMP_T1] = t + 1.0
            fstate[L.F_RAMP_F1] = force
    p[L.P_DRIVE_TORQUE] = drive


def pack_drive(p: np.ndarray, setup) -> None:
    """Pack ``setup``'s vehicle and cycle (``BrakeSetup.vehicle``/``.cycle``) into ``p``
    (a :func:`~brake_sim_ros.model.assembly.pack` of it); nothing without a vehicle, so
    the published model's vector is unchanged.

    Raises:
        ParameterError: a driven vehicle with a rigid coupling (the road load and the
            drive act on the flywheel, which a rigid rotor does not have on its own).
    """
    if setup.vehicle is None:
        return
    if setup.options.rigid_coupling:
        raise ParameterError(
            "a [vehicle] or [cycle] acts on the flywheel through the torsional coupling:"
            " allowed only with rigid_coupling = false"
        )
    vehicle.pack_vehicle(p, setup.vehicle)
    if setup.cycle is not None:
        pack_cycle(p, setup.cycle)
