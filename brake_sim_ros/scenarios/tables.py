"""A scenario's tables other than its defects and sensors, loaded strictly, each into the
model's or the run's type: ``[parameters]``, ``[model]``, ``[actuation]``, ``[vehicle]``,
``[thermal]``, ``[cycle]`` (a drive cycle's segments), ``[conditions]`` (ranges drawn per
run), ``[solver]`` and ``[needs]``.

Defects are :mod:`.defect_tables`', sensors :mod:`.sensors`'; the loader
(:mod:`.loader`) puts the tables together and checks what they mean together.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from typing import Any

from brake_sim_ros.errors import BrakeSimError, ScenarioError
from brake_sim_ros.fleet import conditions as operating
from brake_sim_ros.model.actuation import NOMINAL_PEAK_ACTUATION_N, Actuation, ForceProfile
from brake_sim_ros.model.assembly import SIDES, ModelOptions
from brake_sim_ros.model.cycle import LIMITS as CYCLE_LIMITS
from brake_sim_ros.model.cycle import Cycle, Segment
from brake_sim_ros.model.fidelity import ACCURACY_PRESETS, LEVEL_BY_NAME, OUTPUTS, Needs
from brake_sim_ros.model.parameters import (
    BRAKES,
    DEFAULT_BRAKE,
    NAMED_FIELDS,
    PARAMETER_GROUPS,
    BrakeParameters,
)
from brake_sim_ros.model.service_parameters import (
    ROAD_FRICTION_RANGE,
    ServiceBrakeParameters,
    TyreParameters,
)
from brake_sim_ros.model.thermal import LIMITS as THERMAL_LIMITS
from brake_sim_ros.model.thermal import Thermal
from brake_sim_ros.model.vehicle import LIMITS as VEHICLE_LIMITS
from brake_sim_ros.model.vehicle import LOAD_FACTOR_RANGE, Vehicle
from brake_sim_ros.scenarios.checker import MISSING, Checker, number_table, show_value, value_range
from brake_sim_ros.scenarios.types import MAX_STEP_RANGE_S, SolverSettings
from brake_sim_ros.sensing.sensors import DEFAULT_PISTON_DIAMETER_M, PA_PER_BAR
from brake_sim_ros.solvers.methods import SOLVER_METHODS
from brake_sim_ros.solvers.presets import DEFAULT_PRESET, PRESETS

# the key that set step and sample rate together before the sample rate became the
# scenario's: refused with a pointer to what replaced it
_RETIRED_STEP_KEY = (
    "is no longer read: the output sample rate is the top-level sample_rate_hz (default"
    " 25600 Hz) and the physics step is chosen below the step limit; [solver] max_step_s"
    " bounds it"
)


def parse_brake(ctx: Checker, top: dict[str, Any]) -> BrakeParameters:
    """The top-level key ``brake`` (default "study"): the brake whose default parameters
    the scenario's ``[parameters]`` override (``BrakeParameters.of_brake``). The fidelity
    levels below the full model represent the study brake only, so the service brake
    refuses a ``[needs]`` table. The top-level ``road_friction`` (the service brake's
    only) is the road's sliding friction coefficient under its tyre (TyreParameters;
    dry asphalt by default)."""
    name = ctx.string(top.get("brake", DEFAULT_BRAKE), "brake", BRAKES)
    if name == "service" and "needs" in top:
        raise ctx.fail(
            "needs",
            top["needs"],
            'no [needs] with brake = "service" (the reduced fidelity levels model the study'
            " brake's shoes, without return springs and rest stops: the service brake runs"
            " the full model)",
        )
    params = BrakeParameters.of_brake(name)
    if "road_friction" not in top:
        return params
    if params.service is None:
        raise ctx.fail(
            "road_friction",
            top["road_friction"],
            'road_friction only with brake = "service" (the study brake has no tyre: its'
            " wheel and vehicle are coupled by a spring that never slides)",
        )
    lo, hi = ROAD_FRICTION_RANGE
    friction = ctx.number(top["road_friction"], "road_friction", lo, hi)
    tyre = dataclasses.replace(params.service.tyre, road_friction=friction)
    return dataclasses.replace(params, service=dataclasses.replace(params.service, tyre=tyre))


def parse_parameters(ctx: Checker, data: Any, base: BrakeParameters) -> BrakeParameters:
    """``[parameters.<group>]``: overrides of the default parameters, group by group;
    ``[parameters.service]`` (and ``[parameters.service.tyre]``) on the service brake."""
    data = ctx.table(data, "parameters", {*PARAMETER_GROUPS, "service"})
    overrides: dict[str, dict[str, Any]] = {}
    for group, values in data.items():
        if group == "service":
            continue
        cls = PARAMETER_GROUPS[group]
        names = {f.name for f in dataclasses.fields(cls)}
        values = ctx.table(values, f"parameters.{group}", names)
        overrides[group] = _values(ctx, values, f"parameters.{group}", getattr(base, group))
    try:
        params = base.with_overrides(overrides)
    except BrakeSimError as exc:
        raise ScenarioError(f"{ctx.source}: [parameters]: {exc}") from exc
    return _parse_service(ctx, data["service"], params) if "service" in data else params


def _value(ctx: Checker, value: Any, key: str, default: object = None) -> float | str | bool:
    """A parameter's value: one of its names (NAMED_FIELDS), true or false for a switch
    (a field whose ``default`` is a bool: the service brake's lining over its arc), else
    a number."""
    names = NAMED_FIELDS.get(key.removeprefix("parameters."))
    if names is not None:
        return ctx.string(value, key, names)
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise ctx.fail(key, value, "true or false")
        return value
    return ctx.number(value, key)


def _values(ctx: Checker, data: dict[str, Any], table: str, defaults: object) -> dict[str, Any]:
    """Every value of ``data`` but the service table's sub-table ``tyre`` (:func:`_value`;
    ``defaults``: the dataclass instance whose fields they override)."""
    return {
        k: _value(ctx, v, f"{table}.{k}", getattr(defaults, k))
        for k, v in data.items()
        if k != "tyre"
    }


def _parse_service(ctx: Checker, data: Any, params: BrakeParameters) -> BrakeParameters:
    """``[parameters.service]``: overrides of the service brake's springs, stops and
    hydraulics (ServiceBrakeParameters), and in ``[parameters.service.tyre]`` of its tyre
    (TyreParameters) but the road's friction (the top-level ``road_friction``: the road's,
    not the tyre's). Refused on the study brake, which reads none of them."""
    if params.service is None:
        raise ctx.fail(
            "parameters.service",
            data,
            'a [parameters.service] table only with brake = "service" (the study brake has'
            " no return springs, rest stops, hydraulics or tyre to read it)",
        )
    spec = params.service
    names = {f.name for f in dataclasses.fields(ServiceBrakeParameters)}
    data = ctx.table(data, "parameters.service", names)
    values = _values(ctx, data, "parameters.service", spec)
    tyre = spec.tyre
    if "tyre" in data:
        given = data["tyre"]
        if isinstance(given, dict) and "road_friction" in given:
            raise ctx.fail(
                "parameters.service.tyre.road_friction",
                given["road_friction"],
                "the road's friction as the top-level road_friction (a condition of the"
                " road, not of the tyre; [conditions] road_friction draws it per run)",
            )
        tyre_names = {f.name for f in dataclasses.fields(TyreParameters)} - {"road_friction"}
        given = ctx.table(given, "parameters.service.tyre", tyre_names)
        tyre_values = _values(ctx, given, "parameters.service.tyre", tyre)  # names its key
        try:
            tyre = dataclasses.replace(tyre, **tyre_values)
        except BrakeSimError as exc:
            raise ScenarioError(f"{ctx.source}: [parameters.service.tyre]: {exc}") from exc
    try:
        spec = dataclasses.replace(spec, **values, tyre=tyre)
    except BrakeSimError as exc:
        raise ScenarioError(f"{ctx.source}: [parameters.service]: {exc}") from exc
    return dataclasses.replace(params, service=spec)


def parse_options(ctx: Checker, data: Any) -> ModelOptions:
    """``[model]``: ``rigid_coupling`` and the ``shoes`` the model has."""
    data = ctx.table(data, "model", {"rigid_coupling", "shoes"})
    rigid = data.get("rigid_coupling", False)
    if not isinstance(rigid, bool):
        raise ctx.fail("model.rigid_coupling", rigid, "true or false")
    shoes = data.get("shoes", list(SIDES))
    if (
        not isinstance(shoes, list)
        or not shoes
        or any(not isinstance(s, str) or s not in SIDES for s in shoes)
        or len(set(shoes)) != len(shoes)
    ):
        raise ctx.fail("model.shoes", shoes, f"a non-empty list of distinct names from {SIDES}")
    return ModelOptions(rigid_coupling=rigid, shoes=tuple(s for s in SIDES if s in shoes))


def _profile(ctx: Checker, data: Any, key: str) -> ForceProfile:
    data = ctx.table(data, key, {"times_s", "forces_n"})
    if set(data) != {"times_s", "forces_n"}:
        raise ctx.fail(key, data, "a table with both 'times_s' and 'forces_n'")
    times = data["times_s"]
    forces = data["forces_n"]
    for name, seq in (("times_s", times), ("forces_n", forces)):
        if not isinstance(seq, list) or not seq:
            raise ctx.fail(f"{key}.{name}", seq, "a non-empty array of numbers")
    t = tuple(ctx.number(v, f"{key}.times_s[{i}]", 0.0, 1e6) for i, v in enumerate(times))
    f = tuple(ctx.number(v, f"{key}.forces_n[{i}]", 0.0, 50_000.0) for i, v in enumerate(forces))
    if len(t) != len(f):
        raise ctx.fail(key, data, "'times_s' and 'forces_n' of equal length")
    if any(b <= a for a, b in itertools.pairwise(t)):
        raise ctx.fail(f"{key}.times_s", list(t), "strictly increasing times")
    return ForceProfile(t, f)


def parse_actuation(ctx: Checker, data: Any) -> Actuation:
    """``[actuation]``: a ramp (peak force, N; start and full times, s), or a piecewise
    history per shoe."""
    data = ctx.table(
        data, "actuation", {"profile", "peak_force_n", "start_s", "full_s", "left", "right"}
    )
    kind = ctx.string(data.get("profile", "ramp"), "actuation.profile", ("ramp", "piecewise"))
    if kind == "ramp":
        extra = {"left", "right"} & set(data)
        if extra:
            raise ctx.fail(
                f"actuation.{sorted(extra)[0]}",
                data[sorted(extra)[0]],
                'per-shoe histories only with profile = "piecewise"',
            )
        peak = ctx.number(
            data.get("peak_force_n", NOMINAL_PEAK_ACTUATION_N),
            "actuation.peak_force_n",
            0.0,
            50_000.0,
        )
        start = ctx.number(data.get("start_s", 0.2), "actuation.start_s", 0.0, 1e6)
        full = ctx.number(data.get("full_s", 0.7), "actuation.full_s", start, 1e6, lo_open=True)
        ramp = ForceProfile.ramp(peak, start, full)
        return Actuation(ramp, ramp)
    extra = {"peak_force_n", "start_s", "full_s"} & set(data)
    if extra:
        k = sorted(extra)[0]
        raise ctx.fail(f"actuation.{k}", data[k], 'ramp settings only with profile = "ramp"')
    missing = {"left", "right"} - set(data)
    if missing:
        raise ctx.fail(
            "actuation",
            data,
            "both [actuation.left] and [actuation.right] tables for a piecewise profile",
        )
    return Actuation(
        _profile(ctx, data["left"], "actuation.left"),
        _profile(ctx, data["right"], "actuation.right"),
    )


def parse_vehicle(ctx: Checker, data: Any) -> Vehicle:
    """``[vehicle]``: road load and grade on the flywheel (model/vehicle.py), every key
    optional (the defaults there)."""
    return Vehicle(
        **number_table(ctx, data, "vehicle", VEHICLE_LIMITS, {"wheel_radius_m", "mass_share"})
    )


def parse_thermal(ctx: Checker, data: Any) -> Thermal:
    """``[thermal]``: the brake's temperature as a state (model/thermal.py), every key
    optional (the defaults there)."""
    return Thermal(**number_table(ctx, data, "thermal", THERMAL_LIMITS, {"heat_capacity_j_k"}))


# per segment kind: the keys it takes (besides "kind"), and those it needs
_SEGMENT_KEYS: dict[str, tuple[set[str], set[str]]] = {
    "accelerate": ({"kmh"}, {"kmh"}),
    "cruise": ({"kmh", "duration_s"}, {"duration_s"}),
    "brake": ({"pressure_bar", "force_n", "until_kmh"}, set()),
    "hold": ({"pressure_bar", "force_n", "duration_s", "load_factor"}, {"duration_s"}),
    "release": ({"duration_s"}, {"duration_s"}),
    "drag": ({"kmh", "duration_s"}, {"duration_s"}),
}


def force_from_pressure_n(pressure_bar: float) -> float:
    """Force of one wheel-cylinder piston at ``pressure_bar``, N: the line-pressure
    sensor's relation (sensing/sensors.py) inverted, on its default piston."""
    return pressure_bar * PA_PER_BAR * math.pi * DEFAULT_PISTON_DIAMETER_M**2 / 4.0


def _segment(ctx: Checker, data: Any, key: str) -> Segment:
    if not isinstance(data, dict):
        raise ctx.fail(key, data, "a table with a 'kind'")
    kind = ctx.string(data.get("kind"), f"{key}.kind", tuple(_SEGMENT_KEYS))
    allowed, needed = _SEGMENT_KEYS[kind]
    data = ctx.table(data, key, {"kind", *allowed})
    for name in sorted(needed - set(data)):
        raise ctx.fail(f"{key}.{name}", MISSING, f"a number for a {kind} segment")
    if kind == "brake" and not {"pressure_bar", "force_n"} & set(data):
        raise ctx.fail(f"{key}.pressure_bar", MISSING, "pressure_bar or force_n for a brake")
    if {"pressure_bar", "force_n"} <= set(data):
        raise ctx.fail(f"{key}.force_n", data["force_n"], "pressure_bar or force_n, not both")
    force = 0.0
    if "pressure_bar" in data:
        bar = ctx.number(data["pressure_bar"], f"{key}.pressure_bar", 0.0, 250.0)
        force = force_from_pressure_n(bar)
    elif "force_n" in data:
        force = ctx.number(data["force_n"], f"{key}.force_n", 0.0, 50_000.0)
    speed_key = "until_kmh" if kind == "brake" else "kmh"
    speed = 0.0
    if speed_key in data:
        speed = ctx.number(data[speed_key], f"{key}.{speed_key}", 0.0, 250.0)
        if kind == "accelerate" and speed == 0.0:
            raise ctx.fail(f"{key}.kmh", speed, "a target speed > 0 km/h")
    duration = 0.0
    if "duration_s" in data:
        duration = ctx.number(data["duration_s"], f"{key}.duration_s", 0.0, 86_400.0)
    load = (
        _load_factor(ctx, data["load_factor"], f"{key}.load_factor")
        if "load_factor" in data
        else None
    )
    return Segment(kind, speed, force, duration, load)


def _load_factor(ctx: Checker, value: Any, key: str) -> tuple[float, float]:
    """A hold's ``load_factor``: a number, or ``[low, high]`` drawn per stop."""
    lo, hi = LOAD_FACTOR_RANGE
    allowed = f"a number or an array [low, high] with {lo:g} <= low <= high <= {hi:g}"
    if isinstance(value, list):
        return value_range(ctx, value, key, (lo, hi), allowed)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ctx.fail(key, value, allowed)
    factor = ctx.number(value, key, lo, hi)
    return factor, factor


def parse_cycle(ctx: Checker, data: Any) -> Cycle:
    """``[cycle]``: the controller's settings and ``[[cycle.segments]]`` (model/cycle.py)."""
    data = ctx.table(data, "cycle", {"segments", "repeat", *CYCLE_LIMITS})
    segments = data.get("segments", MISSING)
    if not isinstance(segments, list) or not 1 <= len(segments) <= 64:
        raise ctx.fail("cycle.segments", segments, "an array of 1 to 64 segment tables")
    settings = {
        name: ctx.number(data[name], f"cycle.{name}", lo, hi)
        for name, (lo, hi) in CYCLE_LIMITS.items()
        if name in data
    }
    repeat = data.get("repeat", False)
    if not isinstance(repeat, bool):
        raise ctx.fail("cycle.repeat", repeat, "true or false")
    built = tuple(_segment(ctx, seg, f"cycle.segments[{i}]") for i, seg in enumerate(segments))
    try:
        return Cycle(built, **settings, repeat=repeat)
    except BrakeSimError as exc:
        raise ScenarioError(f"{ctx.source}: [cycle]: {exc}") from exc


def parse_conditions(ctx: Checker, data: Any) -> tuple[tuple[str, float, float], ...]:
    """``[conditions]``: per condition a range ``[low, high]`` drawn per run."""
    data = ctx.table(data, "conditions", set(operating.CONDITION_BY_NAME))
    out = []
    for c in operating.CONDITIONS:
        if c.name not in data:
            continue
        key, value = f"conditions.{c.name}", data[c.name]
        unit = "(dimensionless)" if c.unit == "1" else c.unit
        allowed = f"an array [low, high] with {c.low:g} <= low <= high <= {c.high:g} {unit}"
        out.append((c.name, *value_range(ctx, value, key, (c.low, c.high), allowed)))
    return tuple(out)


def parse_solver(ctx: Checker, data: Any) -> SolverSettings:
    """Solver settings: a preset (default "balanced") gives the method and the largest
    physics step; an explicit ``method`` or ``max_step_s`` overrides it. The step itself
    is chosen by the stepper, below the step limit of the parameters; the sample rate is
    the scenario's, not the solver's."""
    if isinstance(data, dict) and "dt_s" in data:
        raise ScenarioError(
            f"{ctx.source}: key 'solver.dt_s' = {show_value(data['dt_s'])} {_RETIRED_STEP_KEY}"
        )
    data = ctx.table(data, "solver", {"preset", "method", "max_step_s", "rtol"})
    name = ctx.string(data.get("preset", DEFAULT_PRESET), "solver.preset", tuple(PRESETS))
    preset = PRESETS[name]
    method = ctx.string(data.get("method", preset.scheme), "solver.method", SOLVER_METHODS)
    max_step = preset.max_step_s
    if "max_step_s" in data:
        max_step = ctx.number(data["max_step_s"], "solver.max_step_s", *MAX_STEP_RANGE_S)
    return SolverSettings(
        method=method,
        max_step_s=max_step,
        rtol=ctx.number(data.get("rtol", 1e-9), "solver.rtol", 1e-13, 1e-3),
        preset=name,
    )


def parse_needs(ctx: Checker, data: Any, model_shoes: tuple[str, ...]) -> Needs:
    """``[needs]``: the outputs, shoes, accuracy and forced level a run asks for."""
    data = ctx.table(data, "needs", {"outputs", "shoes", "accuracy", "level"})
    if "outputs" not in data:
        raise ctx.fail("needs.outputs", MISSING, f"a list of outputs from {list(OUTPUTS)}")
    lists = {}
    for key, vocabulary in (("outputs", tuple(OUTPUTS)), ("shoes", SIDES)):
        value = data.get(key, list(model_shoes))
        if (
            not isinstance(value, list)
            or not value
            or any(not isinstance(v, str) or v not in vocabulary for v in value)
            or len(set(value)) != len(value)
        ):
            raise ctx.fail(
                f"needs.{key}", value, f"a non-empty list of distinct names from {list(vocabulary)}"
            )
        lists[key] = tuple(value)
    accuracy = data.get("accuracy")
    if accuracy is not None:
        accuracy = ctx.string(accuracy, "needs.accuracy", ACCURACY_PRESETS)
    level = data.get("level")
    if level is not None:
        level = ctx.string(level, "needs.level", tuple(LEVEL_BY_NAME))
    return Needs(outputs=lists["outputs"], shoes=lists["shoes"], accuracy=accuracy, level=level)
