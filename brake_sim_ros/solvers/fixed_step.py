"""Fixed-step stepper for real-time streaming: compiled, uniform output grid.

Schemes (:data:`FIXED_STEP_SCHEMES`):

* ``rk4``: classical RK4; the Kelvin-Voigt force jumps when a contact starts inside a step,
  which limits it to first order through an impact.
* ``rk4-located``: RK4 with each contact onset and separation located inside the step and
  the step split there (the sampled output stays on the uniform grid); fourth order
  through impacts, at a few per cent more cost per step.
* ``semi-implicit-euler``: symplectic Euler, one evaluation per step, first order.

The stepper owns the state between calls, so a caller (the ROS node, the offline
simulator) advances it in chunks and may change the actuation between any two calls.
"""

from __future__ import annotations

import enum
import math

import numpy as np

from brake_sim_ros.errors import ParameterError, SimulationError, StepSizeError
from brake_sim_ros.model import kernel
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.actuation import MAX_ACTUATION_FORCE_N
from brake_sim_ros.model.assembly import initial_state, pack
from brake_sim_ros.model.trajectory import BrakeSetup, SampleBlock
from brake_sim_ros.solvers.stability import StepLimit, step_limit

# A shoe counts as riding on the drum after this long in unbroken contact; a shoe out of
# contact this long is free. Longer than the longest flight between impacts (about
# 20 ms for the published cases), short against the contact regime.
SETTLE_TIME_S = 0.05


FIXED_STEP_SCHEMES: dict[str, int] = {
    "rk4": L.SCHEME_RK4,
    "rk4-located": L.SCHEME_RK4_LOCATED,
    "semi-implicit-euler": L.SCHEME_SEMI_IMPLICIT_EULER,
}
DEFAULT_SCHEME = "rk4-located"


class StepperStatus(enum.Enum):
    RUNNING = "running"
    FAILED = "failed"


class FixedStepStepper:
    """A fixed-step scheme at step ``dt_s``; state carried between :meth:`advance` calls.

    Args:
        setup: parameters, defects, actuation profile and model options.
        dt_s: physics step, s. Refused (StepSizeError) above the limit that the stiffest
            mode of the current parameters allows for this scheme; see :func:`step_limit`.
        scheme: one of :data:`FIXED_STEP_SCHEMES` (default :data:`DEFAULT_SCHEME`).
        max_actuation_n: the largest actuation force this stepper will ever be given
            (the profile's peak by default); the step limit is computed for it, since
            friction stiffness near standstill grows with the normal force.
    """

    def __init__(
        self,
        setup: BrakeSetup,
        dt_s: float,
        *,
        max_actuation_n: float | None = None,
        check_step: bool = True,
        scheme: str = DEFAULT_SCHEME,
    ) -> None:
        if scheme not in FIXED_STEP_SCHEMES:
            raise ParameterError(
                f"fixed-step scheme {scheme!r}: allowed one of {list(FIXED_STEP_SCHEMES)}"
            )
        self.scheme = scheme
        self._scheme_id = FIXED_STEP_SCHEMES[scheme]
        if not (isinstance(dt_s, float | int) and math.isfinite(dt_s) and dt_s > 0):
            raise StepSizeError(f"step dt_s={dt_s!r} is invalid: allowed a finite step > 0 s")
        self.setup = setup
        self.dt_s = float(dt_s)
        peak = max(setup.actuation.left.peak_n, setup.actuation.right.peak_n)
        self.max_actuation_n = float(peak if max_actuation_n is None else max_actuation_n)
        if not 0.0 <= self.max_actuation_n <= MAX_ACTUATION_FORCE_N:
            raise ParameterError(
                f"max_actuation_n={self.max_actuation_n}: allowed 0 to {MAX_ACTUATION_FORCE_N} N"
            )
        self._p = pack(setup.params, setup.defects, setup.options)
        self.limit: StepLimit = step_limit(
            setup, self.max_actuation_n, packed=self._p, scheme=scheme
        )
        if check_step and self.dt_s > self.limit.max_step_s:
            raise StepSizeError(
                f"step {self.dt_s:.3g} s exceeds the limit {self.limit.max_step_s:.3g} s for these"
                f" parameters: {self.limit.reason}"
            )
        self._settle_steps = max(1, round(SETTLE_TIME_S / self.dt_s))
        self._profile = setup.actuation.as_arrays()
        self.reset()

    def reset(self) -> None:
        """Back to t = 0 with the setup's initial state."""
        self._y = initial_state(self.setup.params, self.setup.defects)
        self._step = 0
        self._kstate = np.zeros(L.N_KSTATE, np.int64)
        self._fstate = np.zeros(L.N_FSTATE)
        self._fstate[L.F_STOP_TIME] = -1.0  # the vehicle has not stopped yet
        self._fstate[L.F_WHEEL_LOCK_TIME] = -1.0  # the drum has not stuck yet
        self.status = StepperStatus.RUNNING

    # -- state ------------------------------------------------------------------------------
    @property
    def step_index(self) -> int:
        """Number of steps taken since reset; also the index of the next sample."""
        return self._step

    @property
    def time_s(self) -> float:
        return self._step * self.dt_s

    @property
    def state(self) -> np.ndarray:
        """Copy of the state vector (layout.Y_*)."""
        return self._y.copy()

    def set_state(self, y: np.ndarray) -> None:
        """Replace the state vector (layout.Y_*), e.g. to start from a twisted coupling."""
        y = np.asarray(y, dtype=float)
        if y.shape != (L.N_STATE,) or not np.all(np.isfinite(y)):
            raise ParameterError(f"state of shape {y.shape}: allowed {L.N_STATE} finite values")
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
    def packed_parameters(self) -> np.ndarray:
        return self._p.copy()

    def replace_setup(self, setup: BrakeSetup) -> None:
        """Swap parameters/defects mid-run (takes effect on the next step); state is kept.

        Validity and the step limit are checked first; on error nothing changes.
        """
        p = pack(setup.params, setup.defects, setup.options)
        limit = step_limit(setup, self.max_actuation_n, packed=p, scheme=self.scheme)
        if self.dt_s > limit.max_step_s:
            raise StepSizeError(
                f"the new parameters allow at most {limit.max_step_s:.3g} s per step, the"
                f" stepper runs at {self.dt_s:.3g} s: {limit.reason}"
            )
        self.setup, self._p, self.limit = setup, p, limit
        self._profile = setup.actuation.as_arrays()

    # -- stepping -------------------------------------------------------------------------------
    def advance(
        self, n_steps: int, *, actuation_n: tuple[float, float] | None = None, record_every: int = 1
    ) -> SampleBlock:
        """Advance ``n_steps`` steps and return one sample every ``record_every`` steps.

        Args:
            n_steps: steps to take (>= 0).
            actuation_n: if given, constant (left, right) actuation forces in N for these
                steps, overriding the profile; the actuation-share defect still applies.
                Each must be finite, >= 0 and <= ``max_actuation_n``.
            record_every: decimation of the returned samples (the physics still runs at
                every step).

        Samples are taken at the start of each recorded step, so consecutive calls give a
        gap-free series; the block's ``first_index`` is the step index before the call.
        """
        if n_steps < 0 or record_every < 1:
            raise ValueError(
                f"n_steps={n_steps}, record_every={record_every}: allowed"
                " n_steps >= 0 and record_every >= 1"
            )
        if self.status is StepperStatus.FAILED:
            raise SimulationError("the stepper failed earlier (non-finite state); reset it")
        if actuation_n is None:
            tl, fl, tr, fr = self._profile
        else:
            left, right = (float(a) for a in actuation_n)
            for side, value in (("left", left), ("right", right)):
                if not (math.isfinite(value) and 0.0 <= value <= self.max_actuation_n):
                    raise ParameterError(
                        f"{side} actuation force {value!r} N: allowed a finite force from 0 to"
                        f" {self.max_actuation_n:g} N"
                    )
            tl = tr = np.zeros(1)
            fl = np.array([left])
            fr = np.array([right])
        rows = -(-n_steps // record_every)
        out = np.empty((rows, L.N_COLUMNS))
        first = self._step
        written = kernel.fixed_step_advance(
            self._y,
            self._step,
            self.dt_s,
            n_steps,
            self._p,
            tl,
            fl,
            tr,
            fr,
            0,
            self._kstate,
            self._fstate,
            self._settle_steps,
            record_every,
            out,
            self._scheme_id,
        )
        if self._kstate[L.K_STATUS]:
            self.status = StepperStatus.FAILED
            raise SimulationError(
                f"non-finite state at t = {(first + written * record_every) * self.dt_s:.6f} s"
                f" with step {self.dt_s:g} s ({self.scheme})"
            )
        self._step += n_steps
        return SampleBlock(out[:written], first, self.dt_s * record_every)

    def run(
        self, duration_s: float, *, record_every: int = 1, chunk_steps: int = 100_000, progress=None
    ) -> SampleBlock:
        """Advance until ``duration_s`` (from the current time) and return all samples."""
        total = round(duration_s / self.dt_s)
        blocks = []
        done = 0
        while done < total:
            n = min(chunk_steps - chunk_steps % record_every or record_every, total - done)
            blocks.append(self.advance(n, record_every=record_every))
            done += n
            if progress is not None:
                progress(done / total)
        return (
            SampleBlock.concatenate(blocks)
            if blocks
            else SampleBlock(np.empty((0, L.N_COLUMNS)), self._step, self.dt_s * record_every)
        )
