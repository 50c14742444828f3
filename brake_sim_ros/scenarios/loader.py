"""Scenario files (TOML): strict loading into a BrakeSetup plus run settings.

A scenario names any parameter override, the defects, the actuation, the duration, the
output sample rate, the solver (a preset, or a method and a largest physics step), and
optionally what it needs (``[needs]``: outputs, shoes, accuracy,
forced level; see :mod:`brake_sim_ros.model.fidelity`), which brake unit it is (``unit_id``:
the manufacturing scatter drawn with ``fleet_seed`` around the file's values, see
:mod:`brake_sim_ros.fleet.scatter`) and ranges of operating conditions drawn per run
(``[conditions]``, :mod:`brake_sim_ros.fleet.conditions`). Loading is strict: an unknown key,
a wrong type, or a non-finite or out-of-range value is an error that names the file, the
key, the value and what is allowed. See ``builtin/symmetric.toml`` for a commented example.

A scenario file is hostile input until checked: :func:`read_scenario_file` is the one way a
file is read (regular files only, size, encoding and nesting limits, see there), and every
error is a :class:`~brake_sim_ros.errors.ScenarioError` of one line that quotes no more of
the file than a value or key of a few characters.
"""

from __future__ import annotations

import dataclasses
import os
import re
import tomllib
from importlib import resources
from typing import Any

from brake_sim_ros.errors import BrakeSimError, ScenarioError
from brake_sim_ros.fleet.scatter import NOMINAL_UNIT
from brake_sim_ros.model.adjuster import refuse_on_study
from brake_sim_ros.model.assembly import SIDES, pack
from brake_sim_ros.model.catalogue import refuse_without_circuit
from brake_sim_ros.model.cycle import pack_drive
from brake_sim_ros.model.defects import Defects
from brake_sim_ros.model.fidelity import plan
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.model.service_parameters import WHEEL_CYLINDER_BORE_M
from brake_sim_ros.model.vehicle import DRIVE_LIMITS as VEHICLE_DRIVE_LIMITS
from brake_sim_ros.scenarios.checker import MISSING, SHOWN_CHARS, Checker, show_value
from brake_sim_ros.scenarios.defect_tables import parse_defects
from brake_sim_ros.scenarios.files import (
    MAX_SCENARIO_BYTES,
    is_path,
    read_scenario_text,
    shown_path,
)
from brake_sim_ros.scenarios.sensors import parse_sensors
from brake_sim_ros.scenarios.tables import (
    parse_actuation,
    parse_brake,
    parse_conditions,
    parse_cycle,
    parse_needs,
    parse_options,
    parse_parameters,
    parse_solver,
    parse_thermal,
    parse_vehicle,
)
from brake_sim_ros.scenarios.toml_text import dumps
from brake_sim_ros.scenarios.types import DEFAULT_SAMPLE_RATE_HZ, SAMPLE_RATE_RANGE_HZ, Scenario

BUILTIN_PACKAGE = "brake_sim_ros.scenarios.builtin"
# Limits of a scenario's text beyond its size (files.MAX_SCENARIO_BYTES): a real scenario
# is four levels deep and has a short name.
MAX_NESTING = 32  # tables and arrays inside one another

MAX_NAME_CHARS = 255  # a file name's limit on common file systems


# a detail tomllib quotes from the file ("Cannot declare ('a', 'b') twice"): kept when short
_TOML_DETAIL = re.compile(r"\(.*\)|'.*?'|\".*?\"")


def _toml_reason(exc: tomllib.TOMLDecodeError) -> str:
    """tomllib's message (reason and line/column) with any long quoted detail elided."""

    def short(match: re.Match[str]) -> str:
        text = match.group(0)
        return text if len(text) <= SHOWN_CHARS and text.isprintable() else "(...)"

    text = " ".join(str(exc).split())
    where = re.search(r" \(at (line \d+, column \d+|end of document)\)$", text)
    reason = text[: where.start()] if where else text
    return _TOML_DETAIL.sub(short, reason) + (where.group(0) if where else "")


# what the nesting scan looks at: strings and comments (skipped whole), brackets, dots and
# the characters that end a key (a value's dots: one per number)
_TOKENS = re.compile(
    r'"""(?:\\.|[^\\])*?"""|\'\'\'.*?\'\'\'|"(?:\\.|[^"\\\n])*"|\'[^\'\n]*\'|#[^\n]*|[\[\]{}.=,\n]',
    re.DOTALL,
)


def _too_deep(text: str) -> bool:
    """Whether ``text`` nests brackets, or dots a key, more than :data:`MAX_NESTING` deep.

    Scanned before tomllib sees the text: tomllib recurses once per bracket (a few
    thousand are a RecursionError) and takes memory quadratic in the parts of a dotted key
    (100000 parts: over 20 GB)."""
    depth = dots = 0
    for match in _TOKENS.finditer(text):
        c = match.group(0)[0]
        if c in "\"'#":
            continue
        if c == ".":
            dots += 1
            if dots >= MAX_NESTING:  # a key of more than MAX_NESTING parts
                return True
            continue
        dots = 0
        if c in "[{":
            depth += 1
            if depth > MAX_NESTING:
                return True
        elif c in "]}":
            depth = max(0, depth - 1)
    return False


def parse_toml(text: str, source: str) -> dict[str, Any]:
    """``text`` parsed as TOML, at most :data:`MAX_NESTING` tables and arrays deep (the
    depth is scanned before tomllib sees the text).

    Raises:
        ScenarioError: not TOML (reason and position), or nested too deeply.
    """
    too_deep = ScenarioError(
        f"{source}: nested too deeply: allowed at most {MAX_NESTING} levels of tables and"
        " arrays inside one another (brackets, or parts of a dotted key)"
    )
    if _too_deep(text):
        raise too_deep
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{source}: not valid TOML: {_toml_reason(exc)}") from None
    except ValueError as exc:  # an integer of more than sys.get_int_max_str_digits() digits
        what = "a number with too many digits" if "digits" in str(exc) else "a value"
        raise ScenarioError(f"{source}: not valid TOML: {what} that cannot be read") from None
    stack: list[tuple[Any, int]] = [(data, 1)]  # walked without recursion
    while stack:
        value, depth = stack.pop()
        if depth > MAX_NESTING:
            raise too_deep
        items = value.values() if isinstance(value, dict) else value
        stack.extend((v, depth + 1) for v in items if isinstance(v, dict | list))
    return data


def parse_scenario(text: str, source: str = "<string>") -> Scenario:
    """Parse scenario TOML text; errors name ``source``.

    Raises:
        ScenarioError: anything wrong, in one line (a text over
            :data:`MAX_SCENARIO_BYTES` characters, TOML, nesting, keys, types, values, and
            the physics the values describe); never another exception type.
    """
    if len(text) > MAX_SCENARIO_BYTES:
        raise ScenarioError(
            f"{source}: {len(text)} characters: allowed at most {MAX_SCENARIO_BYTES} bytes"
        )
    try:
        return _parse(parse_toml(text, source), text, source)
    except ScenarioError:
        raise
    except BrakeSimError as exc:  # a check of the model (parameters, profile, defects)
        raise ScenarioError(f"{source}: {exc}") from exc


def on_brake(scenario: Scenario, brake: str) -> Scenario:
    """``scenario`` on the brake ``brake`` (``model.parameters.BRAKES``): its data with the
    top-level ``brake`` key set so, as a campaign sets its base's (written again as TOML
    text, :func:`.toml_text.dumps`) and parsed again; itself if it is on that brake already.

    Raises:
        ScenarioError: the scenario does not hold on this brake (one line).
    """
    if scenario.setup.params.brake == brake:
        return scenario
    data = parse_toml(scenario.text, scenario.source)
    data["brake"] = brake
    return parse_scenario(dumps(data), scenario.source)


def _name(ctx: Checker, value: Any) -> str:
    """The scenario's name: 1 to MAX_NAME_CHARS printable characters, no path separator."""
    if (
        not isinstance(value, str)
        or not 0 < len(value) <= MAX_NAME_CHARS
        or not value.isprintable()
        or any(sep in value for sep in ("/", "\\"))
        or value in (".", "..")
    ):
        raise ctx.fail(
            "name",
            value,
            f"a string of 1 to {MAX_NAME_CHARS} printable characters without '/' or '\\'",
        )
    return value


def _defects(ctx: Checker, top: dict[str, Any], params: BrakeParameters) -> Defects:
    """``[defects]`` (:func:`.defect_tables.parse_defects`) for the brake ``params``: a brake
    without a hydraulic circuit (the study brake) refuses the line's in one line."""
    defects = parse_defects(ctx, top.get("defects", {}))
    if params.service is None:  # the study brake: an ideal force source, no circuit
        try:
            refuse_without_circuit(defects.line)
        except BrakeSimError as exc:
            raise ScenarioError(f"{ctx.source}: [defects.line]: {exc}") from exc
        for side in SIDES:  # nor a self-adjuster
            try:
                refuse_on_study(side, getattr(defects, side).adjuster_seized_mm)
            except BrakeSimError as exc:
                raise ScenarioError(f"{ctx.source}: [defects.{side}]: {exc}") from exc
    return defects


# the keys a scenario file may hold at its top level
TOP_KEYS = frozenset(
    {
        "name",
        "description",
        "brake",
        "road_friction",
        "duration_s",
        "sample_rate_hz",
        "seed",
        "unit_id",
        "fleet_seed",
        "solver",
        "actuation",
        "defects",
        "parameters",
        "model",
        "needs",
        "structure",
        "sensors",
        "conditions",
        "vehicle",
        "cycle",
        "thermal",
    }
)


def _parse(data: dict[str, Any], text: str, source: str) -> Scenario:
    ctx = Checker(source)
    top = ctx.table(data, "", TOP_KEYS)
    if "name" not in top:
        raise ctx.fail("name", MISSING, "a scenario name (string); it is required")
    name = _name(ctx, top["name"])
    seed, fleet_seed = top.get("seed", 0), top.get("fleet_seed", 0)
    for key, value in (("seed", seed), ("fleet_seed", fleet_seed)):
        ctx.seed(value, key)
    params = parse_parameters(ctx, top.get("parameters", {}), parse_brake(ctx, top))
    defects = _defects(ctx, top, params)
    cycle = parse_cycle(ctx, top["cycle"]) if "cycle" in top else None
    if cycle is not None and "actuation" in top:
        raise ctx.fail(
            "actuation", top["actuation"], "no [actuation] with a [cycle] (the cycle brakes)"
        )
    vehicle = parse_vehicle(ctx, top.get("vehicle", {})) if "vehicle" in top or cycle else None
    if cycle is not None:  # the cycle's controller has its own settings
        for key, _lo, _hi in VEHICLE_DRIVE_LIMITS:
            if key in top.get("vehicle", {}):
                raise ctx.fail(
                    f"vehicle.{key}",
                    top["vehicle"][key],
                    f"no [vehicle] {key} with a [cycle] (a live drive's setting; the"
                    f" cycle's controller takes [cycle] {key})",
                )
    setup = BrakeSetup(
        params=params,
        defects=defects,
        actuation=parse_actuation(ctx, top.get("actuation", {})),
        options=parse_options(ctx, top.get("model", {})),
        vehicle=vehicle,
        cycle=cycle,
        thermal=parse_thermal(ctx, top["thermal"]) if "thermal" in top else None,
    )
    if cycle is not None:
        _check_cycle_setup(ctx, top, setup)
    needs = parse_needs(ctx, top["needs"], setup.options.shoes) if "needs" in top else None
    if needs is not None:  # the level must represent the scenario's defects and vehicle
        needs = dataclasses.replace(
            needs,
            defects=defects.kinds,
            growing=defects.growing_kinds,
            driven=setup.driven,
            thermal=setup.thermal is not None,
        )
    try:
        pack_drive(pack(setup.params, setup.defects, setup.options), setup)
        plan(needs, model_shoes=setup.options.shoes)  # refuse needs no level can serve
    except BrakeSimError as exc:
        raise ScenarioError(f"{source}: {exc}") from exc
    scenario = Scenario(
        name=name,
        description=ctx.string(top.get("description", ""), "description"),
        setup=setup,
        duration_s=ctx.number(
            top.get("duration_s", 7.5), "duration_s", 0.0, 86_400.0, lo_open=True
        ),
        seed=seed,
        unit_id=ctx.identifier(top.get("unit_id", NOMINAL_UNIT), "unit_id"),
        fleet_seed=fleet_seed,
        solver=parse_solver(ctx, top.get("solver", {})),
        sample_rate_hz=ctx.number(
            top.get("sample_rate_hz", DEFAULT_SAMPLE_RATE_HZ),
            "sample_rate_hz",
            *SAMPLE_RATE_RANGE_HZ,
        ),
        source=source,
        text=text,
        needs=needs,
        sensors=parse_sensors(ctx, top.get("structure"), top.get("sensors")),
        condition_ranges=parse_conditions(ctx, top.get("conditions", {})),
    )
    _check_bore(ctx, top, scenario)
    return scenario.with_unit()  # the file's values are the drawing; the unit scatters them


def _check_bore(ctx: Checker, top: dict[str, Any], scenario: Scenario) -> None:
    """Refuse a service brake's wheel-cylinder bore that the line-pressure sensors or the
    cycle's pressures would not read: a channel converts the piston's force to pressure on
    its own ``piston_diameter_m``, a cycle's ``pressure_bar`` on the default bore, so a bore
    of another size would make them report or apply another pressure than the model's."""
    spec = scenario.setup.params.service
    if spec is None or spec.wheel_cylinder_bore_m == WHEEL_CYLINDER_BORE_M:
        return
    key, bore = "parameters.service.wheel_cylinder_bore_m", spec.wheel_cylinder_bore_m
    for channel in scenario.sensors.channels:
        if channel.kind == "line_pressure" and channel.piston_diameter_m != bore:
            raise ctx.fail(
                key,
                bore,
                f"the piston_diameter_m of line-pressure channel {show_value(channel.name)}"
                f" ({channel.piston_diameter_m:g} m): give the channel the same bore in"
                " [[sensors]], so that it reads the modelled pressure",
            )
    segments = top.get("cycle", {}).get("segments", [])
    if any(isinstance(seg, dict) and "pressure_bar" in seg for seg in segments):
        raise ctx.fail(
            key,
            bore,
            f"the default bore ({WHEEL_CYLINDER_BORE_M:g} m) with a [cycle] whose segments"
            " give pressure_bar (converted to force on the default bore): give them force_n",
        )


def _check_cycle_setup(ctx: Checker, top: dict[str, Any], setup: BrakeSetup) -> None:
    """Refuse what a drive cycle cannot carry: a shaped actuation (its history is the
    cycle's ramp, which the delay and lag formulas would read as the whole history), a
    drawn peak force (the cycle's segments give the forces) and a drawn load with holds
    that set it per stop (which would the factor be over?)."""
    for side in SIDES:
        defect = getattr(setup.defects, side)
        if defect.force_shaped:
            raise ScenarioError(
                f"{ctx.source}: [defects.{side}]: an actuation delay, lag, pulsation or weak"
                " return spring with a [cycle]: not represented (the cycle's brake ramp is not"
                " a whole actuation history): allowed without a cycle"
            )
    if "peak_force_n" in top.get("conditions", {}):
        raise ctx.fail(
            "conditions.peak_force_n",
            top["conditions"]["peak_force_n"],
            "no drawn peak force with a [cycle] (its segments give the brake forces)",
        )
    if setup.cycle.loads and "load_factor" in top.get("conditions", {}):
        raise ctx.fail(
            "conditions.load_factor",
            top["conditions"]["load_factor"],
            "no drawn load per run with a [cycle] whose holds set the load_factor per stop"
            " (one or the other)",
        )


def builtin_names() -> list[str]:
    """Names of the scenarios shipped with the package."""
    files = resources.files(BUILTIN_PACKAGE).iterdir()
    return sorted(f.name[:-5] for f in files if f.name.endswith(".toml"))


def read_scenario_file(path: str | os.PathLike[str]) -> Scenario:
    """Read and parse one scenario file, as hostile input.

    The one function that reads a scenario file (``brake-sim simulate FILE.toml``, the
    node's ``--scenario`` and its ``~/reset`` service, through :func:`load_scenario`).
    Limits, each checked before the next step:

    * a regular file (a symbolic link to one is followed; a link loop, a directory, a FIFO,
      a device or a socket is refused, and opening never waits for a FIFO's writer);
    * at most :data:`MAX_SCENARIO_BYTES` (1 MiB; a real scenario is a few kB);
    * UTF-8 text (a leading byte-order mark is dropped);
    * TOML, at most :data:`MAX_NESTING` (32) tables and arrays inside one another;
    * then :func:`parse_scenario`'s checks: known keys, types, ranges, a ``name`` of 1 to
      :data:`MAX_NAME_CHARS` (255) printable characters without ``/`` or ``\\``, and the
      physics of the values.

    Raises:
        ScenarioError: the first limit or check that fails, in one line naming the file.
            The message never quotes the file beyond a value or key of at most
            :data:`SHOWN_CHARS` characters, and no other exception type escapes.
    """
    name = shown_path(path)
    return parse_scenario(read_scenario_text(path), name)


def load_scenario(name_or_path: str | os.PathLike[str]) -> Scenario:
    """Load a built-in scenario by name, or a scenario file by path
    (:func:`read_scenario_file`, with its limits).

    Raises:
        ScenarioError: an unknown name, or a file that cannot be read or parsed (one line).
    """
    if is_path(name_or_path):
        return read_scenario_file(name_or_path)
    name = str(name_or_path)
    if name not in builtin_names():
        shown = show_value(name) if name else "''"
        raise ScenarioError(
            f"unknown scenario {shown}: allowed a path to a .toml file or one of"
            f" the built-in scenarios {builtin_names()}"
        )
    text = resources.files(BUILTIN_PACKAGE).joinpath(f"{name}.toml").read_text(encoding="utf-8")
    return parse_scenario(text, f"<built-in {name}>")
