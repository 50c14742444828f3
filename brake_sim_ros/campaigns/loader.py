"""Campaign files (TOML): strict loading into a :class:`~.campaign.Campaign` (whose runs
:mod:`.campaign` plans).

A campaign names a base scenario (a built-in name, or a path relative to the campaign
file), the brake its runs run on (``brake``: "study" or "service", set on the base
scenario; without it, the base's own), the axes it varies (:mod:`.axes`), how many units,
what each run outputs and the split rule (:mod:`.splits`). Loading is strict like a
scenario's: an unknown key, a wrong type or an out-of-range value is one line naming the
file and the key. Every varied scenario is written as TOML text and read again by the
scenario loader, so each field's rule is the scenario loader's and is written once; a
varied scenario it refuses refuses the campaign, naming the run.

See ``builtin/demo.toml`` for a commented example.
"""

from __future__ import annotations

import math
import os
import re
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from brake_sim_ros.campaigns.axes import (
    DEFECT_AXIS,
    DEFECT_COLUMNS,
    DEFECT_NUMBER_COLUMNS,
    DRAW_METHODS,
    AnyAxis,
    Axis,
    DefectAxis,
    Value,
    condition_points,
    defect_choices,
    point_columns,
)
from brake_sim_ros.campaigns.campaign import Campaign, CampaignError, Outputs
from brake_sim_ros.campaigns.splits import (
    SPLITS,
    HeldOut,
    held_out_kind_problem,
    idle_rule,
    unit_counts,
    value_kind,
)
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.model.catalogue import KIND_BY_NAME, brake_kinds
from brake_sim_ros.model.parameters import BRAKES
from brake_sim_ros.scenarios.checker import MISSING, Checker, show_value
from brake_sim_ros.scenarios.files import MAX_SCENARIO_BYTES, is_path, read_scenario_text
from brake_sim_ros.scenarios.loader import (
    BUILTIN_PACKAGE,
    builtin_names,
    parse_scenario,
    parse_toml,
)
from brake_sim_ros.scenarios.toml_text import dumps

CAMPAIGN_PACKAGE = "brake_sim_ros.campaigns.builtin"
MAX_RUNS = 100_000  # runs of one campaign (a manifest row and a file each)
MAX_UNITS = 10_000
DEFAULT_UNITS = 3  # the fewest that fill the default train/validation/test split
MAX_AXIS_VALUES = 10_000
_COLUMN = re.compile(r"[a-z][a-z0-9_]{0,63}")
_KEY_PART = re.compile(r"[A-Za-z0-9_]{1,64}")
# scenario keys no axis sets: the campaign sets them (name, unit) or they are text
_NOT_VARIED = ("name", "unit_id", "description")
# manifest columns of every run: an axis may not take one of these names
RESERVED_COLUMNS = (
    "run_id",
    "unit_id",
    "seed",
    "split",
    "status",
    "error",
    "cost_cpu_s",
    "file",
    "sha256",
    "rows",
    *DEFECT_COLUMNS,
)


# --- reading -------------------------------------------------------------------------------
def builtin_campaigns() -> list[str]:
    files = resources.files(CAMPAIGN_PACKAGE).iterdir()
    return sorted(f.name[:-5] for f in files if f.name.endswith(".toml"))


def load_campaign(name_or_path: str | os.PathLike[str]) -> Campaign:
    """A built-in campaign by name, or a campaign file by path (read as hostile input with
    the scenario files' limits: a regular file, at most 1 MiB of UTF-8 TOML).

    Raises:
        CampaignError: one line naming the file and the key.
    """
    text_path = os.fspath(name_or_path)
    # a built-in's name is the built-in, even beside a file or directory of that name
    # (give ./NAME for the file)
    names_a_file = is_path(name_or_path) and not (
        isinstance(name_or_path, str) and name_or_path in builtin_campaigns()
    )
    try:
        if names_a_file:
            text = read_scenario_text(name_or_path)
            return parse_campaign(text, text_path, directory=Path(text_path).parent)
        if text_path not in builtin_campaigns():
            raise CampaignError(
                f"unknown campaign {show_value(text_path) if text_path else repr('')}: allowed"
                f" a path to a .toml file or one of the built-in campaigns {builtin_campaigns()}"
            )
        text = resources.files(CAMPAIGN_PACKAGE).joinpath(f"{text_path}.toml").read_text("utf-8")
        return parse_campaign(text, f"<built-in campaign {text_path}>", directory=None)
    except CampaignError:
        raise
    except BrakeSimError as exc:
        message = str(exc).replace("scenario file", "campaign file")
        raise CampaignError(message) from None


def _base_text(ctx: Checker, base: Any, directory: Path | None) -> str:
    """The base scenario's TOML text: a built-in name, or a path (relative to the
    campaign file's directory)."""
    if not isinstance(base, str) or not base:
        raise ctx.fail("base", base, f"a built-in scenario {builtin_names()} or a .toml path")
    if base in builtin_names() and not base.endswith(".toml"):
        return resources.files(BUILTIN_PACKAGE).joinpath(f"{base}.toml").read_text("utf-8")
    if not base.endswith(".toml"):
        raise ctx.fail("base", base, f"a built-in scenario {builtin_names()} or a .toml path")
    if directory is None:
        raise ctx.fail("base", base, f"a built-in scenario {builtin_names()} (a built-in campaign)")
    path = Path(base) if os.path.isabs(base) else directory / base
    try:
        return read_scenario_text(path)
    except BrakeSimError as exc:
        raise CampaignError(f"{ctx.source}: key 'base': {exc}") from None


def parse_campaign(text: str, source: str, directory: Path | None = None) -> Campaign:
    """Parse campaign TOML ``text`` (errors name ``source``); ``directory`` is where a
    relative base path is found (None: only built-in bases).

    Raises:
        CampaignError: anything wrong, in one line.
    """
    if len(text) > MAX_SCENARIO_BYTES:
        raise CampaignError(f"{source}: {len(text)} characters: allowed at most 1 MiB")
    try:
        data = parse_toml(text, source)
        return _parse(data, text, source, directory)
    except CampaignError:
        raise
    except BrakeSimError as exc:
        raise CampaignError(str(exc)) from None


def _parse(data: dict[str, Any], text: str, source: str, directory: Path | None) -> Campaign:
    ctx = Checker(source)
    keys = {"name", "description", "base", "brake", "seed", "units", "unit_ids", "outputs"}
    top = ctx.table(data, "", keys | {"axes", "draws", "split"})
    if "name" not in top:
        raise ctx.fail("name", MISSING, "a campaign name; it is required")
    name = top["name"]
    ctx.identifier(name, "name")
    if "base" not in top:
        raise ctx.fail("base", MISSING, "a base scenario (built-in name or .toml path)")
    base_text = _base_text(ctx, top["base"], directory)
    base_data = parse_toml(base_text, f"{source}: base {top['base']}")
    _set_brake(ctx, top, base_data)
    # refused here, not per run (a base that does not hold on the campaign's brake too)
    base = parse_scenario(dumps(base_data), f"{source}: base scenario")
    circuit = base.setup.params.service is not None  # the line's kinds need its circuit
    seed = ctx.integer(top.get("seed", 0), "seed", 0, 2**63 - 1)
    unit_ids = _units(ctx, top)
    outputs = _outputs(ctx, top.get("outputs", {}))
    axes = _axes(ctx, top.get("axes", []), circuit)
    method, count = _draws(ctx, top.get("draws"), axes)
    fractions, held_out = _split(ctx, top.get("split", {}), axes)
    try:
        unit_counts(len(unit_ids), fractions)
    except ValueError as exc:
        key = "unit_ids" if "unit_ids" in top else "units"
        raise CampaignError(f"{source}: key '{key}': {exc}") from None
    campaign = Campaign(
        name=name,
        description=ctx.string(top.get("description", ""), "description"),
        source=source,
        text=text,
        base=top["base"],
        base_text=base_text,
        brake=base.setup.params.brake,
        seed=seed,
        unit_ids=unit_ids,
        outputs=outputs,
        axes=axes,
        draw_method=method,
        draw_count=count,
        fractions=fractions,
        held_out=held_out,
        base_data=base_data,
    )
    n_points = math.prod(
        len(a.choices) if isinstance(a, DefectAxis) else len(a.values) or 1 for a in axes
    ) * (count if any(isinstance(a, Axis) and a.uniform for a in axes) else 1)
    if n_points * len(unit_ids) > MAX_RUNS:
        raise ctx.fail(
            "axes",
            top.get("axes", []),
            f"at most {MAX_RUNS} runs (units x conditions); this campaign has"
            f" {len(unit_ids)} x {n_points}",
        )
    _refuse_idle_rules(ctx, campaign)
    return campaign


def _refuse_idle_rules(ctx: Checker, campaign: Campaign) -> None:
    """Refuse a held-out rule that matches no condition of the campaign (it would hold
    nothing out), or rules that together match every condition (nothing left to train on),
    in one line."""
    if campaign.held_out:
        points = condition_points(
            campaign.axes, campaign.draw_method, campaign.draw_count, campaign.seed
        )
        rows = [point_columns(p) for p in points]
        problem = idle_rule(rows, campaign.held_out)
        if problem is not None:
            raise CampaignError(f"{ctx.source}: key 'split.held_out[{problem[0]}]': {problem[1]}")
        if all(any(rule.matches(row) for rule in campaign.held_out) for row in rows):
            raise CampaignError(
                f"{ctx.source}: key 'split.held_out': holds out every condition, so train and"
                " validation would be empty; allowed rules that leave some conditions to train on"
            )


def _set_brake(ctx: Checker, top: dict[str, Any], base_data: dict[str, Any]) -> None:
    """Set the campaign's ``brake`` (when given; else the base scenario's own stands) on the
    base scenario's data, which every run is varied from. An axis may not vary the brake
    beside it (one of the two would be ignored)."""
    if "brake" not in top:
        return
    brake = ctx.string(top["brake"], "brake", BRAKES)
    axes = top.get("axes", [])
    for i, axis in enumerate(axes if isinstance(axes, list) else []):
        if isinstance(axis, dict) and axis.get("key") == "brake":
            raise ctx.fail(
                f"axes[{i}].key",
                "brake",
                "a key other than 'brake' when the campaign sets its brake (drop one of them)",
            )
    base_data["brake"] = brake


def _units(ctx: Checker, top: dict[str, Any]) -> tuple[str, ...]:
    if "units" in top and "unit_ids" in top:
        raise ctx.fail(
            "unit_ids", top["unit_ids"], "either 'units' (a count) or 'unit_ids', not both"
        )
    if "unit_ids" in top:
        ids = top["unit_ids"]
        if not isinstance(ids, list) or not 0 < len(ids) <= MAX_UNITS:
            raise ctx.fail("unit_ids", ids, f"an array of 1 to {MAX_UNITS} unit ids")
        for i, unit in enumerate(ids):
            ctx.identifier(unit, f"unit_ids[{i}]")
        if len(set(ids)) != len(ids):
            raise ctx.fail("unit_ids", ids, "distinct unit ids")
        return tuple(ids)
    n = ctx.integer(top.get("units", DEFAULT_UNITS), "units", 1, MAX_UNITS)
    return tuple(f"unit-{i:04d}" for i in range(n))


def _outputs(ctx: Checker, data: Any) -> Outputs:
    data = ctx.table(data, "outputs", {"duration_s", "sample_rate_hz", "columns"})
    duration = data.get("duration_s")
    if duration is not None:
        duration = ctx.number(duration, "outputs.duration_s", 0.0, 3600.0, lo_open=True)
    rate = data.get("sample_rate_hz")
    if rate is not None:
        rate = ctx.number(rate, "outputs.sample_rate_hz", 1.0, 1e6)
    columns = data.get("columns", [])
    if "columns" in data and columns == []:  # left out means every column; [] means none
        raise ctx.fail("outputs.columns", columns, "1 or more column names (leave it out: all)")
    if (
        not isinstance(columns, list)
        or len(columns) > 1000
        or any(not isinstance(c, str) or not 0 < len(c) <= 200 for c in columns)
        or len(set(columns)) != len(columns)
    ):
        raise ctx.fail("outputs.columns", columns, "an array of distinct column names")
    return Outputs(duration, rate, tuple(columns))


def _values(ctx: Checker, values: Any, key: str) -> tuple[Value, ...]:
    if not isinstance(values, list) or not 0 < len(values) <= MAX_AXIS_VALUES:
        raise ctx.fail(key, values, f"an array of 1 to {MAX_AXIS_VALUES} values")
    kinds = set()
    for i, v in enumerate(values):
        if isinstance(v, bool):
            kinds.add("bool")
        elif isinstance(v, int | float):
            if isinstance(v, float) and not math.isfinite(v):
                raise ctx.fail(f"{key}[{i}]", v, "a finite number")
            kinds.add("number")
        elif isinstance(v, str):
            kinds.add("string")
        else:
            raise ctx.fail(f"{key}[{i}]", v, "a number, string or boolean")
    if len(kinds) > 1:
        raise ctx.fail(key, values, "values of one type (numbers, strings or booleans)")
    if len(set(values)) != len(values):
        raise ctx.fail(key, values, "distinct values")
    return tuple(values)


def _axes(ctx: Checker, data: Any, circuit: bool) -> tuple[AnyAxis, ...]:
    if not isinstance(data, list) or len(data) > 32:
        raise ctx.fail("axes", data, "an array of at most 32 [[axes]] tables")
    axes: list[AnyAxis] = []
    for i, item in enumerate(data):
        where = f"axes[{i}]"
        if isinstance(item, dict) and "defects" in item:
            axes.append(_defect_axis(ctx, item, where, circuit))
            continue
        item = ctx.table(item, where, {"name", "key", "values", "linspace", "uniform"})
        key = item.get("key")
        parts = key.split(".") if isinstance(key, str) else []
        if not parts or len(parts) > 8 or not all(_KEY_PART.fullmatch(p) for p in parts):
            raise ctx.fail(
                f"{where}.key",
                MISSING if key is None else key,
                "a dotted scenario key, e.g. 'actuation.peak_force_n'",
            )
        if parts[0] in _NOT_VARIED or parts[0] == "defects":
            raise ctx.fail(
                f"{where}.key",
                key,
                "a scenario key other than name, unit_id (set by 'units') and description;"
                " defects through an axis with 'defects'",
            )
        name = item.get("name", key.replace(".", "_"))
        if not isinstance(name, str) or not _COLUMN.fullmatch(name) or name in RESERVED_COLUMNS:
            raise ctx.fail(
                f"{where}.name",
                name,
                "a column name of a-z 0-9 _ (starting with a letter), not one of"
                f" {list(RESERVED_COLUMNS)}",
            )
        given = [k for k in ("values", "linspace", "uniform") if k in item]
        if len(given) != 1:
            raise ctx.fail(where, item, "exactly one of 'values', 'linspace', 'uniform'")
        if "values" in item:
            axes.append(Axis(name, key, values=_values(ctx, item["values"], f"{where}.values")))
        elif "linspace" in item:
            axes.append(
                Axis(name, key, values=_linspace(ctx, item["linspace"], f"{where}.linspace"))
            )
        else:
            lohi = item["uniform"]
            if not isinstance(lohi, list) or len(lohi) != 2:
                raise ctx.fail(f"{where}.uniform", lohi, "[low, high]")
            lo = ctx.number(lohi[0], f"{where}.uniform[0]")
            hi = ctx.number(lohi[1], f"{where}.uniform[1]", lo, math.inf, lo_open=True)
            axes.append(Axis(name, key, uniform=(lo, hi)))
    names = [a.name for a in axes]
    if len(set(names)) != len(names):
        raise ctx.fail("axes", data, "axes of distinct names (and at most one defect axis)")
    keys = [a.key for a in axes if isinstance(a, Axis)]
    if len(set(keys)) != len(keys):
        raise ctx.fail("axes", data, "axes of distinct keys")
    return tuple(axes)


def _linspace(ctx: Checker, value: Any, key: str) -> tuple[Value, ...]:
    if not isinstance(value, list) or len(value) != 3:
        raise ctx.fail(key, value, "[start, stop, num]: num evenly spaced values, both ends in")
    start = ctx.number(value[0], f"{key}[0]")
    stop = ctx.number(value[1], f"{key}[1]")
    num = ctx.integer(value[2], f"{key}[2]", 2, MAX_AXIS_VALUES)
    values = tuple(float(v) for v in np.linspace(start, stop, num))
    if len(set(values)) != len(values):
        raise ctx.fail(key, value, "distinct values (start differs from stop)")
    return values


def _defect_axis(ctx: Checker, item: dict[str, Any], where: str, circuit: bool) -> DefectAxis:
    """A defect axis: ``defects`` "all" (every kind the base's brake carries: the line's
    kinds only with its hydraulic circuit, the service brake's) or a list of them."""
    item = ctx.table(item, where, {"name", "defects", "severities", "healthy"})
    if item.get("name", DEFECT_AXIS) != DEFECT_AXIS:
        raise ctx.fail(f"{where}.name", item["name"], f"'{DEFECT_AXIS}' for the defect axis")
    kinds = item["defects"]
    allowed = [k.name for k in brake_kinds(circuit)]
    if kinds == "all":
        kinds = allowed
    if (
        not isinstance(kinds, list)
        or not kinds
        or any(not isinstance(k, str) or k not in allowed for k in kinds)
        or len(set(kinds)) != len(kinds)
    ):
        why = (
            ""
            if circuit
            else ' (the base is the study brake: the line\'s kinds need brake = "service")'
        )
        raise ctx.fail(f"{where}.defects", kinds, f'"all" or distinct kinds from {allowed}{why}')
    fractions = item.get("severities", [1.0])
    if not isinstance(fractions, list) or not 0 < len(fractions) <= 100:
        raise ctx.fail(
            f"{where}.severities", fractions, "an array of fractions of each kind's service limit"
        )
    values = tuple(
        ctx.number(f, f"{where}.severities[{i}]", 0.0, 10.0, lo_open=True)
        for i, f in enumerate(fractions)
    )
    if len(set(values)) != len(values):
        raise ctx.fail(f"{where}.severities", fractions, "distinct fractions")
    healthy = item.get("healthy", True)
    if not isinstance(healthy, bool) and not (isinstance(healthy, int) and 0 <= healthy <= 1000):
        raise ctx.fail(f"{where}.healthy", healthy, "true, false or a count of healthy runs 0-1000")
    choices = defect_choices(tuple(kinds), values, healthy)
    for c in choices:  # a fraction beyond a kind's range: refused here, naming it
        if c.kind in KIND_BY_NAME:
            try:
                KIND_BY_NAME[c.kind].check(c.severity, f"{c.location} ")
            except BrakeSimError as exc:
                raise CampaignError(f"{ctx.source}: key '{where}.severities': {exc}") from None
    return DefectAxis(choices)


def _draws(ctx: Checker, data: Any, axes: tuple[AnyAxis, ...]) -> tuple[str, int]:
    drawn = any(isinstance(a, Axis) and a.uniform is not None for a in axes)
    if data is None:
        if drawn:
            raise ctx.fail("draws", MISSING, "a [draws] table (method, n) for the 'uniform' axes")
        return "lhs", 0
    data = ctx.table(data, "draws", {"method", "n"})
    if not drawn:
        raise ctx.fail("draws", data, "no [draws] table without an axis of 'uniform' values")
    method = ctx.string(data.get("method", "lhs"), "draws.method", DRAW_METHODS)
    if "n" not in data:
        raise ctx.fail("draws.n", MISSING, "the number of drawn points")
    return method, ctx.integer(data["n"], "draws.n", 1, MAX_RUNS)


def _split(
    ctx: Checker, data: Any, axes: tuple[AnyAxis, ...]
) -> tuple[dict[str, float], tuple[HeldOut, ...]]:
    data = ctx.table(data, "split", {*SPLITS, "held_out"})
    fractions = {s: ctx.number(data.get(s, 0.0), f"split.{s}", 0.0, 1.0) for s in SPLITS}
    if not data.keys() & set(SPLITS):
        fractions = {"train": 0.6, "validation": 0.2, "test": 0.2}
    if abs(sum(fractions.values()) - 1.0) > 1e-9:
        raise ctx.fail("split", data, "train + validation + test fractions summing to 1")
    columns: set[str] = set()
    types: dict[str, set[str]] = {}  # a column's value kinds: "number", "string", "bool"
    for a in axes:
        if isinstance(a, DefectAxis):
            columns |= set(DEFECT_COLUMNS)
            for c in DEFECT_COLUMNS:
                types[c] = {"number"} if c in DEFECT_NUMBER_COLUMNS else {"string"}
        else:
            columns.add(a.name)
            kinds = {"number"} if a.uniform is not None else {value_kind(v) for v in a.values}
            types.setdefault(a.name, set()).update(kinds)
    rules = data.get("held_out", [])
    if not isinstance(rules, list) or len(rules) > 32:
        raise ctx.fail(
            "split.held_out", rules, "an array of at most 32 tables {column, values | min, max}"
        )
    held = []
    for i, rule in enumerate(rules):
        where = f"split.held_out[{i}]"
        rule = ctx.table(rule, where, {"column", "values", "min", "max"})
        column = rule.get("column")
        if column not in columns:
            raise ctx.fail(
                f"{where}.column",
                MISSING if column is None else column,
                f"a varied column, one of {sorted(columns)}",
            )
        values = _values(ctx, rule["values"], f"{where}.values") if "values" in rule else ()
        lo = ctx.number(rule["min"], f"{where}.min") if "min" in rule else None
        hi = ctx.number(rule["max"], f"{where}.max") if "max" in rule else None
        if not values and lo is None and hi is None:
            raise ctx.fail(where, rule, "'values', or a range 'min'/'max'")
        if lo is not None and hi is not None and lo > hi:
            raise ctx.fail(f"{where}.max", hi, f"a maximum >= the minimum {lo:g}")
        problem = held_out_kind_problem(values, lo is not None or hi is not None, types[column])
        if problem is not None:
            key, value, allowed = problem
            raise ctx.fail(f"{where}{key}", value, allowed)
        held.append(HeldOut(column, values, lo, hi))
    if held and fractions["test"] == 0.0:
        raise ctx.fail("split.test", 0.0, "a test fraction > 0 when values are held out")
    return fractions, tuple(held)
