"""ROS parameters of the node: run control, and the model parameters generated from the core.

Model parameters are not a second source of truth. Their names, types and default values
come from the core: ``BrakeParameters``'s groups in ``model/parameters.py`` and the defect
catalogue's fields (``model/catalogue.py``: each kind's key and attributes, with their
ranges and descriptions), read from the loaded scenario, and a new value is validated by
building the core objects again and handing them to the stepper: the core's
``ParameterError`` message (or ``StepSizeError``, for a pathological step limit) is the
refusal reason. A change that needs a smaller physics step
is not refused: the stepper re-picks its substeps per sample. Names are
``<group>.<field>`` (``friction.coefficient``, ``shoe.running_clearance_m``),
``defects.<side>.<field>``, ``defects.drum.<field>`` and ``defects.line.<field>`` (the
service brake's hydraulic circuit, refused by the study brake; :func:`defect_fields`: the
catalogue's fields there; the drum's harmonics are the scenario's and have no parameter).

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
from dataclasses import dataclass, fields
from typing import Any

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.actuation import MAX_ACTUATION_FORCE_N, NOMINAL_PEAK_ACTUATION_N
from brake_sim_ros.model.catalogue import (
    KIND_BY_NAME,
    KINDS,
    LINE,
    DefectField,
    fields_at,
    kind_of_field,
    label_column,
)
from brake_sim_ros.model.defects import Defects, DrumDefect, LineDefect, ShoeDefect
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.model.parameters import (
    NAMED_FIELDS,
    PARAMETER_GROUPS,
    BrakeParameters,
    unit_of,
)
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.model.service_parameters import (
    ROAD_FRICTION_RANGE,
    SERVICE_LIMITS,
    TYRE_LIMITS,
    ServiceBrakeParameters,
    TyreParameters,
)
from brake_sim_ros.model.vehicle import DRIVE_LIMITS, Vehicle
from brake_sim_ros.stream import run_parameters
from brake_sim_ros.stream.run_parameters import (  # noqa: F401 (re-exported)
    DEFAULT_SCENARIO,
    RunParameter,
    check_run_id,
)

DRIVE_LIMIT_RANGES = {name: (lo, hi) for name, lo, hi in DRIVE_LIMITS}

# Fields that are initial conditions: a change applies at the next reset.
# Model values a recording may lack, having been made before they existed: the value that
# gave its run (build_model).
LEGACY_VALUES: dict[str, Any] = {"shoe.pose": "tip-abutment"}

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
    "service.return_spring_preload_n": (0.0, 2000.0),  # [core]
    "service.return_spring_rate_n_per_m": (0.0, 1e6),  # [core]
    "service.residual_force_n": (0.0, 2000.0),
    "service.stop_stiffness_n_per_m": (1e5, 1e9),  # [core]
    "service.stop_damping_n_s_per_m": (0.0, 1e6),
    "service.wheel_cylinder_bore_m": (0.005, 0.05),  # [core]
    "service.line_compliance_m3_per_pa": (1e-16, 1e-10),  # [core]
    "service.line_resistance_pa_s_per_m3": (1e7, 1e14),  # [core]
    "service.tyre.road_friction": ROAD_FRICTION_RANGE,  # [core]
    **{f"service.{name}": (lo, hi) for name, lo, hi, _allowed in SERVICE_LIMITS},  # [core]
    **{f"service.tyre.{name}": (lo, hi) for name, lo, hi in TYRE_LIMITS},  # [core]
}
# The service brake's groups under their node names, present only on the service brake
# (BrakeParameters.service): ``service.<field>`` (its springs, stops and hydraulics) and
# ``service.tyre.<field>`` (its tyre, the road's friction included): the scenario's
# [parameters.service] and [parameters.service.tyre], and its top-level road_friction.
SERVICE_GROUPS: dict[str, type] = {
    "service": ServiceBrakeParameters,
    "service.tyre": TyreParameters,
}
# the defects' ranges are their catalogue fields' (model/catalogue.py), in scenario terms


def defect_fields(location: str) -> tuple[DefectField, ...]:
    """The catalogue fields that are node parameters ``defects.<location>.<name>``."""
    return fields_at(location)


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


# -- run control: the table in run_parameters ---------------------------------------------
def run_parameter_specs() -> list[RunParameter]:
    """Parameters that control the run, not the physics: :data:`.run_parameters.
    RUN_PARAMETERS` (read at each call).

    ``duration_s`` and ``max_actuation_force_n`` default to 0 = "from the scenario"; the
    node replaces that by the effective value once the scenario is loaded.
    """
    return list(run_parameters.RUN_PARAMETERS)


FIXED_AT_START = run_parameters.fixed_at_start()


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
        for f in defect_fields(side):
            values[f"defects.{side}.{f.name}"] = getattr(shoe, f.name)
    for f in defect_fields("drum"):
        values[f"defects.drum.{f.name}"] = float(getattr(defects.drum, f.name))
    # the line's on either brake (a node keeps its parameters across a ~/reset to a
    # scenario on the other brake); the study brake refuses a value other than healthy
    for f in defect_fields(LINE):
        values[f"defects.{LINE}.{f.name}"] = float(getattr(defects.line, f.name))
    for group in PARAMETER_GROUPS:
        obj = getattr(params, group)
        for f in fields(obj):
            values[f"{group}.{f.name}"] = getattr(obj, f.name)
    if params.service is not None:
        for f in fields(ServiceBrakeParameters):
            if f.name != "tyre":
                values[f"service.{f.name}"] = getattr(params.service, f.name)
        for f in fields(TyreParameters):
            values[f"service.tyre.{f.name}"] = getattr(params.service.tyre, f.name)
    return values


def _service_from(values: dict[str, Any]) -> ServiceBrakeParameters | None:
    """The service brake's parameters from flat values (every ``service.*`` field), or
    None when they hold none (a study brake's).

    Raises:
        ParameterError: some of the service brake's fields given but not all, or the
            core's reason for an invalid value.
    """
    given = {k for k in values if k.startswith("service.")}
    if not given:
        return None
    names = {
        f"{group}.{f.name}"
        for group, cls in SERVICE_GROUPS.items()
        for f in fields(cls)
        if f.name != "tyre"
    }
    missing = sorted(names - given)
    if missing:
        raise ParameterError(
            f"service brake parameters without {missing[0]!r} ({len(missing)} missing):"
            " allowed all of the service brake's parameters or none"
        )
    tyre = TyreParameters(
        **{f.name: values[f"service.tyre.{f.name}"] for f in fields(TyreParameters)}
    )
    spec = {
        f.name: values[f"service.{f.name}"]
        for f in fields(ServiceBrakeParameters)
        if f.name != "tyre"
    }
    return ServiceBrakeParameters(**spec, tyre=tyre)


def model_parameter_specs(params: BrakeParameters, defects: Defects) -> list[ParamSpec]:
    """One spec per model field, defaults from ``params`` and ``defects``."""
    specs = []
    for name, value in model_values(params, defects).items():
        parts = name.split(".")
        field_name = parts[-1]
        spec_range = _RANGES.get(name)
        if parts[0] == "defects":
            where = {"drum": "Drum", LINE: "Hydraulic line"}.get(
                parts[1], f"{parts[1].capitalize()} shoe"
            )
            kind = kind_of_field(parts[1], field_name)
            f = next(f for f in kind.fields() if f.name == field_name)
            text = f"{where} defect {kind.name}, {field_name} ({f.unit}): {f.description}."
            spec_range = (f.low, f.high)
        else:
            cls = {**PARAMETER_GROUPS, **SERVICE_GROUPS}[name.rsplit(".", 1)[0]]
            doc = _attribute_doc(cls, field_name) or _first_line(cls.__doc__)
            text = f"{field_name} ({unit_of(field_name)}): {doc}."
            if name in NAMED_FIELDS:
                text = f"{field_name} (one of {', '.join(NAMED_FIELDS[name])}): {doc}."
        if name in INITIAL_CONDITIONS:
            text += " Initial condition: a change applies at the next ~/reset."
        if parts[0] == "defects" and kind_of_field(parts[1], field_name).tied:
            text += " Tied: setting one side alone sets the other side's mirror image."
        text += " Validated by the physics core; invalid values are refused with its reason."
        specs.append(ParamSpec(name, _ros_value(value), text, spec_range))
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
        kwargs = {f.name: values[f"defects.{side}.{f.name}"] for f in defect_fields(side)}
        shoes[side] = ShoeDefect(**kwargs)
    numbers = {f.name: values[f"defects.drum.{f.name}"] for f in defect_fields("drum")}
    drum = (drum or DrumDefect()).replace(**numbers)
    line = LineDefect(**{f.name: values[f"defects.{LINE}.{f.name}"] for f in defect_fields(LINE)})
    defects = Defects(left=shoes["left"], right=shoes["right"], drum=drum, line=line)
    groups = {}
    for group, cls in PARAMETER_GROUPS.items():
        # a recording made before shoes had pose rules had the only one there was
        given = {**LEGACY_VALUES, **values} if group == "shoe" else values
        groups[group] = cls(**{f.name: given[f"{group}.{f.name}"] for f in fields(cls)})
    return BrakeParameters(**groups, service=_service_from(values)), defects


def complete_actuation_share(changes: dict[str, Any]) -> dict[str, Any]:
    """When one shoe's key of a tied kind (the actuation share: catalogue
    ``DefectKind.tied``) changes alone, add the other's mirror image ``2 healthy - value``
    (``1 - value`` for the share).

    The core requires left + right = 1 (the total actuation force is kept), so a lone
    change could never be valid; completing it keeps ``ros2 param set`` usable.
    """
    out = dict(changes)
    for kind in KINDS:
        if not kind.tied:
            continue
        for side, other in (("left", "right"), ("right", "left")):
            name = f"defects.{side}.{kind.scenario_key}"
            other_name = f"defects.{other}.{kind.scenario_key}"
            value = changes.get(name)
            if (
                other_name not in changes
                and isinstance(value, float | int)
                and not isinstance(value, bool)
            ):
                out[other_name] = 2.0 * kind.healthy_value - float(value)
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
    # the brake itself is the scenario's choice: values without the service brake's
    # parameters (a recording made before they were node parameters) keep the scenario's
    if params.service is None:
        params = dataclasses.replace(params, service=setup.params.service)
    elif setup.params.service is None:
        raise ParameterError(
            "service.* parameters on the study brake: allowed only on a scenario with"
            ' brake = "service" (the study brake has no springs, hydraulics or tyre)'
        )
    elif params.service.wheel_cylinder_bore_m != setup.params.service.wheel_cylinder_bore_m:
        raise ParameterError(
            f"service.wheel_cylinder_bore_m={params.service.wheel_cylinder_bore_m!r}: allowed"
            f" only the scenario's {setup.params.service.wheel_cylinder_bore_m!r} while it"
            " runs (a part of the brake, and the line-pressure sensors read with it): set"
            " it in the scenario's [parameters.service]"
        )
    return dataclasses.replace(setup, params=params, defects=defects)
