"""Actuation commands: the checks they must pass and what happens when they stop.

Pure logic, no ROS. Time is counted in steps of one output sample (simulated time: the
stepper's unit, whatever physics substeps it takes inside), so the same commands at the
same steps give the same forces, whatever the wall clock did.

Semantics (the node's ``~/actuation`` subscription):

* A valid command (both forces finite, >= 0 and <= ``max_actuation_force_n``) takes effect
  at the next sample, ``s_c`` = the node's sample index when the command is
  processed, and overrides the scenario's force profile for both shoes. The forces are
  per shoe, before the actuation-share defect (the core multiplies each shoe's force by
  ``2 * actuation_share``, exactly as it does for the profile).
* It stays in force for ``command_timeout_s`` of *simulated* time: steps
  ``s_c .. s_c + timeout_steps - 1``, ``timeout_steps = max(1, round(timeout_s /
  period))`` with ``period`` the sample period. Every new valid command restarts that
  window. While paused, simulated time does not advance, so a command does not age.
* When the window ends without a new command, ``on_command_timeout`` decides:

  ``profile``      the scenario's force profile resumes, evaluated at the current
                   simulated time (as if no command had been given). This can be a step
                   change of force.
  ``hold``         the last command's forces stay in force until the next command or a
                   reset.
  ``ramp_to_zero`` each shoe's force falls linearly from the last command's value at
                   ``command_ramp_rate_n_per_s``: ``F(t) = max(0, F_cmd - rate (t - t_out))``
                   with ``t`` the simulated time at the start of each step (held for that
                   step) and ``t_out`` the end of the window; it then stays at zero until
                   the next command or a reset. The scenario profile does not come back.

* An invalid command (NaN, +-inf, negative, above the maximum) is rejected as a whole:
  it changes nothing, not even the timeout window.

Drive commands (``~/drive``, :func:`drive_command`) have no timeout: a valid one holds
from the next sample until the next one or a reset (which returns to coasting); the
stepper runs it (:class:`brake_sim_ros.model.cycle.LiveDrive`). An invalid one (unknown
mode, a non-finite or out-of-range value of the field its mode uses) changes nothing.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.cycle import DRIVE_MODES, LiveDrive

Forces = tuple[float, float]
"""(left, right) actuation forces, N."""

Segment = tuple[int, Forces | None]
"""``(n_steps, forces)``: constant forces for ``n_steps`` steps; None = the scenario profile."""


class TimeoutBehaviour(enum.Enum):
    HOLD = "hold"
    RAMP_TO_ZERO = "ramp_to_zero"
    PROFILE = "profile"

    @classmethod
    def parse(cls, text: str) -> TimeoutBehaviour:
        try:
            return cls(text)
        except ValueError:
            allowed = ", ".join(f'"{b.value}"' for b in cls)
            raise ValueError(f"on_command_timeout={text!r} is invalid: allowed {allowed}") from None


def check_command(left_n: float, right_n: float, max_force_n: float) -> str | None:
    """Why a command must be rejected, or None when it is valid."""
    for side, value in (("left", left_n), ("right", right_n)):
        if not math.isfinite(value):
            return f"{side}_force_n={value!r} is not a finite number"
        if value < 0.0:
            return f"{side}_force_n={value:g} N is negative (a shoe is pushed, never pulled)"
        if value > max_force_n:
            return f"{side}_force_n={value:g} N exceeds max_actuation_force_n = {max_force_n:g} N"
    return None


def drive_command(
    mode: int, drive_torque_n_m: float, target_speed_m_s: float
) -> tuple[LiveDrive | None, str | None]:
    """A DriveCommand's fields as the core's command, or None and why it must be rejected.

    ``mode`` is the message's MODE_* number, the index of :data:`DRIVE_MODES`.
    """
    if not 0 <= mode < len(DRIVE_MODES):
        allowed = ", ".join(f"{i} ({name.upper()})" for i, name in enumerate(DRIVE_MODES))
        return None, f"mode={mode!r} is unknown: allowed {allowed}"
    try:
        return LiveDrive(DRIVE_MODES[mode], float(drive_torque_n_m), float(target_speed_m_s)), None
    except ParameterError as exc:
        return None, str(exc)


def describe_drive(drive: LiveDrive) -> str:
    """The drive in force in a few words: ``coast``, ``torque 60 N m``, ``target_speed 5
    m/s``."""
    if drive.mode == "torque":
        return f"torque {drive.drive_torque_n_m:g} N m"
    if drive.mode == "target_speed":
        return f"target_speed {drive.target_speed_m_s:g} m/s"
    return drive.mode


@dataclass(frozen=True)
class CommandPolicy:
    """Parameters of the command timeout (see the module docstring)."""

    timeout_s: float = 0.2
    behaviour: TimeoutBehaviour = TimeoutBehaviour.PROFILE
    ramp_rate_n_per_s: float = 5000.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.timeout_s) and self.timeout_s > 0):
            raise ValueError(f"command_timeout_s={self.timeout_s!r}: allowed a finite time > 0 s")
        if not (math.isfinite(self.ramp_rate_n_per_s) and self.ramp_rate_n_per_s > 0):
            raise ValueError(
                f"command_ramp_rate_n_per_s={self.ramp_rate_n_per_s!r}: allowed a"
                " finite rate > 0 N/s"
            )


@dataclass(frozen=True)
class _Command:
    forces: Forces
    step: int


class ActuationPlanner:
    """Turns the latest command and the policy into constant-force segments of steps.

    A step here is one output sample, the stepper's unit: a command takes effect at a
    sample boundary.

    Args:
        sample_period_s: time between samples, s.
        policy: timeout behaviour.
    """

    def __init__(self, sample_period_s: float, policy: CommandPolicy | None = None) -> None:
        self.sample_period_s = float(sample_period_s)
        self.policy = policy or CommandPolicy()
        self._command: _Command | None = None
        self._applied = True

    @property
    def timeout_steps(self) -> int:
        return max(1, round(self.policy.timeout_s / self.sample_period_s))

    @property
    def last_command(self) -> Forces | None:
        return None if self._command is None else self._command.forces

    def command(self, forces: Forces, step: int) -> bool:
        """Accept a valid command at ``step``. True if it replaced one that never took effect."""
        dropped = self._command is not None and not self._applied
        self._command = _Command((float(forces[0]), float(forces[1])), int(step))
        self._applied = False
        return dropped

    def clear(self) -> bool:
        """Forget the command (reset). True if one was pending and never took effect."""
        dropped = self._command is not None and not self._applied
        self._command = None
        self._applied = True
        return dropped

    def source(self, step: int) -> str:
        """What drives the actuation at ``step``: profile, command, hold, ramp or zero."""
        cmd = self._command
        if cmd is None:
            return "profile"
        if step < cmd.step + self.timeout_steps:
            return "command"
        behaviour = self.policy.behaviour
        if behaviour is TimeoutBehaviour.PROFILE:
            return "profile"
        if behaviour is TimeoutBehaviour.HOLD:
            return "hold"
        return "zero" if self._ramp_forces(step) == (0.0, 0.0) else "ramp"

    def segments(self, step: int, n_steps: int) -> list[Segment]:
        """Constant-force segments covering steps ``step .. step + n_steps - 1``, in order."""
        if n_steps <= 0:
            return []
        cmd = self._command
        if cmd is None:
            return [(n_steps, None)]
        self._applied = True
        end = step + n_steps
        expiry = cmd.step + self.timeout_steps
        out: list[Segment] = []
        if step < expiry:
            n = min(end, expiry) - step
            out.append((n, cmd.forces))
            step += n
        if step < end:
            behaviour = self.policy.behaviour
            if behaviour is TimeoutBehaviour.PROFILE:
                out.append((end - step, None))
            elif behaviour is TimeoutBehaviour.HOLD:
                out.append((end - step, cmd.forces))
            else:
                for k in range(step, end):
                    forces = self._ramp_forces(k)
                    if forces == (0.0, 0.0):
                        out.append((end - k, forces))
                        break
                    out.append((1, forces))
        return _merge(out)

    def _ramp_forces(self, step: int) -> Forces:
        cmd = self._command
        assert cmd is not None
        elapsed_s = (step - cmd.step - self.timeout_steps) * self.sample_period_s
        drop = self.policy.ramp_rate_n_per_s * max(0.0, elapsed_s)
        return (max(0.0, cmd.forces[0] - drop), max(0.0, cmd.forces[1] - drop))


def _merge(segments: list[Segment]) -> list[Segment]:
    merged: list[Segment] = []
    for n, forces in segments:
        if merged and merged[-1][1] == forces:
            merged[-1] = (merged[-1][0] + n, forces)
        else:
            merged.append((n, forces))
    return merged
