"""Fixed-step stepper for real-time streaming: compiled, uniform output grid.

Schemes (:data:`FIXED_STEP_SCHEMES`):

* ``rk4``: classical RK4; the Kelvin-Voigt force jumps when a contact starts inside a step,
  which limits it to first order through an impact.
* ``rk4-located``: RK4 with each contact onset and separation located inside the step and
  the step split there (the sampled output stays on the uniform grid); fourth order
  through impacts, at a few per cent more cost per step.
* ``semi-implicit-euler``: symplectic Euler, one evaluation per step, first order.

The stepper's unit is the output sample. It is built with a sample period (the scenario's
``sample_rate_hz``) and takes, inside each sample interval, the fewest whole physics
substeps whose step stays within both the accuracy bound ``max_step_s`` (a preset's largest
step) and the step limit of the current parameters (:func:`step_limit`)::

    substeps = ceil(sample_period / min(max_step_s, limit))
    physics step = sample_period / substeps

so the sample rate never depends on the defect or the actuation level. A change of the
parameters (:meth:`FixedStepStepper.replace_setup`) or an actuation force above the one the
limit was computed for re-picks the substeps at once; only a limit below
:data:`MIN_PHYSICS_STEP_S` (a pathological model) is refused.

The stepper owns the state between calls, so a caller (the ROS node, the offline
simulator) advances it in chunks and may change the actuation between any two calls.
Live actuation commands reach a shoe whose actuation is delayed or lagging (an actuation
defect) through the same shaping as the scenario's history: the stepper keeps the shoe's
commanded history (:class:`CommandHistory`). A run with a vehicle and no drive cycle
also takes live drive commands (:meth:`FixedStepStepper.drive`), held until the next.
"""

from __future__ import annotations

import enum
import math

import numpy as np

from brake_sim_ros.errors import ParameterError, SimulationError, StepSizeError
from brake_sim_ros.model import advance
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.actuation import MAX_ACTUATION_FORCE_N
from brake_sim_ros.model.assembly import initial_state, pack, resized_state
from brake_sim_ros.model.cycle import LiveDrive, pack_drive, pack_live_drive, torque_refusal
from brake_sim_ros.model.run_setup import BrakeSetup, SampleBlock
from brake_sim_ros.model.thermal import pack_thermal
from brake_sim_ros.solvers.stability import StepLimit, step_limit

# A shoe counts as riding on the drum after this long in unbroken contact; a shoe out of
# contact this long is free. Longer than the longest flight between impacts (about
# 20 ms for the published cases), short against the contact regime.
SETTLE_TIME_S = 0.05
# The smallest physics step the stepper takes, s. A limit below it is refused: 10 ns is
# 3907 substeps per 25.6 kHz sample, 1e8 steps (a minute of CPU) per simulated second;
# every defect in the core's ranges at MAX_ACTUATION_FORCE_N needs more than 500 ns.
MIN_PHYSICS_STEP_S = 1e-8


FIXED_STEP_SCHEMES: dict[str, int] = {
    "rk4": L.SCHEME_RK4,
    "rk4-located": L.SCHEME_RK4_LOCATED,
    "semi-implicit-euler": L.SCHEME_SEMI_IMPLICIT_EULER,
}
DEFAULT_SCHEME = "rk4-located"


# How far back a command history keeps its knots beyond the delay, in lag time constants:
# a slope change that old weighs exp(-40) (4e-18) in the lag's sum, below rounding.
HISTORY_LAGS = 40.0


class CommandHistory:
    """The commanded force history of one shoe under live commands: piecewise-linear knots
    (s, N) for :func:`brake_sim_ros.model.actuation.shaped`, so that a delayed or lagging
    shoe (``S_ACTUATION_DELAY``, ``S_ACTUATION_LAG``) answers a live command as it answers
    the scenario's history.

    It starts from what the line was commanded until the first live command it sees: the
    scenario's history, or the live force in force (a shoe that became delayed or lagging
    during live commands, its history before unknown to it: held), and takes each new
    command as a ramp over one physics step from the previous force (a command holds from
    its sample on; the knots must increase).
    Knots older than the delay plus :data:`HISTORY_LAGS` lag time constants are dropped.

    Args:
        ts, fs: the commanded knots so far for this shoe (s, N).
        t_s: simulated time of the first live command, s.
        keep_s: how far back knots are kept, s (the delay plus ``HISTORY_LAGS`` lags).
    """

    def __init__(self, ts: np.ndarray, fs: np.ndarray, t_s: float, keep_s: float) -> None:
        self.keep_s = keep_s
        before = ts < t_s
        self.ts = [float(t) for t in ts[before]]
        self.fs = [float(f) for f in fs[before]]
        self.ts.append(t_s)
        self.fs.append(float(np.interp(t_s, ts, fs)))

    def command(self, t_s: float, force_n: float, ramp_s: float) -> None:
        """A command of ``force_n`` (N) from ``t_s`` (s) on, reached within ``ramp_s``."""
        if force_n == self.fs[-1]:
            return
        if self.ts[-1] > t_s:  # a command within the last ramp: it ends at the new force
            self.fs[-1] = force_n
            return
        if self.ts[-1] < t_s:
            self.ts.append(t_s)
            self.fs.append(self.fs[-1])
        self.ts.append(t_s + ramp_s)
        self.fs.append(force_n)
        old = 0
        while old + 1 < len(self.ts) and self.ts[old + 1] < t_s - self.keep_s:
            old += 1
        del self.ts[:old], self.fs[:old]

    def knots(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array(self.ts), np.array(self.fs)


class StepperStatus(enum.Enum):
    RUNNING = "running"
    FAILED = "failed"


def substeps_for(sample_period_s: float, max_step_s: float) -> int:
    """Fewest whole substeps of one sample interval whose step is at most ``max_step_s``."""
    if not max_step_s < math.inf:
        return 1
    n = max(1, math.ceil(sample_period_s / max_step_s))
    # ceil of a rounded quotient is at most one too many; one check, not a loop: for a
    # step far below the period, n and n - 1 give the same quotient and a loop never ends
    if n > 1 and sample_period_s / (n - 1) <= max_step_s:
        n -= 1
    return n


class FixedStepStepper:
    """A fixed-step scheme that outputs one sample every ``sample_period_s``; state carried
    between :meth:`advance` calls.

    Args:
        setup: parameters, defects, actuation profile and model options.
        sample_period_s: time between output samples, s (1 / the scenario's sample rate).
        scheme: one of :data:`FIXED_STEP_SCHEMES` (default :data:`DEFAULT_SCHEME`).
        max_step_s: largest physics step for accuracy, s (a preset's); None = only the
            step limit bounds it.
        limit_force_n: actuation force, N, the step limit is computed for at the start
            (friction stiffness near standstill grows with the normal force); at least the
            profile's peak, which is the default. A larger force given to :meth:`advance`
            raises it and re-picks the substeps.
        check_step: False for studies of steps beyond the limit: the limit is still
            computed (and reported) but neither picks the substeps nor refuses anything;
            the physics step is the sample period divided by ``ceil(sample_period_s /
            max_step_s)`` (1 without ``max_step_s``).

    Raises:
        StepSizeError: a sample period that is not a finite time > 0, or a step limit
            below :data:`MIN_PHYSICS_STEP_S` (named, with its reason).
        ParameterError: an unknown scheme or invalid parameters.
    """

    def __init__(
        self,
        setup: BrakeSetup,
        sample_period_s: float,
        *,
        scheme: str = DEFAULT_SCHEME,
        max_step_s: float | None = None,
        limit_force_n: float | None = None,
        check_step: bool = True,
    ) -> None:
        if scheme not in FIXED_STEP_SCHEMES:
            raise ParameterError(
                f"fixed-step scheme {scheme!r}: allowed one of {list(FIXED_STEP_SCHEMES)}"
            )
        self.scheme = scheme
        self._scheme_id = FIXED_STEP_SCHEMES[scheme]
        for name, value in (("sample period", sample_period_s), ("max_step_s", max_step_s)):
            if value is not None and not (
                isinstance(value, float | int) and math.isfinite(value) and value > 0
            ):
                raise StepSizeError(f"{name} {value!r} is invalid: allowed a finite step > 0 s")
        if check_step and max_step_s is not None and max_step_s < MIN_PHYSICS_STEP_S:
            raise StepSizeError(
                f"max_step_s {max_step_s:g} s: allowed a physics step of at least"
                f" {MIN_PHYSICS_STEP_S:g} s (the smallest step taken)"
            )
        self.sample_period_s = float(sample_period_s)
        self.max_step_s = None if max_step_s is None else float(max_step_s)
        self.check_step = check_step
        self.setup = setup
        peak = _peak_n(setup)
        force = peak if limit_force_n is None else max(peak, float(limit_force_n))
        _check_force("limit_force_n", force)
        self._base_force_n = force
        self._p = _packed(setup)
        self._profile = setup.actuation.as_arrays()
        self.limit_force_n = force
        self.limit: StepLimit = step_limit(setup, force, packed=self._p, scheme=scheme)
        self.substeps = 1
        self.reset()

    def reset(self) -> None:
        """Back to t = 0 with the setup's initial state; a step limit raised by live
        actuation goes back to the one for the starting force."""
        if self.limit_force_n != self._base_force_n:
            self.limit_force_n = self._base_force_n
            self.limit = step_limit(
                self.setup, self._base_force_n, packed=self._p, scheme=self.scheme
            )
        self.substeps = self._substeps_for(self.limit, "these parameters")
        self._y = initial_state(
            self.setup.params,
            self.setup.defects,
            self.setup.start_temperature_c,
            held_temperature_c=self.setup.held_temperature_c,
        )
        self._histories: list[CommandHistory | None] = [None, None]
        self._live_n: tuple[float, float] | None = None  # the live forces in force, N
        self._sample = 0
        self._kstate = np.zeros(L.N_KSTATE, np.int64)
        self._fstate = np.zeros(L.N_FSTATE)
        self._fstate[L.F_STOP_TIME] = -1.0  # the vehicle has not stopped yet
        self._fstate[L.F_WHEEL_LOCK_TIME] = -1.0  # the drum has not stuck yet
        self._kstate[L.K_SEGMENT] = -1  # a drive cycle starts its first segment at once
        self._drive = LiveDrive()  # coasting until a live drive command
        self._pack_live_drive()
        self.status = StepperStatus.RUNNING

    def fresh(self) -> FixedStepStepper:
        """A new stepper at t = 0 with this one's setup, sample period, scheme and bounds."""
        return FixedStepStepper(
            self.setup,
            self.sample_period_s,
            scheme=self.scheme,
            max_step_s=self.max_step_s,
            limit_force_n=self._base_force_n,
            check_step=self.check_step,
        )

    # -- the step ------------------------------------------------------------------------------
    @property
    def physics_step_s(self) -> float:
        """The physics step in use, s: the sample period divided by :attr:`substeps`."""
        return self.sample_period_s / self.substeps

    def _substeps_for(self, limit: StepLimit, what: str) -> int:
        """Substeps per sample for ``limit``; StepSizeError below MIN_PHYSICS_STEP_S."""
        bound = math.inf if self.max_step_s is None else self.max_step_s
        if not self.check_step:
            return substeps_for(self.sample_period_s, bound)
        if limit.max_step_s < MIN_PHYSICS_STEP_S:
            needed = math.ceil(self.sample_period_s / limit.max_step_s)
            raise StepSizeError(
                f"{what} allow a physics step of at most {limit.max_step_s:.3g} s"
                f" ({limit.reason}): {needed} substeps per {self.sample_period_s:.3g} s sample,"
                f" below the smallest step taken, {MIN_PHYSICS_STEP_S:g} s"
            )
        return substeps_for(self.sample_period_s, min(bound, limit.max_step_s))

    def _use_substeps(self, substeps: int) -> None:
        """Switch to ``substeps`` per sample from the current sample on. The regime
        bookkeeping counts physics steps: its counters are rescaled to the new step."""
        old = self.substeps
        if substeps == old:
            return
        now_old, now_new = self._sample * old, self._sample * substeps
        for k in (L.K_LEFT_LAST_CHANGE_STEP, L.K_RIGHT_LAST_CHANGE_STEP):
            since = now_old - int(self._kstate[k])
            self._kstate[k] = now_new - (since * substeps) // old
        self.substeps = substeps

    def describe_step(self) -> str:
        """One line: sample rate, physics step and substeps, and the limit that set them."""
        bound = "" if self.max_step_s is None else f", accuracy bound {self.max_step_s:.3g} s"
        return (
            f"{1.0 / self.sample_period_s:g} Hz samples, physics step"
            f" {self.physics_step_s:.4g} s ({self.substeps} per sample, {self.scheme}); step"
            f" limit {self.limit.max_step_s:.3g} s for {self.limit_force_n:g} N of"
            f" actuation{bound}"
        )

    # -- state ------------------------------------------------------------------------------
    @property
    def sample_index(self) -> int:
        """Samples advanced since reset; also the index of the next sample."""
        return self._sample

    @property
    def time_s(self) -> float:
        return self._sample * self.sample_period_s

    @property
    def state(self) -> np.ndarray:
        """Copy of the state vector (layout.Y_*)."""
        return self._y.copy()

    def set_state(self, y: np.ndarray) -> None:
        """Replace the state vector (layout.Y_*), e.g. to start from a twisted coupling."""
        y = np.asarray(y, dtype=float)
        size = self._y.shape[0]  # assembly.state_size's
        if y.shape != (size,) or not np.all(np.isfinite(y)):
            raise ParameterError(f"state of shape {y.shape}: allowed {size} finite values")
        self._y = y.copy()

    @property
    def locked(self) -> bool:
        """Static friction holds the drum at standstill now (model/standstill.py)."""
        return bool(self._kstate[L.K_STUCK])

    @property
    def stop_time_s(self) -> float | None:
        """Instant the vehicle came to rest, s (None until it has): the drum held and the
        rotor's remaining energy within what the brake holds (model/standstill.py)."""
        stop = float(self._fstate[L.F_STOP_TIME])
        return stop if stop >= 0.0 else None

    @property
    def wheel_lock_time_s(self) -> float | None:
        """Instant the drum first stuck, s (None until it has); the stop time or earlier."""
        lock = float(self._fstate[L.F_WHEEL_LOCK_TIME])
        return lock if lock >= 0.0 else None

    @property
    def breakaways(self) -> int:
        """Times the held drum broke away again (coupling torque above the capacity)."""
        return int(self._kstate[L.K_BREAKAWAYS])

    @property
    def located_switches(self) -> int:
        """Contact onsets and separations located inside steps so far (rk4-located only)."""
        return int(self._fstate[L.F_SWITCHES])

    @property
    def adjuster_takeup_m(self) -> tuple[float, float]:
        """Lining wear each shoe's self-adjuster (left, right) has taken up within the run
        so far, m: whole steps, in the lining's radius (model/ratchet.py; 0 where it does
        not step within the run). Besides the wear it took up at the start (model/adjuster.py)."""
        return self._adjuster_m(L.F_ADJUSTER_TAKEN)

    @property
    def adjuster_pending_m(self) -> tuple[float, float]:
        """Teeth each shoe's self-adjuster (left, right) has picked up in an application
        and not yet taken up (the shoe has not returned to the lengthened strut), m."""
        return self._adjuster_m(L.F_ADJUSTER_PENDING)

    def _adjuster_m(self, slot: int) -> tuple[float, float]:
        steps = self._p[L.P_ADJUSTER_STEP : L.P_ADJUSTER_STEP + 2]
        left, right = (float(self._fstate[slot + i] * steps[i]) for i in range(2))
        return left, right

    @property
    def packed_parameters(self) -> np.ndarray:
        return self._p.copy()

    def replace_setup(self, setup: BrakeSetup) -> None:
        """Swap parameters/defects mid-run (takes effect on the next sample); state is kept.

        Validity is checked and the substeps re-picked for the new step limit; on error
        (invalid parameters, a limit below MIN_PHYSICS_STEP_S) nothing changes.
        """
        p = _packed(setup)
        force = max(self.limit_force_n, _peak_n(setup))
        limit = step_limit(setup, force, packed=p, scheme=self.scheme)
        substeps = self._substeps_for(limit, "the new parameters")
        was_thermal = self.setup.thermal is not None
        self.setup, self._p, self.limit, self.limit_force_n = setup, p, limit, force
        self._base_force_n = max(self._base_force_n, _peak_n(setup))
        self._profile = setup.actuation.as_arrays()
        self._pack_live_drive()  # the command in force holds on the new parameters
        self._use_substeps(substeps)
        self._y = resized_state(
            self._y,
            setup.params,
            setup.defects,
            was_thermal=was_thermal,
            start_temperature_c=setup.start_temperature_c,
            held_temperature_c=setup.held_temperature_c,
        )

    def drive_refusal(self, command: LiveDrive | None = None) -> str | None:
        """Why this run takes no live drive commands (or not ``command``: a torque above
        its vehicle's ``max_drive_torque_n_m``), or None when it does."""
        if self.setup.cycle is not None:
            return (
                "this run's drive cycle drives the vehicle ([cycle]): allowed only for a"
                " scenario without a cycle"
            )
        if self.setup.vehicle is None:
            return (
                "this run has no vehicle for the drive to act on: allowed only for a scenario"
                " with a [vehicle] table"
            )
        return None if command is None else torque_refusal(command, self.setup.vehicle)

    @property
    def live_drive(self) -> LiveDrive:
        """The live drive command in force (coast at reset)."""
        return self._drive

    def drive(self, command: LiveDrive) -> None:
        """Drive by ``command`` from the next sample (:attr:`sample_index`) on, until the
        next command or a reset (model/cycle.py: coast, a torque, or a target speed by the
        cycle's speed controller, run at every physics step in the compiled stepping).

        Raises:
            ParameterError: a run that takes none, or not this command
                (:meth:`drive_refusal`); nothing changes.
        """
        refusal = self.drive_refusal(command)
        if refusal is not None:
            raise ParameterError(f"drive commands: {refusal}")
        self._drive = command
        self._pack_live_drive()

    def _pack_live_drive(self) -> None:
        if self.drive_refusal() is None:
            pack_live_drive(self._p, self._drive, self.setup.vehicle)

    def _raise_limit_force(self, force_n: float) -> None:
        """Recompute the step limit for a larger actuation force and re-pick the substeps."""
        limit = step_limit(self.setup, force_n, packed=self._p, scheme=self.scheme)
        substeps = self._substeps_for(limit, f"{force_n:g} N of actuation")
        self.limit, self.limit_force_n = limit, force_n
        self._use_substeps(substeps)

    # -- stepping -------------------------------------------------------------------------------
    def advance(
        self,
        n_samples: int,
        *,
        actuation_n: tuple[float, float] | None = None,
        record_every: int = 1,
    ) -> SampleBlock:
        """Advance ``n_samples`` sample intervals; return every ``record_every``-th sample.

        Args:
            n_samples: sample intervals to advance (>= 0), each :attr:`substeps` physics steps.
            actuation_n: if given, constant (left, right) actuation forces in N for these
                samples, overriding the profile; the actuation-share defect still applies.
                Each must be finite, >= 0 and <= MAX_ACTUATION_FORCE_N; one above
                :attr:`limit_force_n` raises it and re-picks the substeps first.
            record_every: decimation of the returned samples (the physics still runs at
                every substep).

        Sample ``k`` is the state at ``k * sample_period_s`` exactly (the time column is
        ``k * sample_period_s``), so consecutive calls give a gap-free series on one uniform
        grid; the block's ``first_index`` is the sample index before the call.
        """
        if n_samples < 0 or record_every < 1:
            raise ValueError(
                f"n_samples={n_samples}, record_every={record_every}: allowed"
                " n_samples >= 0 and record_every >= 1"
            )
        if self.status is StepperStatus.FAILED:
            raise SimulationError("the stepper failed earlier (non-finite state); reset it")
        if actuation_n is None:
            tl, fl, tr, fr = self._profile
        elif self.setup.cycle is not None:
            raise ParameterError(
                "actuation commands: this run's drive cycle commands the brake ([cycle]):"
                " allowed only for a scenario without a cycle"
            )
        else:
            left, right = (float(a) for a in actuation_n)
            for side, value in (("left", left), ("right", right)):
                _check_force(f"{side} actuation force", value)
            if max(left, right) > self.limit_force_n:
                self._raise_limit_force(max(left, right))
            tl = tr = np.zeros(1)
            fl = np.array([left])
            fr = np.array([right])
            knots = [(tl, fl), (tr, fr)]
            for i, force in enumerate((left, right)):
                keep_s = self._history_keep_s(i)
                if keep_s is None:
                    continue
                history = self._histories[i]
                t_s = self._sample * self.sample_period_s
                if history is None:
                    ts, fs = self._profile[2 * i], self._profile[2 * i + 1]
                    if self._live_n is not None:
                        ts, fs = np.zeros(1), np.array([self._live_n[i]])
                    history = self._histories[i] = CommandHistory(ts, fs, t_s, keep_s)
                history.command(t_s, force, self.physics_step_s)
                knots[i] = history.knots()
            (tl, fl), (tr, fr) = knots
            self._live_n = (left, right)
        if actuation_n is None:
            self._histories = [None, None]  # back on the scenario's history
            self._live_n = None
        rows = -(-n_samples // record_every)
        out = np.empty((rows, L.N_COLUMNS))
        first = self._sample
        written = self._integrate(n_samples, record_every, (tl, fl, tr, fr), out)
        return SampleBlock(out[:written], first, self.sample_period_s * record_every)

    def _history_keep_s(self, shoe: int) -> float | None:
        """How far back the commanded history of ``shoe`` (0 left, 1 right) matters, s:
        its delay plus :data:`HISTORY_LAGS` lags; None for a shoe that is neither delayed
        nor lagging (a live command then reaches it at once, as a constant)."""
        base = L.P_SHOE_BASE + shoe * L.SHOE_STRIDE
        delay, lag = self._p[base + L.S_ACTUATION_DELAY], self._p[base + L.S_ACTUATION_LAG]
        if delay <= 0.0 and lag <= 0.0:
            return None
        return float(delay + HISTORY_LAGS * lag)

    def _integrate(self, n_samples: int, record_every: int, knots, out: np.ndarray) -> int:
        """Run the kernel over ``n_samples`` samples into ``out``; rows written."""
        tl, fl, tr, fr = knots
        first, sub = self._sample, self.substeps
        dt = self.physics_step_s
        written = advance.fixed_step_advance(
            self._y,
            first * sub,
            dt,
            n_samples * sub,
            self._p,
            tl,
            fl,
            tr,
            fr,
            0,
            self._kstate,
            self._fstate,
            max(1, round(SETTLE_TIME_S / dt)),
            record_every * sub,
            out,
            self._scheme_id,
        )
        if sub > 1:  # the kernel's time is step x physics step: state it on the sample grid
            out[:written, L.COL["time_s"]] = (
                first + record_every * np.arange(written)
            ) * self.sample_period_s
        if self._kstate[L.K_STATUS]:
            self.status = StepperStatus.FAILED
            t_fail = (first + written * record_every) * self.sample_period_s
            raise SimulationError(
                f"non-finite state at t = {t_fail:.6f} s with physics step {dt:g} s ({self.scheme})"
            )
        self._sample += n_samples
        return written

    def run(
        self,
        duration_s: float,
        *,
        record_every: int = 1,
        chunk_samples: int = 100_000,
        progress=None,
    ) -> SampleBlock:
        """Advance by ``duration_s`` (rounded to whole samples) and return every
        ``record_every``-th sample, written into one array (no copies)."""
        total = round(duration_s / self.sample_period_s)
        first = self._sample
        out = np.empty((-(-total // record_every), L.N_COLUMNS))
        chunk = max(record_every, chunk_samples - chunk_samples % record_every)
        done = rows = 0
        while done < total:
            n = min(chunk, total - done)
            rows += self._integrate(n, record_every, self._profile, out[rows:])
            done += n
            if progress is not None:
                progress(done / total)
        return SampleBlock(out[:rows], first, self.sample_period_s * record_every)


def _peak_n(setup: BrakeSetup) -> float:
    return setup.peak_force_n


def _packed(setup: BrakeSetup) -> np.ndarray:
    """The kernels' parameter vector of ``setup``: the brake, its vehicle and cycle, and its
    temperature."""
    p = pack(setup.params, setup.defects, setup.options)
    pack_drive(p, setup)
    pack_thermal(p, setup)
    return p


def _check_force(what: str, value: float) -> None:
    if not (math.isfinite(value) and 0.0 <= value <= MAX_ACTUATION_FORCE_N):
        raise ParameterError(
            f"{what} {value!r} N: allowed a finite force from 0 to {MAX_ACTUATION_FORCE_N:g} N"
        )
