"""The scenario's ``[structure]`` and ``[[sensors]]`` tables, loaded strictly.

Absent tables give the defaults (:class:`~brake_sim_ros.sensing.structure.StructureParameters`,
:func:`~brake_sim_ros.sensing.sensors.default_channels`); ``sensors = []`` measures nothing.
An unknown key, a wrong type or a value out of range is an error naming the file, the table
and key, the value and what is allowed, like the rest of the loader (whose checker,
:class:`~.checker.Checker`, this module uses). Example::

    [structure]                        # optional; all modes replace the defaults
    mounts = ["backing_plate", "knuckle"]
    [[structure.modes]]
    direction = "x"                    # x or y, frame brake_backing_plate
    frequency_hz = 1200.0
    damping_ratio = 0.02
    modal_mass_kg = 5.0
    left_pin = 1.0                     # mode-shape value at each pin (participation)
    right_pin = 1.0
    at_mounts = [0.8, 0.4]             # mode-shape value at each mount, in mounts order

    [[sensors]]                        # optional; the list replaces the default set
    name = "plate_x"
    kind = "accelerometer"             # accelerometer, load_pin, line_pressure, wheel_speed
    preset = "adxl1002_class"          # the kind's presets (sensing/sensors.py); then overrides:
    location = "backing_plate"         # a mount, a side, "wheel_cylinder" or "tone_ring"
    axis = "x"
    # rate_hz, sensitivity_ratio, noise_density_per_sqrt_hz, bandwidth_hz, resonance_hz,
    # resonance_damping_ratio, range_min, range_max, adc_bits, antialias_fraction,
    # tone_ring_teeth, piston_diameter_m  (0 for bandwidth_hz, resonance_hz, adc_bits,
    # antialias_fraction: none)
    [[sensors.faults]]                 # faults of the sensor above (sensing/faults.py)
    kind = "bias_drift"
    onset_s = 2.0
    size = 0.5
    duration_s = 1.0                   # optional: to the end
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from brake_sim_ros.errors import BrakeSimError, ScenarioError
from brake_sim_ros.scenarios.checker import Checker
from brake_sim_ros.sensing.faults import FAULT_KINDS, SensorFault
from brake_sim_ros.sensing.kinds import SENSOR_KINDS
from brake_sim_ros.sensing.sensors import (
    SensorChannel,
    SensorSet,
    Transducer,
    default_channels,
)
from brake_sim_ros.sensing.structure import AXES, Mode, StructureParameters

_MODE_KEYS = {f.name for f in dataclasses.fields(Mode)}
# transducer fields a sensor table may override; 0 means "none" for the optional ones
_OPTIONAL = ("bandwidth_hz", "resonance_hz", "adc_bits", "antialias_fraction")
_TRANSDUCER_KEYS = {f.name for f in dataclasses.fields(Transducer)} - {"name"}
_CHANNEL_KEYS = {"name", "kind", "preset", "location", "axis", "rate_hz", "sensitivity_ratio"}
_CHANNEL_KEYS |= {"tone_ring_teeth", "piston_diameter_m", "faults"}
_FAULT_KEYS = {f.name for f in dataclasses.fields(SensorFault)}


def _array(ctx: Checker, value: Any, key: str) -> list[Any]:
    if not isinstance(value, list):
        raise ctx.fail(key, value, "an array")
    return value


def _wrap(ctx: Checker, where: str, exc: BrakeSimError) -> ScenarioError:
    return ScenarioError(f"{ctx.source}: [{where}]: {exc}")


def parse_structure(ctx: Checker, data: Any) -> StructureParameters:
    """``[structure]``: mounts and modes (each optional, defaults otherwise)."""
    if data is None:
        return StructureParameters()
    data = ctx.table(data, "structure", {"mounts", "modes"})
    default = StructureParameters()
    mounts = default.mounts
    if "mounts" in data:
        raw = _array(ctx, data["mounts"], "structure.mounts")
        mounts = tuple(ctx.string(m, f"structure.mounts[{i}]") for i, m in enumerate(raw))
    modes = default.modes
    if "modes" in data:
        modes = []
        for i, raw in enumerate(_array(ctx, data["modes"], "structure.modes")):
            key = f"structure.modes[{i}]"
            raw = ctx.table(raw, key, _MODE_KEYS)
            missing = _MODE_KEYS - set(raw)
            if missing:
                raise ctx.fail(key, raw, f"a table with every key of {sorted(_MODE_KEYS)}")
            shape = _array(ctx, raw["at_mounts"], f"{key}.at_mounts")
            values = {
                k: ctx.number(v, f"{key}.{k}")
                for k, v in raw.items()
                if k not in ("direction", "at_mounts")
            }
            try:
                modes.append(
                    Mode(
                        direction=ctx.string(raw["direction"], f"{key}.direction", AXES),
                        at_mounts=tuple(
                            ctx.number(v, f"{key}.at_mounts[{j}]") for j, v in enumerate(shape)
                        ),
                        **values,
                    )
                )
            except BrakeSimError as exc:
                raise _wrap(ctx, key, exc) from exc
        modes = tuple(modes)
    elif mounts != default.mounts:
        raise ctx.fail("structure.mounts", list(mounts), "the default mounts unless modes are set")
    try:
        return StructureParameters(mounts=mounts, modes=modes)
    except BrakeSimError as exc:
        raise _wrap(ctx, "structure", exc) from exc


def _fault(ctx: Checker, data: Any, key: str) -> SensorFault:
    data = ctx.table(data, key, _FAULT_KEYS)
    if "kind" not in data or "onset_s" not in data:
        raise ctx.fail(key, data, "a table with at least 'kind' and 'onset_s'")
    try:
        return SensorFault(
            kind=ctx.string(data["kind"], f"{key}.kind", FAULT_KINDS),
            onset_s=ctx.number(data["onset_s"], f"{key}.onset_s", 0.0, 86_400.0),
            size=ctx.number(data.get("size", 0.0), f"{key}.size"),
            duration_s=(
                ctx.number(data["duration_s"], f"{key}.duration_s", 0.0, 86_400.0, lo_open=True)
                if "duration_s" in data
                else math.inf
            ),
        )
    except BrakeSimError as exc:
        raise _wrap(ctx, key, exc) from exc


def _channel(ctx: Checker, data: Any, key: str) -> SensorChannel:
    data = ctx.table(data, key, _CHANNEL_KEYS | _TRANSDUCER_KEYS)
    for required in ("name", "kind", "location"):
        if required not in data:
            raise ctx.fail(f"{key}.{required}", None, "a value (required)")
    kind = ctx.string(data["kind"], f"{key}.kind", tuple(SENSOR_KINDS))
    entry = SENSOR_KINDS[kind]
    preset = ctx.string(
        data.get("preset", entry.default_preset), f"{key}.preset", tuple(entry.presets)
    )
    changes: dict[str, Any] = {}
    for name in sorted(_TRANSDUCER_KEYS & set(data)):
        where = f"{key}.{name}"
        if name == "adc_bits":
            bits = ctx.integer(data[name], where, 0, 32)
            changes[name] = bits or None
        else:
            value = ctx.number(data[name], where)
            changes[name] = None if (name in _OPTIONAL and value == 0.0) else value
    fields: dict[str, Any] = {}
    if "rate_hz" in data:
        fields["rate_hz"] = ctx.number(data["rate_hz"], f"{key}.rate_hz", 0.0, 1e6, lo_open=True)
    if "sensitivity_ratio" in data:
        fields["sensitivity_ratio"] = ctx.number(
            data["sensitivity_ratio"], f"{key}.sensitivity_ratio", 0.0, 100.0, lo_open=True
        )
    if "tone_ring_teeth" in data:
        fields["tone_ring_teeth"] = ctx.integer(
            data["tone_ring_teeth"], f"{key}.tone_ring_teeth", 1, 1000
        )
    if "piston_diameter_m" in data:
        fields["piston_diameter_m"] = ctx.number(
            data["piston_diameter_m"], f"{key}.piston_diameter_m", 1e-3, 0.1
        )
    faults = tuple(
        _fault(ctx, f, f"{key}.faults[{i}]")
        for i, f in enumerate(_array(ctx, data.get("faults", []), f"{key}.faults"))
    )
    try:
        transducer = dataclasses.replace(entry.presets[preset], **changes)
        return SensorChannel(
            name=ctx.string(data["name"], f"{key}.name"),
            kind=kind,
            location=ctx.string(data["location"], f"{key}.location"),
            axis=ctx.string(data.get("axis", ""), f"{key}.axis"),
            transducer=transducer,
            faults=faults,
            **fields,
        )
    except BrakeSimError as exc:
        raise _wrap(ctx, key, exc) from exc


def parse_sensors(ctx: Checker, structure: Any, sensors: Any) -> SensorSet:
    """The scenario's sensor set from its ``[structure]`` and ``[[sensors]]`` tables (None
    where the scenario has none)."""
    params = parse_structure(ctx, structure)
    channels = default_channels()
    if sensors is not None:
        raw = _array(ctx, sensors, "sensors")
        channels = tuple(_channel(ctx, c, f"sensors[{i}]") for i, c in enumerate(raw))
    try:
        return SensorSet(structure=params, channels=channels)
    except BrakeSimError as exc:
        raise _wrap(ctx, "sensors", exc) from exc
