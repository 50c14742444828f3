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
import hashlib
import itertools
import math
import os
import re
import stat
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from typing import Any

from brake_sim_ros.errors import BrakeSimError, ScenarioError
from brake_sim_ros.fleet import conditions as operating
from brake_sim_ros.fleet.scatter import NOMINAL_UNIT, UnitValue, unit_values
from brake_sim_ros.identifiers import IDENTIFIER_RULE, is_identifier
from brake_sim_ros.model.actuation import (
    NOMINAL_PEAK_ACTUATION_N,
    Actuation,
    ForceProfile,
)
from brake_sim_ros.model.assembly import SIDES, ModelOptions, pack
from brake_sim_ros.model.catalogue import (
    DRUM_KIND,
    GROWTH_KEYS,
    GROWTH_LAWS,
    LAW_PARAMETERS,
    MAX_GROWTH_TIME_S,
    DefectKind,
    Growth,
    fields_at,
    kinds_at,
)
from brake_sim_ros.model.cycle import LIMITS as CYCLE_LIMITS
from brake_sim_ros.model.cycle import Cycle, Segment, pack_drive
from brake_sim_ros.model.defects import (
    MAX_DRUM_HARMONICS,
    MAX_DRUM_ORDER,
    Defects,
    DrumDefect,
    DrumHarmonic,
    ShoeDefect,
)
from brake_sim_ros.model.fidelity import ACCURACY_PRESETS, LEVEL_BY_NAME, OUTPUTS, Needs, plan
from brake_sim_ros.model.parameters import (
    BRAKES,
    DEFAULT_BRAKE,
    PARAMETER_GROUPS,
    BrakeParameters,
)
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.model.thermal import LIMITS as THERMAL_LIMITS
from brake_sim_ros.model.thermal import Thermal
from brake_sim_ros.model.vehicle import DRIVE_LIMITS as VEHICLE_DRIVE_LIMITS
from brake_sim_ros.model.vehicle import LIMITS as VEHICLE_LIMITS
from brake_sim_ros.model.vehicle import LOAD_FACTOR_RANGE, Vehicle
from brake_sim_ros.scenarios.sensors import parse_sensors
from brake_sim_ros.scenarios.unit_draws import unit_brake, unit_sensor_set
from brake_sim_ros.sensing.sensors import (
    DEFAULT_PISTON_DIAMETER_M,
    PA_PER_BAR,
    SensorSet,
    default_sensor_set,
)
from brake_sim_ros.solvers.fixed_step import MIN_PHYSICS_STEP_S
from brake_sim_ros.solvers.methods import FIXED_STEP_METHODS, SOLVER_METHODS
from brake_sim_ros.solvers.presets import DEFAULT_PRESET, PRESETS

BUILTIN_PACKAGE = "brake_sim_ros.scenarios.builtin"
# The output sample rate of a scenario that does not set one: 25.6 kHz, the common
# condition-monitoring rate (a power-of-two number of samples per 10 ms chunk: 256).
DEFAULT_SAMPLE_RATE_HZ = 25_600.0
SAMPLE_RATE_RANGE_HZ = (1.0, 1e6)
# The largest physics step a scenario or the command line may set, s: from the smallest step
# the stepper takes (a smaller bound would ask for billions of substeps) to 10 ms.
MAX_STEP_RANGE_S = (MIN_PHYSICS_STEP_S, 1e-2)

# Limits of a scenario file (read_scenario_file): a real scenario is a few kB, four levels
# deep and has a short name.
MAX_SCENARIO_BYTES = 1024 * 1024
MAX_NESTING = 32  # tables and arrays inside one another
MAX_NAME_CHARS = 255  # a file name's limit on common file systems
# a value or key is quoted in an error message only up to this many characters (its repr);
# a longer one is described ("a string of 300 characters"): messages never echo the file
SHOWN_CHARS = 24
_MISSING = object()
# the key that set step and sample rate together before the sample rate became the
# scenario's: refused with a pointer to what replaced it
_RETIRED_STEP_KEY = (
    "is no longer read: the output sample rate is the top-level sample_rate_hz (default"
    " 25600 Hz) and the physics step is chosen below the step limit; [solver] max_step_s"
    " bounds it"
)


@dataclass(frozen=True)
class SolverSettings:
    """How a scenario is integrated. Not the sample rate: that is the scenario's.

    Attributes:
        method: a fixed-step scheme ("rk4-located", "rk4", "semi-implicit-euler": compiled,
            real-time capable) or "reference" (adaptive DOP853 with contact onsets and the
            lock located as events).
        max_step_s: largest physics step of the fixed-step schemes, s (accuracy); the
            stepper takes the fewest whole substeps per sample that keep within it and
            within the step limit of the parameters.
        rtol: relative tolerance of the reference solver.
        preset: the preset (``solvers.presets``) that gave the method and the largest
            step where the scenario did not set them explicitly.
    """

    method: str = PRESETS[DEFAULT_PRESET].scheme
    max_step_s: float = PRESETS[DEFAULT_PRESET].max_step_s
    rtol: float = 1e-9
    preset: str = DEFAULT_PRESET

    @property
    def fixed_step_scheme(self) -> str:
        """The scheme a fixed-step stepper (the ROS node) uses: the method, or the preset's
        scheme when the method is the reference solver."""
        return self.method if self.method in FIXED_STEP_METHODS else PRESETS[self.preset].scheme

    def with_overrides(
        self,
        *,
        preset: str | None = None,
        method: str | None = None,
        max_step_s: float | None = None,
    ) -> SolverSettings:
        """These settings with a new preset (its method and largest step replace the
        current ones), then an explicit method or largest step on top; None keeps."""
        out = self
        if preset is not None:
            if preset not in PRESETS:
                raise ScenarioError(f"solver preset {preset!r}: allowed one of {list(PRESETS)}")
            chosen = PRESETS[preset]
            out = dataclasses.replace(
                out, preset=preset, method=chosen.scheme, max_step_s=chosen.max_step_s
            )
        if method is not None:
            if method not in SOLVER_METHODS:
                raise ScenarioError(f"solver method {method!r}: allowed one of {SOLVER_METHODS}")
            out = dataclasses.replace(out, method=method)
        if max_step_s is not None:
            lo, hi = MAX_STEP_RANGE_S
            if not (math.isfinite(max_step_s) and lo <= max_step_s <= hi):
                raise ScenarioError(
                    f"largest physics step {max_step_s!r} s: allowed a step from {lo:g} to {hi:g} s"
                )
            out = dataclasses.replace(out, max_step_s=float(max_step_s))
        return out


@dataclass(frozen=True)
class Scenario:
    """A braking event to run: the physics setup and how long and how to integrate it."""

    name: str
    description: str = ""
    setup: BrakeSetup = field(default_factory=BrakeSetup)
    duration_s: float = 7.5
    seed: int = 0  # the run's: its sensor noise and its drawn [conditions]
    # which brake of a fleet; "nominal": the drawing's brake. ``setup.params`` and
    # ``sensors`` are that unit's (fleet/scatter.py), drawn from the scenario's values (kept
    # in ``nominal_params`` / ``nominal_sensors``) with ``unit_id`` and ``fleet_seed``: a
    # unit is the same brake in every run, whatever the run's seed
    unit_id: str = NOMINAL_UNIT
    fleet_seed: int = 0
    solver: SolverSettings = field(default_factory=SolverSettings)
    sample_rate_hz: float = DEFAULT_SAMPLE_RATE_HZ
    source: str = "<built-in>"
    text: str = ""
    needs: Needs | None = None  # None: the full model, every signal
    sensors: SensorSet = field(default_factory=default_sensor_set)  # [structure], [[sensors]]
    nominal_params: BrakeParameters | None = None  # the scenario's own; None: setup.params
    nominal_sensors: SensorSet | None = None  # the scenario's own; None: sensors
    # [conditions]: (name, low, high) ranges drawn per run from the seed (fleet/conditions.py),
    # and the values drawn for this run, (name, value), applied to setup
    condition_ranges: tuple[tuple[str, float, float], ...] = ()
    conditions: tuple[tuple[str, float], ...] = ()
    nominal_actuation: Actuation | None = None  # the scenario's own; None: setup.actuation

    @property
    def drawn(self) -> bool:
        """Whether the run's seed draws this scenario's operating conditions (it has
        ``[conditions]`` ranges): another seed is then another setup, not only other
        noise."""
        return bool(self.condition_ranges)

    @property
    def drawing_params(self) -> BrakeParameters:
        """The scenario's parameters before the unit's scatter (its file's values)."""
        return self.setup.params if self.nominal_params is None else self.nominal_params

    @property
    def drawing_sensors(self) -> SensorSet:
        """The scenario's sensors before the unit's scatter."""
        return self.sensors if self.nominal_sensors is None else self.nominal_sensors

    def conditions_record(self) -> dict[str, dict[str, Any]]:
        """The run's drawn operating conditions for ground truth: per name its value,
        unit and range (empty without ``[conditions]``)."""
        ranges = {name: (low, high) for name, low, high in self.condition_ranges}
        return {
            name: {
                "value": value,
                "unit": operating.CONDITION_BY_NAME[name].unit,
                "range": list(ranges[name]),
            }
            for name, value in self.conditions
        }

    def unit_values(self) -> list[UnitValue]:
        """Every scattered value of this scenario's unit against the scenario's own (the
        unit's ground truth; all unchanged for unit "nominal")."""
        return unit_values(
            self.drawing_params, self.setup.params, self.drawing_sensors, self.sensors
        )

    def with_unit(
        self,
        unit_id: str | None = None,
        *,
        seed: int | None = None,
        fleet_seed: int | None = None,
    ) -> Scenario:
        """This scenario as brake unit ``unit_id`` of the fleet ``fleet_seed``, run with
        ``seed`` (None keeps each): the scenario's own parameters and sensors with the
        unit's manufacturing scatter (:mod:`brake_sim_ros.fleet.scatter`, drawn from the unit
        id and the fleet seed: the same brake in every run); unit "nominal" is the
        scenario's brake itself. The run's seed draws its operating conditions from the
        scenario's ``[conditions]`` ranges (:mod:`brake_sim_ros.fleet.conditions`),
        applied to the scenario's own values before the unit's scatter, and seeds the
        sensor noise. Defects and model options are kept as they are.

        Raises:
            ScenarioError: a malformed unit id or seed, or a unit whose drawn brake leaves
                the model's validity (one line naming the scenario and the unit).
        """
        unit_id = self.unit_id if unit_id is None else unit_id
        seed = self.seed if seed is None else seed
        fleet_seed = self.fleet_seed if fleet_seed is None else fleet_seed
        ctx = _Ctx(self.source)
        _unit_id(ctx, unit_id)
        for key, value in (("seed", seed), ("fleet_seed", fleet_seed)):
            if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < 2**63:
                raise ctx.fail(key, value, "an integer from 0 to 2^63 - 1")
        params, sensors = self.drawing_params, self.drawing_sensors
        actuation = (
            self.setup.actuation if self.nominal_actuation is None else self.nominal_actuation
        )
        ranges = {name: (low, high) for name, low, high in self.condition_ranges}
        try:
            drawn = operating.draw(ranges, seed)
            setup = operating.apply(
                dataclasses.replace(self.setup, params=params, actuation=actuation), drawn
            )
            setup = dataclasses.replace(setup, params=unit_brake(setup.params, unit_id, fleet_seed))
            if setup.cycle is not None:  # the seed keys its per-stop load draws
                setup = dataclasses.replace(
                    setup, cycle=dataclasses.replace(setup.cycle, seed=seed)
                )
            drawn_sensors = unit_sensor_set(sensors, unit_id, fleet_seed)
            pack_drive(pack(setup.params, setup.defects, setup.options), setup)
        except BrakeSimError as exc:
            raise ScenarioError(f"{self.source}: {exc}") from None
        return dataclasses.replace(
            self,
            setup=setup,
            sensors=drawn_sensors,
            unit_id=unit_id,
            seed=seed,
            fleet_seed=fleet_seed,
            nominal_params=params,
            nominal_sensors=sensors,
            nominal_actuation=actuation,
            conditions=tuple(drawn.items()),
        )

    @property
    def digest(self) -> str:
        """SHA-256 of the scenario file's text (empty when built in code)."""
        return hashlib.sha256(self.text.encode()).hexdigest()

    @property
    def sample_period_s(self) -> float:
        """Time between output samples, s."""
        return 1.0 / self.sample_rate_hz

    def with_solver(
        self,
        *,
        preset: str | None = None,
        method: str | None = None,
        max_step_s: float | None = None,
        sample_rate_hz: float | None = None,
    ) -> Scenario:
        """This scenario with solver settings or the sample rate overridden (the CLI's
        ``--preset``, ``--method``, ``--max-step``, ``--sample-rate``); None keeps."""
        solver = self.solver.with_overrides(preset=preset, method=method, max_step_s=max_step_s)
        rate = self.sample_rate_hz
        if sample_rate_hz is not None:
            lo, hi = SAMPLE_RATE_RANGE_HZ
            if not (math.isfinite(sample_rate_hz) and lo <= sample_rate_hz <= hi):
                raise ScenarioError(
                    f"sample rate {sample_rate_hz!r} Hz: allowed {lo:g} to {hi:g} Hz"
                )
            rate = float(sample_rate_hz)
        return dataclasses.replace(self, solver=solver, sample_rate_hz=rate)

    def with_defects(self, defects: Defects) -> Scenario:
        setup = dataclasses.replace(self.setup, defects=defects)
        pack_drive(pack(setup.params, setup.defects, setup.options), setup)  # validity check
        needs = self.needs
        if needs is not None:  # the level must represent the new defects
            needs = dataclasses.replace(needs, defects=defects.kinds, growing=defects.growing_kinds)
            plan(needs, model_shoes=setup.options.shoes)
        return dataclasses.replace(self, setup=setup, needs=needs)


# --- strict value checks --------------------------------------------------------------------
def _kind(value: Any) -> str:
    """What ``value`` is, without quoting it."""
    if isinstance(value, dict):
        return f"a table of {len(value)} key{'s' * (len(value) != 1)}"
    if isinstance(value, list):
        return f"an array of {len(value)} item{'s' * (len(value) != 1)}"
    if isinstance(value, str):
        return f"a string of {len(value)} characters"
    if isinstance(value, int) and not isinstance(value, bool):
        return f"an integer of {len(str(abs(value)))} digits"
    return f"a {type(value).__name__} value"


def _short(value: Any) -> bool:
    """Whether ``value``'s repr is cheap and possibly short (no deep or long content)."""
    if isinstance(value, str):
        return len(value) <= SHOWN_CHARS
    if isinstance(value, int) and not isinstance(value, bool):
        return abs(value) < 10**SHOWN_CHARS
    if isinstance(value, dict):
        return len(value) <= 8 and all(_short(k) and _short_scalar(v) for k, v in value.items())
    if isinstance(value, list):
        return len(value) <= 8 and all(_short_scalar(v) for v in value)
    return True


def _short_scalar(value: Any) -> bool:
    return not isinstance(value, dict | list) and _short(value)


def show_value(value: Any) -> str:
    """``value`` for a one-line message: its repr when short and printable (at most
    :data:`SHOWN_CHARS` characters), else what it is ("a string of 300 characters")."""
    if isinstance(value, bool):
        return "true" if value else "false"
    text = repr(value) if _short(value) else ""
    return text if 0 < len(text) <= SHOWN_CHARS and text.isprintable() else _kind(value)


def _show_key(key: str) -> str:
    """A key of the file for a message (keys longer than 40 characters are described)."""
    if len(key) <= 40 and key.isprintable():
        return key
    return f"<a key of {len(key)} characters>"


class _Ctx:
    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, key: str, value: Any, allowed: str) -> ScenarioError:
        if value is _MISSING:
            return ScenarioError(f"{self.source}: key '{key}' is missing: allowed {allowed}")
        return ScenarioError(
            f"{self.source}: key '{key}' = {show_value(value)} is invalid: allowed {allowed}"
        )

    def table(self, data: Any, key: str, allowed_keys: set[str]) -> dict[str, Any]:
        if not isinstance(data, dict):
            raise self.fail(key, data, "a table")
        for k in data:
            if k not in allowed_keys:
                where = f"{key}.{_show_key(k)}" if key else _show_key(k)
                raise self.fail(
                    where, data[k], f"one of the keys {sorted(allowed_keys)} (unknown key)"
                )
        return data

    def number(
        self,
        value: Any,
        key: str,
        lo: float = -math.inf,
        hi: float = math.inf,
        lo_open: bool = False,
    ) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(key, value, "a number")
        value = float(value)
        if not math.isfinite(value):
            raise self.fail(key, value, "a finite number")
        if value < lo or value > hi or (lo_open and value == lo):
            low = f"> {lo:g}" if lo_open else f">= {lo:g}"
            raise self.fail(key, value, f"a number {low} and <= {hi:g}")
        return value

    def string(self, value: Any, key: str, choices: tuple[str, ...] | None = None) -> str:
        if not isinstance(value, str):
            raise self.fail(key, value, "a string")
        if choices is not None and value not in choices:
            raise self.fail(key, value, f"one of {list(choices)}")
        return value


def _profile(ctx: _Ctx, data: Any, key: str) -> ForceProfile:
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


def _actuation(ctx: _Ctx, data: Any) -> Actuation:
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


def _growth(ctx: _Ctx, data: dict[str, Any], key: str, healthy: float) -> Growth:
    """The onset and growth law stated in ``data`` (keys :data:`.catalogue.GROWTH_KEYS`,
    all optional: a step at 0 s); the parameters each law takes, their limits and
    defaults are the catalogue's (:data:`.catalogue.LAW_PARAMETERS`). ``start`` is a value
    of the key itself, so ``healthy`` (the key's healthy value) is taken off to give a
    severity."""
    law = ctx.string(data.get("growth", "step"), f"{key}.growth", GROWTH_LAWS)
    onset = ctx.number(data.get("onset_s", 0.0), f"{key}.onset_s", 0.0, MAX_GROWTH_TIME_S)
    values: dict[str, Any] = {"onset_s": onset, "law": law}
    for param in LAW_PARAMETERS:
        name = param.name
        if name in data and law != param.law:
            raise ctx.fail(f"{key}.{name}", data[name], f'a value only with growth = "{param.law}"')
        if law != param.law:
            continue
        if name not in data and param.default is None:
            raise ctx.fail(f"{key}.{name}", _MISSING, f'a number with growth = "{law}"')
        value = data.get(name, param.default)
        if param.high is None:
            values[name] = ctx.number(value, f"{key}.{name}") - healthy
        else:
            values[name] = ctx.number(value, f"{key}.{name}", 0.0, param.high, lo_open=True)
    try:
        return Growth(**values)
    except BrakeSimError as exc:
        raise ScenarioError(f"{ctx.source}: [{key}]: {exc}") from exc


def _value_or_growth(
    ctx: _Ctx, value: Any, key: str, kind: DefectKind
) -> tuple[float, Growth | None]:
    """A defect key's value: a number (the final value, present from the start), or a
    table ``{value, onset_s, growth, ...}`` (:data:`.catalogue.GROWTH_KEYS`): the final
    value and its growth."""
    growth = None
    if isinstance(value, dict):
        value = ctx.table(value, key, {"value", *GROWTH_KEYS})
        if "value" not in value:
            raise ctx.fail(f"{key}.value", _MISSING, "a number (the final value)")
        growth = _growth(ctx, value, key, kind.healthy_value)
        value = value["value"]
    return ctx.number(value, key), growth


def _location_values(
    ctx: _Ctx, data: dict[str, Any], location: str, growth: list[tuple[str, str, Growth]]
) -> dict[str, float]:
    """The numbers of ``[defects.<location>]``: each catalogue field there given (its
    kind's key may carry a growth table, added to ``growth``)."""
    values = {}
    for kind in kinds_at(location):
        for f in kind.fields():
            if f.name not in data:
                continue
            key = f"defects.{location}.{f.name}"
            if f.name == kind.scenario_key:
                values[f.name], law = _value_or_growth(ctx, data[f.name], key, kind)
                if law is not None:
                    growth.append((kind.name, location, law))
            else:
                values[f.name] = ctx.number(data[f.name], key)
    return values


def _harmonics(ctx: _Ctx, rows: Any) -> tuple[DrumHarmonic, ...]:
    """``[[defects.drum.harmonics]]``: tables ``{order, amplitude_um, phase_deg}``."""
    if not isinstance(rows, list):
        raise ctx.fail(
            "defects.drum.harmonics", rows, "an array of tables {order, amplitude_um, phase_deg}"
        )
    if len(rows) > MAX_DRUM_HARMONICS:
        raise ctx.fail("defects.drum.harmonics", rows, f"at most {MAX_DRUM_HARMONICS} harmonics")
    harmonics = []
    for i, row in enumerate(rows):
        key = f"defects.drum.harmonics[{i}]"
        row = ctx.table(row, key, {"order", "amplitude_um", "phase_deg"})
        for name in ("order", "amplitude_um"):
            if name not in row:
                raise ctx.fail(f"{key}.{name}", _MISSING, "a number (order: an integer)")
        order = row["order"]
        if isinstance(order, bool) or not isinstance(order, int):
            raise ctx.fail(f"{key}.order", order, f"an integer 1 to {MAX_DRUM_ORDER}")
        amplitude = ctx.number(row["amplitude_um"], f"{key}.amplitude_um")
        phase = ctx.number(row.get("phase_deg", 0.0), f"{key}.phase_deg")
        try:
            harmonics.append(DrumHarmonic(order, amplitude, phase))
        except BrakeSimError as exc:
            raise ScenarioError(f"{ctx.source}: [{key}]: {exc}") from exc
    return tuple(harmonics)


def _drum(ctx: _Ctx, data: Any, growth: list[tuple[str, str, Growth]]) -> DrumDefect:
    """``[defects.drum]``: ``harmonics``, an array of tables ``{order, amplitude_um,
    phase_deg}`` (phase optional, 0 deg); the amplitudes are the final ones and the
    growth keys (:data:`.catalogue.GROWTH_KEYS`) in the table itself say when the drum
    goes out of round and how (``rate_per_s`` and ``start`` in um of peak runout, the sum
    of the amplitudes; every harmonic grows in proportion). Every other drum field is
    the catalogue's (``fields_at("drum")``, e.g. a flat's ``flat_depth_um``, a number or
    a table ``{value, onset_s, growth, ...}`` as a shoe's keys, and its attributes)."""
    numbers = {f.name for f in fields_at("drum")}
    data = ctx.table(data, "defects.drum", {"harmonics", *GROWTH_KEYS, *numbers})
    growth.append((DRUM_KIND, "drum", _growth(ctx, data, "defects.drum", 0.0)))
    values = _location_values(ctx, data, "drum", growth)
    harmonics = _harmonics(ctx, data.get("harmonics", []))
    try:
        return DrumDefect(harmonics, **values)
    except BrakeSimError as exc:
        raise ScenarioError(f"{ctx.source}: [defects.drum]: {exc}") from exc


def _defects(ctx: _Ctx, data: Any) -> Defects:
    """``[defects.left]``, ``[defects.right]``: each key a catalogue field of a shoe
    (``brake-sim defects``): a kind's key is a number (the final value, present from the
    start) or a table ``{value, onset_s, growth, rate_per_s, doubling_time_s, start}``
    (:data:`.catalogue.GROWTH_KEYS`: when it starts and how it grows toward ``value``;
    ``start`` and ``rate_per_s`` in the key's unit, e.g. 0.52 and 0.05 for a share); a
    tied kind's key given for one shoe only implies the other's (the actuation shares sum
    to 1); ``[defects.drum]``: :func:`_drum`."""
    data = ctx.table(data, "defects", {*SIDES, "drum"})
    growth: list[tuple[str, str, Growth]] = []
    shoes = {}
    for side in SIDES:
        names = {f.name for f in fields_at(side)}
        d = ctx.table(data.get(side, {}), f"defects.{side}", names)
        shoes[side] = _location_values(ctx, d, side, growth)
    for kind in kinds_at(SIDES[0]):
        if not kind.tied:
            continue
        key = kind.scenario_key
        for side, other in (("left", "right"), ("right", "left")):
            if key in shoes[side] and key not in shoes[other]:
                shoes[other][key] = 2.0 * kind.healthy_value - shoes[side][key]
    built = {}
    for side in SIDES:  # each shoe's own checks name the shoe's table
        try:
            built[side] = ShoeDefect(**shoes[side])
        except BrakeSimError as exc:
            raise ScenarioError(f"{ctx.source}: [defects.{side}]: {exc}") from exc
    drum = _drum(ctx, data.get("drum", {}), growth)
    try:
        return Defects(**built, drum=drum, growth=tuple(growth))
    except BrakeSimError as exc:
        raise ScenarioError(f"{ctx.source}: [defects]: {exc}") from exc


def _number_table(
    ctx: _Ctx,
    data: Any,
    table: str,
    limits: tuple[tuple[str, float, float], ...],
    open_low: set[str],
) -> dict[str, float]:
    """A table of optional numbers, each within its (name, low, high) limits (``open_low``:
    the names whose low limit is excluded); only the keys given."""
    data = ctx.table(data, table, {name for name, _lo, _hi in limits})
    return {
        name: ctx.number(data[name], f"{table}.{name}", lo, hi, lo_open=name in open_low)
        for name, lo, hi in limits
        if name in data
    }


def _vehicle(ctx: _Ctx, data: Any) -> Vehicle:
    """``[vehicle]``: road load and grade on the flywheel (model/vehicle.py), every key
    optional (the defaults there)."""
    return Vehicle(
        **_number_table(ctx, data, "vehicle", VEHICLE_LIMITS, {"wheel_radius_m", "mass_share"})
    )


def _thermal(ctx: _Ctx, data: Any) -> Thermal:
    """``[thermal]``: the brake's temperature as a state (model/thermal.py), every key
    optional (the defaults there)."""
    return Thermal(**_number_table(ctx, data, "thermal", THERMAL_LIMITS, {"heat_capacity_j_k"}))


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


def _segment(ctx: _Ctx, data: Any, key: str) -> Segment:
    if not isinstance(data, dict):
        raise ctx.fail(key, data, "a table with a 'kind'")
    kind = ctx.string(data.get("kind"), f"{key}.kind", tuple(_SEGMENT_KEYS))
    allowed, needed = _SEGMENT_KEYS[kind]
    data = ctx.table(data, key, {"kind", *allowed})
    for name in sorted(needed - set(data)):
        raise ctx.fail(f"{key}.{name}", _MISSING, f"a number for a {kind} segment")
    if kind == "brake" and not {"pressure_bar", "force_n"} & set(data):
        raise ctx.fail(f"{key}.pressure_bar", _MISSING, "pressure_bar or force_n for a brake")
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


def _load_factor(ctx: _Ctx, value: Any, key: str) -> tuple[float, float]:
    """A hold's ``load_factor``: a number, or ``[low, high]`` drawn per stop."""
    lo, hi = LOAD_FACTOR_RANGE
    allowed = f"a number or an array [low, high] with {lo:g} <= low <= high <= {hi:g}"
    if isinstance(value, list):
        return _range(ctx, value, key, (lo, hi), allowed)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ctx.fail(key, value, allowed)
    factor = ctx.number(value, key, lo, hi)
    return factor, factor


def _cycle(ctx: _Ctx, data: Any) -> Cycle:
    """``[cycle]``: the controller's settings and ``[[cycle.segments]]`` (model/cycle.py)."""
    data = ctx.table(data, "cycle", {"segments", "repeat", *CYCLE_LIMITS})
    segments = data.get("segments", _MISSING)
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


def _brake(ctx: _Ctx, top: dict[str, Any]) -> BrakeParameters:
    """The top-level key ``brake`` (default "study"): the brake whose default parameters
    the scenario's ``[parameters]`` override (``BrakeParameters.of_brake``). The fidelity
    levels below the full model represent the study brake only, so the service brake
    refuses a ``[needs]`` table."""
    name = ctx.string(top.get("brake", DEFAULT_BRAKE), "brake", BRAKES)
    if name == "service" and "needs" in top:
        raise ctx.fail(
            "needs",
            top["needs"],
            'no [needs] with brake = "service" (the reduced fidelity levels model the study'
            " brake's shoes, without return springs and rest stops: the service brake runs"
            " the full model)",
        )
    return BrakeParameters.of_brake(name)


def _parameters(ctx: _Ctx, data: Any, base: BrakeParameters) -> BrakeParameters:
    data = ctx.table(data, "parameters", set(PARAMETER_GROUPS))
    overrides: dict[str, dict[str, float]] = {}
    for group, values in data.items():
        cls = PARAMETER_GROUPS[group]
        names = {f.name for f in dataclasses.fields(cls)}
        values = ctx.table(values, f"parameters.{group}", names)
        overrides[group] = {k: ctx.number(v, f"parameters.{group}.{k}") for k, v in values.items()}
    try:
        return base.with_overrides(overrides)
    except BrakeSimError as exc:
        raise ScenarioError(f"{ctx.source}: [parameters]: {exc}") from exc


def _conditions(ctx: _Ctx, data: Any) -> tuple[tuple[str, float, float], ...]:
    """``[conditions]``: per condition a range ``[low, high]`` drawn per run."""
    data = ctx.table(data, "conditions", set(operating.CONDITION_BY_NAME))
    out = []
    for c in operating.CONDITIONS:
        if c.name not in data:
            continue
        key, value = f"conditions.{c.name}", data[c.name]
        unit = "(dimensionless)" if c.unit == "1" else c.unit
        allowed = f"an array [low, high] with {c.low:g} <= low <= high <= {c.high:g} {unit}"
        out.append((c.name, *_range(ctx, value, key, (c.low, c.high), allowed)))
    return tuple(out)


def _range(
    ctx: _Ctx, value: Any, key: str, limits: tuple[float, float], allowed: str
) -> tuple[float, float]:
    """``[low, high]``, two numbers within ``limits`` with low <= high (``allowed``: what
    the one-line error says is allowed)."""
    if not isinstance(value, list) or len(value) != 2:
        raise ctx.fail(key, value, allowed)
    low, high = (ctx.number(v, f"{key}[{i}]", *limits) for i, v in enumerate(value))
    if low > high:
        raise ctx.fail(key, value, allowed)
    return low, high


def _options(ctx: _Ctx, data: Any) -> ModelOptions:
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


def _solver(ctx: _Ctx, data: Any) -> SolverSettings:
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


def _needs(ctx: _Ctx, data: Any, model_shoes: tuple[str, ...]) -> Needs:
    data = ctx.table(data, "needs", {"outputs", "shoes", "accuracy", "level"})
    if "outputs" not in data:
        raise ctx.fail("needs.outputs", _MISSING, f"a list of outputs from {list(OUTPUTS)}")
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


def _name(ctx: _Ctx, value: Any) -> str:
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


def _unit_id(ctx: _Ctx, value: Any) -> str:
    """A brake unit's id (:mod:`brake_sim_ros.identifiers`)."""
    if not is_identifier(value):
        raise ctx.fail("unit_id", value, IDENTIFIER_RULE)
    return value


def _parse(data: dict[str, Any], text: str, source: str) -> Scenario:
    ctx = _Ctx(source)
    top = ctx.table(
        data,
        "",
        {
            "name",
            "description",
            "brake",
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
        },
    )
    if "name" not in top:
        raise ctx.fail("name", _MISSING, "a scenario name (string); it is required")
    name = _name(ctx, top["name"])
    seed, fleet_seed = top.get("seed", 0), top.get("fleet_seed", 0)
    for key, value in (("seed", seed), ("fleet_seed", fleet_seed)):
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < 2**63:
            raise ctx.fail(key, value, "an integer from 0 to 2^63 - 1")
    params = _parameters(ctx, top.get("parameters", {}), _brake(ctx, top))
    defects = _defects(ctx, top.get("defects", {}))
    cycle = _cycle(ctx, top["cycle"]) if "cycle" in top else None
    if cycle is not None and "actuation" in top:
        raise ctx.fail(
            "actuation", top["actuation"], "no [actuation] with a [cycle] (the cycle brakes)"
        )
    vehicle = _vehicle(ctx, top.get("vehicle", {})) if "vehicle" in top or cycle else None
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
        actuation=_actuation(ctx, top.get("actuation", {})),
        options=_options(ctx, top.get("model", {})),
        vehicle=vehicle,
        cycle=cycle,
        thermal=_thermal(ctx, top["thermal"]) if "thermal" in top else None,
    )
    if cycle is not None:
        _check_cycle_setup(ctx, top, setup)
    needs = _needs(ctx, top["needs"], setup.options.shoes) if "needs" in top else None
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
        unit_id=_unit_id(ctx, top.get("unit_id", NOMINAL_UNIT)),
        fleet_seed=fleet_seed,
        solver=_solver(ctx, top.get("solver", {})),
        sample_rate_hz=ctx.number(
            top.get("sample_rate_hz", DEFAULT_SAMPLE_RATE_HZ),
            "sample_rate_hz",
            *SAMPLE_RATE_RANGE_HZ,
        ),
        source=source,
        text=text,
        needs=needs,
        sensors=parse_sensors(ctx, top.get("structure"), top.get("sensors")),
        condition_ranges=_conditions(ctx, top.get("conditions", {})),
    )
    return scenario.with_unit()  # the file's values are the drawing; the unit scatters them


def _check_cycle_setup(ctx: _Ctx, top: dict[str, Any], setup: BrakeSetup) -> None:
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


def _describe(path: str | os.PathLike[str]) -> str:
    """A path for a message: as given when printable and short, else its repr, cut."""
    text = os.fspath(path)
    if isinstance(text, bytes):
        text = os.fsdecode(text)
    shown = text if text.isprintable() else repr(text)
    return shown if len(shown) <= 300 else f"{shown[:150]}...{shown[-100:]}"


_FILE_TYPES = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


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
    name = _describe(path)
    return parse_scenario(read_scenario_text(path), name)


def read_scenario_text(path: str | os.PathLike[str], *, follow_symlinks: bool = True) -> str:
    """The text of a scenario file, read as hostile input: the file-level limits of
    :func:`read_scenario_file` (a regular file that is never waited on, at most
    :data:`MAX_SCENARIO_BYTES`, UTF-8 without NUL characters), checked on the open file.

    Args:
        follow_symlinks: False refuses a final symbolic link (O_NOFOLLOW): for paths
            resolved and checked before opening, so a link swapped in later is not followed.

    Raises:
        ScenarioError: one line naming the file and the rule; never the file's content.
    """
    name = _describe(path)
    try:
        # O_NONBLOCK: opening a FIFO does not wait for a writer; it is refused below
        flags = os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC
        if not follow_symlinks:
            flags |= getattr(os, "O_NOFOLLOW", 0)
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise ScenarioError(f"{name}: cannot read the scenario file: no such file") from None
    except OSError as exc:
        raise ScenarioError(
            f"{name}: cannot read the scenario file: {exc.strerror or exc}"
        ) from None
    except (ValueError, TypeError):  # a NUL byte in the path, not a path at all
        raise ScenarioError(f"{name}: cannot read the scenario file: not a valid path") from None
    try:
        info = os.fstat(fd)
        for test, what in _FILE_TYPES:
            if test(info.st_mode):
                raise ScenarioError(
                    f"{name}: cannot read the scenario file: it is {what}; allowed a regular file"
                )
        if not stat.S_ISREG(info.st_mode):
            raise ScenarioError(
                f"{name}: cannot read the scenario file: not a regular file; allowed one"
            )
        too_big = ScenarioError(
            f"{name}: the scenario file is larger than {MAX_SCENARIO_BYTES} bytes (1 MiB):"
            " allowed at most that"
        )
        if info.st_size > MAX_SCENARIO_BYTES:
            raise too_big
        chunks, size = [], 0
        while size <= MAX_SCENARIO_BYTES:  # the file may grow after fstat
            chunk = os.read(fd, MAX_SCENARIO_BYTES + 1 - size)
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        if size > MAX_SCENARIO_BYTES:
            raise too_big
    except OSError as exc:
        raise ScenarioError(
            f"{name}: cannot read the scenario file: {exc.strerror or exc}"
        ) from None
    finally:
        os.close(fd)
    data = b"".join(chunks)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        column = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        raise ScenarioError(
            f"{name}: not UTF-8 text (a byte that is not UTF-8 at line {line}, column"
            f" {column}): allowed a UTF-8 TOML file"
        ) from None
    if "\x00" in text:
        raise ScenarioError(f"{name}: contains NUL characters: allowed a UTF-8 TOML file")
    return text.removeprefix("\ufeff")


def _is_path(name_or_path: str | os.PathLike[str]) -> bool:
    """Whether ``load_scenario`` reads a file: a Path, a name ending in .toml, or a name an
    existing file or directory has (so that it is refused as one, not as a name)."""
    if not isinstance(name_or_path, str):
        return True
    if name_or_path.endswith(".toml") or "/" in name_or_path or os.sep in name_or_path:
        return True
    try:
        return os.path.lexists(name_or_path)
    except (OSError, ValueError):
        return False


def load_scenario(name_or_path: str | os.PathLike[str]) -> Scenario:
    """Load a built-in scenario by name, or a scenario file by path
    (:func:`read_scenario_file`, with its limits).

    Raises:
        ScenarioError: an unknown name, or a file that cannot be read or parsed (one line).
    """
    if _is_path(name_or_path):
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
