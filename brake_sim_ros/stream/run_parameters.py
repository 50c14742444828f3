"""The run parameters: one table, read by the node, the recording and re-simulation.

A run parameter controls the run, not the physics (those are the model parameters of
:mod:`.parameters`, generated from the core's dataclasses). Each is declared once in
:data:`RUN_PARAMETERS`: its name, default (whose Python type is its ROS type), description,
range, when it may change (:class:`Change`) and what it affects (:class:`Affects`). From
that one entry:

* the node declares it as a ROS parameter (:func:`~brake_sim_ros.ros.descriptors.
  descriptor`) and refuses a change while it runs when it is fixed at start;
* :class:`~brake_sim_ros.stream.session.RunSession` holds its value (``settings``) and
  applies a change to it (:meth:`~brake_sim_ros.stream.session.RunSession.apply`);
* the ``brake_sim_run`` record of a recording carries its value at the start, unless it
  names what runs or paces the wall clock (:func:`recorded`);
* ``brake-sim resim`` reads it back (the run record, a live node's parameters record, else
  its default, :func:`start_values`) and re-simulates a recorded change of it, or refuses
  one of a parameter fixed at start in one line.

Adding one is a table entry and the code of its effect (docs/architecture.md has the
checklist). This module imports no rclpy.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.identifiers import IDENTIFIER_RULE, is_identifier
from brake_sim_ros.model.actuation import MAX_ACTUATION_FORCE_N
from brake_sim_ros.model.vehicle import (
    DEFAULT_MAX_DRIVE_TORQUE_N_M,
    DEFAULT_SPEED_TIME_CONSTANT_S,
    DRIVE_LIMITS,
)

DEFAULT_SCENARIO = "symmetric"
_FIXED = "Fixed at start-up: a change is refused."
_DRIVE_MAX = {name: hi for name, _lo, hi in DRIVE_LIMITS}


class Change(enum.Enum):
    """When a run parameter may change."""

    AT_START = "start"  # fixed at start-up: the node refuses a change
    ANY_TIME = "any time"  # while the run goes on (ros2 param set), from the next sample


class Affects(enum.Enum):
    """What a run parameter changes (and so how a recorded run treats it)."""

    WHAT_RUNS = "what runs"  # the scenario, unit and identity of the run (own records)
    PACING = "pacing"  # wall clock only: never a sample or a message (not recorded)
    END = "end"  # where the free run ends
    CHUNKING = "chunking"  # how the samples are cut into messages
    STREAM = "stream"  # which messages the run publishes
    COMMANDS = "commands"  # what commands are accepted and how they time out
    DRIVE = "drive"  # a live drive's settings (the model's vehicle)


@dataclass(frozen=True)
class RunParameter:
    """One run parameter (duck-types :class:`~.parameters.ParamSpec` for descriptors).

    Attributes:
        name: ROS parameter name, also its key in the run record.
        default: default value; its Python type (float, int, bool, str) is the ROS type.
        text: one or two sentences with the unit (the fixed-at-start note is added).
        range: closed (low, high) for numbers (the node's descriptor and resim's check).
        changes: when it may change.
        affects: what it changes.
        constraints: free-text additional constraints shown by tools.
    """

    name: str
    default: float | int | bool | str
    text: str
    range: tuple[float, float] | None = None
    changes: Change = Change.ANY_TIME
    affects: Affects = Affects.STREAM
    constraints: str = ""

    @property
    def description(self) -> str:
        fixed = self.changes is Change.AT_START
        return f"{self.text} {_FIXED}" if fixed else self.text

    def check(self, value: Any, where: str) -> float | bool | str:
        """``value`` as this parameter's type (an int for a float is taken), or
        ParameterError naming ``where``, the value and what is allowed."""
        kind = type(self.default)
        if kind is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if type(value) is not kind:
            raise ParameterError(
                f"{where}: {self.name}={str(value)[:64]!r}: allowed a {kind.__name__}"
            )
        if self.range is not None and kind in (int, float):
            lo, hi = self.range
            if not (math.isfinite(value) and lo <= value <= hi):
                raise ParameterError(f"{where}: {self.name}={value!r}: allowed {lo:g} to {hi:g}")
        return value


def _drive(name: str, what: str, unit: str, default: float) -> RunParameter:
    return RunParameter(
        name,
        0.0,
        f"{what} of a live drive (~/drive; a scenario with a [vehicle] and no [cycle]),"
        f" {unit}: 0 at start-up = the scenario's [vehicle] {name} (default {default:g});"
        " applies to every scenario ~/reset loads.",
        (0.0, _DRIVE_MAX[name]),
        Change.AT_START,
        Affects.DRIVE,
    )


RUN_PARAMETERS: tuple[RunParameter, ...] = (
    RunParameter(
        "scenario",
        DEFAULT_SCENARIO,
        "Scenario loaded at start-up: a built-in name or a path to a .toml file. "
        "Switch it with the ~/reset service (its 'scenario' field).",
        changes=Change.AT_START,
        affects=Affects.WHAT_RUNS,
    ),
    RunParameter(
        "scenario_dirs",
        "",
        "Directories (separated by ':') from which ~/reset requests may load .toml "
        "scenario files; empty = none, a request may only name a built-in scenario. "
        "Symlinks and '..' are resolved before the check.",
        changes=Change.AT_START,
        affects=Affects.WHAT_RUNS,
    ),
    RunParameter(
        "run_id",
        "",
        "Identifier of the run in every ground-truth message (DefectState, ContactEvent), "
        "in /diagnostics and in recordings: empty = a fresh UUID4 (32 hex digits) at "
        f"start and at each ~/reset; otherwise this text ({IDENTIFIER_RULE}), "
        "kept across resets.",
        changes=Change.AT_START,
        affects=Affects.WHAT_RUNS,
        constraints=f"empty, or {IDENTIFIER_RULE}",
    ),
    RunParameter(
        "unit_id",
        "",
        "Brake unit to simulate (its manufacturing scatter, drawn with the scenario's "
        "fleet_seed from the scenario's values): empty = the scenario's unit_id; "
        f"'nominal' = the scenario's brake itself; otherwise {IDENTIFIER_RULE}. "
        "Applies to every scenario ~/reset loads; the unit is "
        "the same brake whatever the run's seed (a new seed draws new sensor noise and a "
        "scenario's [conditions] again).",
        changes=Change.AT_START,
        affects=Affects.WHAT_RUNS,
        constraints=f"empty, 'nominal', or {IDENTIFIER_RULE}",
    ),
    RunParameter(
        "duration_s",
        0.0,
        "Simulated time after which the free run ends (s); 0 at start-up = the "
        "scenario's duration. At the end the node idles, or exits with exit_at_end.",
        (0.0, 86_400.0),
        affects=Affects.END,
    ),
    RunParameter(
        "continuous",
        False,
        "Run without end: duration_s is ignored, and the run stops only when asked "
        "(pause, shutdown, or ~/reset, which starts a new run). For long runs that "
        "follow live commands or a scenario's cycle; memory stays bounded. Turned off "
        "at run time, duration_s applies again (the run ends at once if it is past).",
        affects=Affects.END,
    ),
    RunParameter(
        "exit_at_end",
        False,
        "Print a summary and exit 0 when duration_s is reached (CLI --exit-at-end).",
        changes=Change.AT_START,
        affects=Affects.END,
    ),
    RunParameter(
        "real_time_factor",
        1.0,
        "Simulated seconds per wall second; 0 = as fast as possible.",
        (0.0, 1000.0),
        affects=Affects.PACING,
    ),
    RunParameter(
        "paused",
        False,
        "Stop stepping; ~/step then advances the simulation on request.",
        affects=Affects.PACING,
    ),
    RunParameter(
        "chunk_rate_hz",
        100.0,
        "Pivot-force chunks per simulated second (Hz); each chunk carries "
        "round(sample rate / chunk_rate_hz) samples.",
        (1.0, 1000.0),
        affects=Affects.CHUNKING,
    ),
    RunParameter(
        "state_rate_hz",
        100.0,
        "BrakeState and JointState messages per simulated second (Hz), taken at "
        "sample indices that are multiples of round(sample rate / state_rate_hz).",
        (1.0, 10_000.0),
    ),
    RunParameter("publish_clock", True, "Publish simulated time on /clock (rosgraph_msgs/Clock)."),
    RunParameter(
        "publish_measured",
        False,
        "Run the scenario's sensors (noise, dynamics, faults; seeded from the run's seed) "
        "and publish what they measure on ~/measured (MeasuredChunk), measured_rate_hz "
        "chunks per simulated second. Off by default.",
        changes=Change.AT_START,
    ),
    RunParameter(
        "measured_subscribers",
        0,
        "With publish_measured: hold the first sample until ~/measured has this many "
        "subscribers (0 to 64), so that a monitor started first assesses the run from "
        "sample 0; 0 = start at once.",
        (0, 64),
        changes=Change.AT_START,
        affects=Affects.PACING,
    ),
    RunParameter(
        "measured_rate_hz",
        10.0,
        "MeasuredChunk messages per simulated second (Hz) with publish_measured: a "
        "chunk is due once round(sample rate / measured_rate_hz) samples are pending, "
        "and what is pending is also published when the run ends, pauses, at each "
        "~/step and at ~/reset. Fewer, longer chunks cost the sensors less CPU; the "
        "samples are the same bits at any rate.",
        (1.0, 1000.0),
        changes=Change.AT_START,
    ),
    RunParameter(
        "diagnostics_period_s",
        1.0,
        "Wall-time period of /diagnostics (s).",
        (0.05, 60.0),
        affects=Affects.PACING,
    ),
    RunParameter(
        "max_actuation_force_n",
        0.0,
        "Largest accepted actuation command per shoe (N); larger commands are "
        "rejected. The physics step follows any accepted force (more substeps per "
        "sample). 0 at start-up = 2 x the scenario's peak force.",
        (0.0, MAX_ACTUATION_FORCE_N),
        Change.AT_START,
        Affects.COMMANDS,
    ),
    _drive(
        "max_drive_torque_n_m",
        "Largest drive torque on the flywheel (a larger torque command is "
        "refused; the speed controller is clamped to it)",
        "N m",
        DEFAULT_MAX_DRIVE_TORQUE_N_M,
    ),
    _drive(
        "speed_time_constant_s",
        "Time constant of the speed controller's approach to a target speed",
        "s",
        DEFAULT_SPEED_TIME_CONSTANT_S,
    ),
    RunParameter(
        "command_timeout_s",
        0.2,
        "Simulated time a command stays in force without a newer one (s).",
        (0.001, 3600.0),
        affects=Affects.COMMANDS,
    ),
    RunParameter(
        "on_command_timeout",
        "profile",
        "What happens when commands stop: 'profile' (the scenario's force profile "
        "resumes at the current time), 'hold' (keep the last command), "
        "'ramp_to_zero' (fall linearly at command_ramp_rate_n_per_s, then 0).",
        affects=Affects.COMMANDS,
        constraints="one of: profile, hold, ramp_to_zero",
    ),
    RunParameter(
        "command_ramp_rate_n_per_s",
        5000.0,
        "Force decrease rate of on_command_timeout = 'ramp_to_zero' (N/s).",
        (1.0, 1e7),
        affects=Affects.COMMANDS,
    ),
)


def by_name() -> dict[str, RunParameter]:
    """The table by name (read at each call: a test may add an entry)."""
    return {p.name: p for p in RUN_PARAMETERS}


def defaults() -> dict[str, float | bool | str]:
    """Every run parameter's default, by name."""
    return {p.name: p.default for p in RUN_PARAMETERS}


def fixed_at_start() -> frozenset[str]:
    """The names a running node refuses to change."""
    return frozenset(p.name for p in RUN_PARAMETERS if p.changes is Change.AT_START)


def names_affecting(*affects: Affects) -> frozenset[str]:
    """The names of the run parameters that affect any of ``affects``."""
    return frozenset(p.name for p in RUN_PARAMETERS if p.affects in affects)


def recorded(parameter: RunParameter) -> bool:
    """Whether the ``brake_sim_run`` record carries ``parameter``'s value at the start:
    all but what runs (which has records of its own) and the wall clock's pacing. A
    live drive's settings are recorded only for a run that takes one (as in force)."""
    return parameter.affects not in (Affects.WHAT_RUNS, Affects.PACING)


def start_values(
    run: Mapping[str, Any], parameters: Mapping[str, Any] | None, where: str
) -> dict[str, float | bool | str]:
    """The run parameters a recorded run started with: for each, the ``brake_sim_run``
    record's value (``run``, decoded), else the node's parameters record's (a live run,
    ``parameters``), else its default (a recording made before the parameter existed).

    Raises:
        ParameterError: a value of the wrong type or out of range (one line, ``where``).
    """
    out: dict[str, float | bool | str] = {}
    for p in RUN_PARAMETERS:
        if recorded(p) and p.name in run:
            out[p.name] = p.check(run[p.name], f"{where} run record")
        elif parameters is not None and p.name in parameters:
            out[p.name] = p.check(parameters[p.name], f"{where} parameters record")
        else:
            out[p.name] = p.default
    return out


def check_run_id(value: str) -> str:
    """``value`` if it is a valid ``run_id`` parameter (empty included), else ParameterError
    naming what is allowed (the value shown at most 64 characters long)."""
    if value == "" or is_identifier(value):
        return value
    shown = value if len(value) <= 64 else value[:64] + "..."
    raise ParameterError(
        f"run_id={shown!r}: allowed empty (a fresh UUID4 per run) or {IDENTIFIER_RULE}"
    )
