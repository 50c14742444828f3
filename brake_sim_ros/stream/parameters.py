"""ROS parameters of the node: run control, and the model parameters generated from the core.

Model parameters are not a second source of truth. Their names, types and default values
come from the core's frozen dataclasses (``BrakeParameters``'s groups in
``model/parameters.py``, ``ShoeDefect`` and the drum's flat in ``model/defects.py``), read
from the loaded
scenario, and a new value is validated by building the core objects again and handing
them to the stepper: the core's ``ParameterError`` message (or ``StepSizeError``, for a
pathological step limit) is the refusal reason. A change that needs a smaller physics step
is not refused: the stepper re-picks its substeps per sample. Names are
``<group>.<field>`` (``friction.coefficient``, ``shoe.running_clearance_m``),
``defects.<side>.<field>`` and ``defects.drum.<field>`` for the drum's flat
(:data:`DRUM_FIELDS`; the drum's harmonics are the scenario's and have no parameter).

The ``FloatingPointRange`` of each descriptor is an envelope for tools such as
rqt_reconfigure; where the core has fixed bounds (defects, friction, drum radius, ...)
it equals them, elsewhere it is a generous plausible span. The core checks everything
else (open bounds, relations between fields such as pivot radius < drum radius, the
lining clearing the drum).

Two model fields are initial conditions and only take effect at the next ``~/reset``:
``defects.<side>.initial_angle_deg`` (the shoe's starting angle) and
``driveline.initial_speed_rad_s``. They are validated and accepted at once.

This module imports no rclpy; ``brake_sim_ros.ros.descriptors`` turns a spec into ROS's
``ParameterDescriptor``.
"""

from __future__ import annotations

import dataclasses
import inspect
import re
from dataclasses import dataclass, fields
from typing import Any

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.actuation import MAX_ACTUATION_FORCE_N, NOMINAL_PEAK_ACTUATION_N
from brake_sim_ros.model.catalogue import DRUM_KIND, KIND_BY_NAME, KINDS, label_column
from brake_sim_ros.model.defects import (
    MAX_FLAT_WIDTH_DEG,
    MAX_PULSATION_HZ,
    Defects,
    DrumDefect,
    ShoeDefect,
)
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.model.parameters import PARAMETER_GROUPS, BrakeParameters, unit_of
from brake_sim_ros.model.trajectory import BrakeSetup
from brake_sim_ros.model.vehicle import (
    DEFAULT_MAX_DRIVE_TORQUE_N_M,
    DEFAULT_SPEED_TIME_CONSTANT_S,
    DRIVE_LIMITS,
    Vehicle,
)

DRIVE_LIMIT_RANGES = {name: (lo, hi) for name, lo, hi in DRIVE_LIMITS}

DEFAULT_SCENARIO = "symmetric"

# Fields that are initial conditions: a change applies at the next reset.
INITIAL_CONDITIONS = frozenset(
    {
        "driveline.initial_speed_rad_s",
        "defects.left.initial_angle_deg",
        "defects.right.initial_angle_deg",
    }
)

# UI envelope per model field (see the module docstring); "[core]" marks the core's bounds.
_RANGES: dict[str, tuple[float, float]] = {
    "driveline.flywheel_inertia_kg_m2": (0.0, 1000.0),
    "driveline.drum_inertia_kg_m2": (0.0, 10.0),
    "driveline.coupling_stiffness_n_m_per_rad": (0.0, 1e7),
    "driveline.coupling_damping_n_m_s_per_rad": (0.0, 1e5),
    "driveline.initial_speed_rad_s": (-400.0, 400.0),  # [core]
    "shoe.drum_radius_m": (0.05, 0.5),  # [core]
    "shoe.pivot_radius_m": (0.01, 0.5),
    "shoe.pivot_polar_angle_deg": (0.0, 360.0),
    "shoe.running_clearance_m": (0.0, 0.05),
    "shoe.lining_start_deg": (90.0, 270.0),  # [core]
    "shoe.lining_end_deg": (90.0, 270.0),  # [core]
    "shoe.lining_width_m": (0.005, 0.2),  # [core]
    "shoe.tip_x_m": (-0.5, 0.5),
    "shoe.tip_y_m": (-0.5, 0.5),
    "shoe.mass_kg": (0.0, 100.0),
    "shoe.mass_centre_x_m": (-0.5, 0.5),
    "shoe.mass_centre_y_m": (-0.5, 0.5),
    "shoe.inertia_about_pivot_kg_m2": (0.0, 10.0),
    "contact.drum_youngs_modulus_pa": (1e6, 1e13),  # [core]
    "contact.drum_poisson_ratio": (0.0, 0.5),  # [core] (0.5 itself refused by the core)
    "contact.shoe_youngs_modulus_pa": (1e6, 1e13),  # [core]
    "contact.shoe_poisson_ratio": (0.0, 0.5),  # [core] (0.5 itself refused by the core)
    "contact.damping_n_s_per_m": (0.0, 1e6),
    "friction.coefficient": (0.0, 1.0),  # [core]
    "friction.smoothing_speed_m_s": (1e-5, 1.0),  # [core]
    # the defects' ranges are the catalogue's (model/catalogue.py), in scenario terms
    **{
        f"defects.{k.scenario_key}": (k.healthy_value + k.minimum, k.healthy_value + k.maximum)
        for k in KINDS
        if k.name != DRUM_KIND  # the harmonics have no node parameter
    },
    "defects.actuation_pulsation_hz": (0.0, MAX_PULSATION_HZ),  # a pulsation's attribute
    "defects.flat_centre_deg": (-360.0, 360.0),  # [core] a flat's attributes
    "defects.flat_width_deg": (0.0, MAX_FLAT_WIDTH_DEG),  # [core] (0 itself refused)
}
# the drum's fields that are node parameters (defects.drum.<field>): its flat
DRUM_FIELDS = ("flat_depth_um", "flat_centre_deg", "flat_width_deg")


@dataclass(frozen=True)
class ParamSpec:
    """One ROS parameter: name, default, documentation and UI range.

    Attributes:
        name: ROS parameter name.
        default: default value; its Python type (float, int, bool, str) is the ROS type.
        description: one or two sentences with the unit.
        range: closed (low, high) FloatingPointRange for doubles, or None.
        constraints: free-text additional constraints shown by tools.
    """

    name: str
    default: float | int | bool | str
    description: str
    range: tuple[float, float] | None = None
    constraints: str = ""


# -- run control ---------------------------------------------------------------------------
def run_parameter_specs() -> list[ParamSpec]:
    """Parameters that control the run, not the physics.

    ``duration_s`` and ``max_actuation_force_n`` default to 0 = "from the scenario"; the
    node replaces that by the effective value once the scenario is loaded.
    """
    fixed = "Fixed at start-up: a change is refused."
    return [
        ParamSpec(
            "scenario",
            DEFAULT_SCENARIO,
            "Scenario loaded at start-up: a built-in name or a path to a .toml file. "
            "Switch it with the ~/reset service (its 'scenario' field). " + fixed,
        ),
        ParamSpec(
            "scenario_dirs",
            "",
            "Directories (separated by ':') from which ~/reset requests may load .toml "
            "scenario files; empty = none, a request may only name a built-in scenario. "
            "Symlinks and '..' are resolved before the check. " + fixed,
        ),
        ParamSpec(
            "run_id",
            "",
            "Identifier of the run in every ground-truth message (DefectState, ContactEvent), "
            "in /diagnostics and in recordings: empty = a fresh UUID4 (32 hex digits) at "
            "start and at each ~/reset; otherwise this text (1 to 64 of A-Z a-z 0-9 . _ -), "
            "kept across resets. " + fixed,
            constraints="empty, or 1 to 64 characters of A-Z a-z 0-9 . _ -",
        ),
        ParamSpec(
            "unit_id",
            "",
            "Brake unit to simulate (its manufacturing scatter, drawn with the scenario's "
            "fleet_seed from the scenario's values): empty = the scenario's unit_id; "
            "'nominal' = the scenario's brake itself; otherwise 1 to 64 of A-Z a-z 0-9 _ . - "
            "(not starting with '.'). Applies to every scenario ~/reset loads; the unit is "
            "the same brake whatever the run's seed (a new seed draws new sensor noise and a "
            "scenario's [conditions] again). " + fixed,
            constraints="empty, 'nominal', or 1 to 64 characters of A-Z a-z 0-9 _ . -",
        ),
        ParamSpec(
            "duration_s",
            0.0,
            "Simulated time after which the free run ends (s); 0 at start-up = the "
            "scenario's duration. At the end the node idles, or exits with exit_at_end.",
            (0.0, 86_400.0),
        ),
        ParamSpec(
            "continuous",
            False,
            "Run without end: duration_s is ignored, and the run stops only when asked "
            "(pause, shutdown, or ~/reset, which starts a new run). For long runs that "
            "follow live commands or a scenario's cycle; memory stays bounded. Turned off "
            "at run time, duration_s applies again (the run ends at once if it is past).",
        ),
        ParamSpec(
            "exit_at_end",
            False,
            "Print a summary and exit 0 when duration_s is reached (CLI --exit-at-end). " + fixed,
        ),
        ParamSpec(
            "real_time_factor",
            1.0,
            "Simulated seconds per wall second; 0 = as fast as possible.",
            (0.0, 1000.0),
        ),
        ParamSpec(
            "paused", False, "Stop stepping; ~/step then advances the simulation on request."
        ),
        ParamSpec(
            "chunk_rate_hz",
            100.0,
            "Pivot-force chunks per simulated second (Hz); each chunk carries "
            "round(sample rate / chunk_rate_hz) samples.",
            (1.0, 1000.0),
        ),
        ParamSpec(
            "state_rate_hz",
            100.0,
            "BrakeState and JointState messages per simulated second (Hz), taken at "
            "sample indices that are multiples of round(sample rate / state_rate_hz).",
            (1.0, 10_000.0),
        ),
        ParamSpec("publish_clock", True, "Publish simulated time on /clock (rosgraph_msgs/Clock)."),
        ParamSpec(
            "publish_measured",
            False,
            "Run the scenario's sensors (noise, dynamics, faults; seeded from the run's seed) "
            "and publish what they measure on ~/measured (MeasuredChunk), measured_rate_hz "
            "chunks per simulated second. Off by default. " + fixed,
        ),
        ParamSpec(
            "measured_subscribers",
            0,
            "With publish_measured: hold the first sample until ~/measured has this many "
            "subscribers (0 to 64), so that a monitor started first assesses the run from "
            "sample 0; 0 = start at once. " + fixed,
        ),
        ParamSpec(
            "measured_rate_hz",
            10.0,
            "MeasuredChunk messages per simulated second (Hz) with publish_measured: a "
            "chunk is due once round(sample rate / measured_rate_hz) samples are pending, "
            "and what is pending is also published when the run ends, pauses, at each "
            "~/step and at ~/reset. Fewer, longer chunks cost the sensors less CPU; the "
            "samples are the same bits at any rate. " + fixed,
            (1.0, 1000.0),
        ),
        ParamSpec(
            "diagnostics_period_s", 1.0, "Wall-time period of /diagnostics (s).", (0.05, 60.0)
        ),
        ParamSpec(
            "max_actuation_force_n",
            0.0,
            "Largest accepted actuation command per shoe (N); larger commands are "
            "rejected. The physics step follows any accepted force (more substeps per "
            "sample). 0 at start-up = 2 x the scenario's peak force. " + fixed,
            (0.0, MAX_ACTUATION_FORCE_N),
        ),
        *(
            ParamSpec(
                name,
                0.0,
                f"{what} of a live drive (~/drive; a scenario with a [vehicle] and no "
                f"[cycle]), {unit}: 0 at start-up = the scenario's [vehicle] {name} "
                f"(default {default:g}); applies to every scenario ~/reset loads. " + fixed,
                (0.0, hi),
            )
            for name, what, unit, default, hi in (
                (
                    "max_drive_torque_n_m",
                    "Largest drive torque on the flywheel (a larger torque command is "
                    "refused; the speed controller is clamped to it)",
                    "N m",
                    DEFAULT_MAX_DRIVE_TORQUE_N_M,
                    DRIVE_LIMIT_RANGES["max_drive_torque_n_m"][1],
                ),
                (
                    "speed_time_constant_s",
                    "Time constant of the speed controller's approach to a target speed",
                    "s",
                    DEFAULT_SPEED_TIME_CONSTANT_S,
                    DRIVE_LIMIT_RANGES["speed_time_constant_s"][1],
                ),
            )
        ),
        ParamSpec(
            "command_timeout_s",
            0.2,
            "Simulated time a command stays in force without a newer one (s).",
            (0.001, 3600.0),
        ),
        ParamSpec(
            "on_command_timeout",
            "profile",
            "What happens when commands stop: 'profile' (the scenario's force profile "
            "resumes at the current time), 'hold' (keep the last command), "
            "'ramp_to_zero' (fall linearly at command_ramp_rate_n_per_s, then 0).",
            constraints="one of: profile, hold, ramp_to_zero",
        ),
        ParamSpec(
            "command_ramp_rate_n_per_s",
            5000.0,
            "Force decrease rate of on_command_timeout = 'ramp_to_zero' (N/s).",
            (1.0, 1e7),
        ),
    ]


FIXED_AT_START = frozenset(
    {
        "scenario",
        "scenario_dirs",
        "exit_at_end",
        "max_actuation_force_n",
        "max_drive_torque_n_m",
        "speed_time_constant_s",
        "run_id",
        "unit_id",
        "publish_measured",
        "measured_subscribers",
        "measured_rate_hz",
    }
)
_RUN_ID = re.compile(r"[A-Za-z0-9._-]{1,64}")


def check_run_id(value: str) -> str:
    """``value`` if it is a valid ``run_id`` parameter (empty included), else ParameterError
    naming what is allowed (the value shown at most 64 characters long)."""
    if value == "" or _RUN_ID.fullmatch(value):
        return value
    shown = value if len(value) <= 64 else value[:64] + "..."
    raise ParameterError(
        f"run_id={shown!r}: allowed empty (a fresh UUID4 per run) or 1 to 64 characters"
        " of A-Z a-z 0-9 . _ -"
    )


# -- model parameters ---------------------------------------------------------------------------
def _first_line(doc: str | None) -> str:
    return (doc or "").strip().splitlines()[0].rstrip(".") if doc else ""


def _attribute_doc(cls: type, field_name: str) -> str:
    """The field's entry in the class docstring's ``Attributes:`` section, one line."""
    lines = inspect.cleandoc(cls.__doc__ or "").splitlines()
    try:
        start = lines.index("Attributes:") + 1
    except ValueError:
        return ""
    entry: list[str] = []
    for line in lines[start:]:
        if not line.strip():
            break
        stripped = line.strip()
        if line.startswith("    ") and not line.startswith("        "):
            if entry:
                break
            if stripped.startswith(f"{field_name}:"):
                entry.append(stripped[len(field_name) + 1 :].strip())
        elif entry:
            entry.append(stripped)
    return " ".join(entry).rstrip(".")


def model_values(params: BrakeParameters, defects: Defects) -> dict[str, Any]:
    """Flat ``{ros_name: value}`` of every model field, in declaration order."""
    values: dict[str, Any] = {}
    for side in SIDES:
        shoe = getattr(defects, side)
        for f in fields(ShoeDefect):
            values[f"defects.{side}.{f.name}"] = getattr(shoe, f.name)
    for name in DRUM_FIELDS:
        values[f"defects.drum.{name}"] = float(getattr(defects.drum, name))
    for group in PARAMETER_GROUPS:
        obj = getattr(params, group)
        for f in fields(obj):
            values[f"{group}.{f.name}"] = getattr(obj, f.name)
    return values


def model_parameter_specs(params: BrakeParameters, defects: Defects) -> list[ParamSpec]:
    """One spec per model field, defaults from ``params`` and ``defects``."""
    specs = []
    for name, value in model_values(params, defects).items():
        parts = name.split(".")
        field_name = parts[-1]
        if parts[0] == "defects" and parts[1] == "drum":
            what = f"Drum defect, {field_name}"
            doc = _attribute_doc(DrumDefect, field_name)
            range_key = f"defects.{field_name}"
        elif parts[0] == "defects":
            what = f"{parts[1].capitalize()} shoe defect, {field_name}"
            doc = _attribute_doc(ShoeDefect, field_name)
            range_key = f"defects.{field_name}"
        else:
            cls = PARAMETER_GROUPS[parts[0]]
            what = f"{field_name}"
            doc = _attribute_doc(cls, field_name) or _first_line(cls.__doc__)
            range_key = name
        text = f"{what} ({unit_of(field_name)}): {doc}."
        if name in INITIAL_CONDITIONS:
            text += " Initial condition: a change applies at the next ~/reset."
        if name.endswith("actuation_share"):
            text += " Left + right = 1: setting one side alone sets the other side to 1 - value."
        text += " Validated by the physics core; invalid values are refused with its reason."
        specs.append(ParamSpec(name, _ros_value(value), text, _RANGES.get(range_key)))
    return specs


def _ros_value(value: Any) -> float | int | bool | str:
    if isinstance(value, bool | str):
        return value
    if isinstance(value, int):
        return int(value)
    return float(value)


def build_model(
    values: dict[str, Any], drum: DrumDefect | None = None
) -> tuple[BrakeParameters, Defects]:
    """Core objects from flat ROS values (every model field present), with ``drum`` (the
    scenario's drum: its harmonics, which have no flat values; default round) and the
    flat the values give it.

    Raises:
        ParameterError: from the core, with its message, when a value or combination is
            invalid.
    """
    shoes = {}
    for side in SIDES:
        kwargs = {f.name: values[f"defects.{side}.{f.name}"] for f in fields(ShoeDefect)}
        shoes[side] = ShoeDefect(**kwargs)
    flat = {name: values[f"defects.drum.{name}"] for name in DRUM_FIELDS}
    drum = dataclasses.replace(drum or DrumDefect(), **flat)
    defects = Defects(left=shoes["left"], right=shoes["right"], drum=drum)
    groups = {}
    for group, cls in PARAMETER_GROUPS.items():
        groups[group] = cls(**{f.name: values[f"{group}.{f.name}"] for f in fields(cls)})
    return BrakeParameters(**groups), defects


def complete_actuation_share(changes: dict[str, Any]) -> dict[str, Any]:
    """When one shoe's actuation share changes alone, add the other's as ``1 - value``.

    The core requires left + right = 1 (the total actuation force is kept), so a lone
    change could never be valid; completing it keeps ``ros2 param set`` usable.
    """
    out = dict(changes)
    for side, other in (("left", "right"), ("right", "left")):
        name, other_name = (f"defects.{side}.actuation_share", f"defects.{other}.actuation_share")
        value = changes.get(name)
        if (
            other_name not in changes
            and isinstance(value, float | int)
            and not isinstance(value, bool)
        ):
            out[other_name] = 1.0 - float(value)
    return out


# -- the actuation limit ------------------------------------------------------------------------
def auto_max_actuation_force(setup: BrakeSetup) -> float:
    """Default ``max_actuation_force_n``: 2 x the scenario's peak force (the nominal peak
    for a scenario without actuation), at most MAX_ACTUATION_FORCE_N.

    It bounds what commands may ask, nothing else: the stepper re-picks its substeps for
    any accepted force, so the physics step never limits it.
    """
    peak = max(setup.actuation.left.peak_n, setup.actuation.right.peak_n)
    base = peak if peak > 0 else NOMINAL_PEAK_ACTUATION_N
    return min(2.0 * base, MAX_ACTUATION_FORCE_N)


# -- a live drive's settings --------------------------------------------------------------------
DRIVE_LIMIT_NAMES = tuple(DRIVE_LIMIT_RANGES)


def with_drive_limits(setup: BrakeSetup, overrides: dict[str, float]) -> BrakeSetup:
    """``setup`` with its vehicle's live-drive settings (``max_drive_torque_n_m`` N m,
    ``speed_time_constant_s`` s) replaced by ``overrides`` where they are > 0 (0: the
    scenario's); unchanged for a run that takes no live drive (no vehicle, or a cycle,
    whose controller has its own settings), but the values are checked all the same.

    Raises:
        ParameterError: a value outside the vehicle's limits (``vehicle.DRIVE_LIMITS``),
            named with what is allowed.
    """
    given = {k: float(v) for k, v in overrides.items() if v != 0.0}
    unknown = set(given) - set(DRIVE_LIMIT_NAMES)
    if unknown:
        raise ParameterError(f"drive settings {sorted(unknown)}: allowed {DRIVE_LIMIT_NAMES}")
    Vehicle(**given)  # checked whether this run uses them or not (a later ~/reset may)
    if not given or setup.vehicle is None or setup.cycle is not None:
        return setup
    return dataclasses.replace(setup, vehicle=dataclasses.replace(setup.vehicle, **given))


def node_setup(
    setup: BrakeSetup, values: dict[str, Any], drive_overrides: dict[str, float]
) -> BrakeSetup:
    """The setup a node steps for a scenario's ``setup``: its model from the flat ROS
    ``values`` (every model field: the node's parameters, the scenario's with any
    overrides; :func:`changed_setup`: the scenario's drum harmonics and growth laws kept)
    and its live drive's settings from ``drive_overrides`` (:func:`with_drive_limits`).
    The node at start and ``brake-sim resim`` of its recording build it here, so they
    step the same.

    Raises:
        ParameterError: from the core, one line, for an invalid value or combination.
    """
    return with_drive_limits(changed_setup(setup, values), drive_overrides)


def changed_setup(setup: BrakeSetup, values: dict[str, Any]) -> BrakeSetup:
    """``setup`` with the model of the flat ROS ``values`` (every model field: the
    parameters after a run-time change): its drum harmonics, vehicle, cycle and the
    onsets and growth laws of its defects still present are kept (the parameters set
    final values only, so a live change of a growing defect changes where it grows to,
    not how). The node's rule for a change while it runs, and ``brake-sim resim``'s for
    a recorded one.

    Raises:
        ParameterError: from the core, one line, for an invalid value or combination.
    """
    params, defects = build_model(values, drum=setup.defects.drum)
    at = defects.severities()
    kept = tuple(
        (kind, loc, law)
        for kind, loc, law in setup.defects.growth
        if at[label_column(KIND_BY_NAME[kind], loc)] != 0.0
    )
    defects = dataclasses.replace(defects, growth=kept)
    return dataclasses.replace(setup, params=params, defects=defects)
