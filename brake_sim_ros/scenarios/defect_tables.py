"""A scenario's ``[defects]`` tables, loaded strictly: each shoe's catalogue fields
(``[defects.left]``, ``[defects.right]``), the drum's (``[defects.drum]`` and its
harmonics), the hydraulic line's (``[defects.line]``, the service brake's circuit), and
how each defect grows (a key's table ``{value, onset_s, growth, ...}``).

The fields, their growth laws and limits are the catalogue's
(:mod:`brake_sim_ros.model.catalogue`); the values are checked by the model's defect
classes, whose messages are given the table's name.
"""

from __future__ import annotations

from typing import Any

from brake_sim_ros.errors import BrakeSimError, ScenarioError
from brake_sim_ros.model.assembly import SIDES
from brake_sim_ros.model.catalogue import (
    DRUM_KIND,
    GROWTH_KEYS,
    GROWTH_LAWS,
    LAW_PARAMETERS,
    LINE,
    MAX_GROWTH_TIME_S,
    DefectKind,
    Growth,
    fields_at,
    kinds_at,
)
from brake_sim_ros.model.defects import (
    MAX_DRUM_HARMONICS,
    MAX_DRUM_ORDER,
    Defects,
    DrumDefect,
    DrumHarmonic,
    LineDefect,
    ShoeDefect,
)
from brake_sim_ros.scenarios.checker import MISSING, Checker


def _growth(ctx: Checker, data: dict[str, Any], key: str, healthy: float) -> Growth:
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
            raise ctx.fail(f"{key}.{name}", MISSING, f'a number with growth = "{law}"')
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
    ctx: Checker, value: Any, key: str, kind: DefectKind
) -> tuple[float, Growth | None]:
    """A defect key's value: a number (the final value, present from the start), or a
    table ``{value, onset_s, growth, ...}`` (:data:`.catalogue.GROWTH_KEYS`): the final
    value and its growth."""
    growth = None
    if isinstance(value, dict):
        value = ctx.table(value, key, {"value", *GROWTH_KEYS})
        if "value" not in value:
            raise ctx.fail(f"{key}.value", MISSING, "a number (the final value)")
        growth = _growth(ctx, value, key, kind.healthy_value)
        value = value["value"]
    return ctx.number(value, key), growth


def _location_values(
    ctx: Checker, data: dict[str, Any], location: str, growth: list[tuple[str, str, Growth]]
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


def _harmonics(ctx: Checker, rows: Any) -> tuple[DrumHarmonic, ...]:
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
                raise ctx.fail(f"{key}.{name}", MISSING, "a number (order: an integer)")
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


def _drum(ctx: Checker, data: Any, growth: list[tuple[str, str, Growth]]) -> DrumDefect:
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


def _line(ctx: Checker, data: Any, growth: list[tuple[str, str, Growth]]) -> LineDefect:
    """``[defects.line]``: the hydraulic circuit's catalogue fields (``fields_at("line")``,
    e.g. ``air_in_line_ml``), each a number or a growth table as a shoe's keys. Whether the
    brake has a circuit is the loader's check (the study brake refuses them)."""
    d = ctx.table(data, f"defects.{LINE}", {f.name for f in fields_at(LINE)})
    values = _location_values(ctx, d, LINE, growth)
    try:
        return LineDefect(**values)
    except BrakeSimError as exc:
        raise ScenarioError(f"{ctx.source}: [defects.{LINE}]: {exc}") from exc


def parse_defects(ctx: Checker, data: Any) -> Defects:
    """``[defects.left]``, ``[defects.right]``: each key a catalogue field of a shoe
    (``brake-sim defects``): a kind's key is a number (the final value, present from the
    start) or a table ``{value, onset_s, growth, rate_per_s, doubling_time_s, start}``
    (:data:`.catalogue.GROWTH_KEYS`: when it starts and how it grows toward ``value``;
    ``start`` and ``rate_per_s`` in the key's unit, e.g. 0.52 and 0.05 for a share); a
    tied kind's key given for one shoe only implies the other's (the actuation shares sum
    to 1); ``[defects.drum]``: :func:`_drum`; ``[defects.line]``: :func:`_line`."""
    data = ctx.table(data, "defects", {*SIDES, "drum", LINE})
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
    line = _line(ctx, data.get(LINE, {}), growth)
    try:
        return Defects(**built, drum=drum, line=line, growth=tuple(growth))
    except BrakeSimError as exc:
        raise ScenarioError(f"{ctx.source}: [defects]: {exc}") from exc
