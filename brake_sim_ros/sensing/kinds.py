"""Sensor kinds: each channel kind the sensor bank knows, with its model, as a registry.

A :class:`SensorKind` carries what a :class:`.sensors.SensorChannel` of that kind needs
and what :class:`.sensors.SensorBank` computes for it: its unit, where it may sit, whether
it takes an axis, its transducer presets and default, the faults it can carry, the
sample-block columns it reads and its true value from them (its model), and its output
series. The bank dispatches on the entry, so a channel of a kind without an entry is
refused, never computed as another kind. :func:`registered` adds a kind for a block (a
test's).

The built-in kinds and their figures: :mod:`.sensors`.

Pure: numpy only.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.model.service_parameters import WHEEL_CYLINDER_BORE_M
from brake_sim_ros.sensing import faults as sf
from brake_sim_ros.sensing.transducers import (
    IDEAL,
    STANDARD_GRAVITY_M_S2,  # noqa: F401 (re-exported)
    Transducer,
    accel,
)


class Channel(Protocol):
    """What a kind's model reads of its channel (:class:`.sensors.SensorChannel`)."""

    name: str
    location: str
    axis: str
    piston_diameter_m: float


LINE_PRESSURE_LOCATION = "wheel_cylinder"
TONE_RING_LOCATION = "tone_ring"
PA_PER_BAR = 1e5
DEFAULT_TONE_RING_TEETH = 48
DEFAULT_PISTON_DIAMETER_M = WHEEL_CYLINDER_BORE_M  # the model's wheel cylinder
# where a kind may sit: a mount point of the structure (checked by the sensor set)
ON_STRUCTURE = ("<a mount point of the structure>",)

Columns = dict[str, np.ndarray]


@dataclass(frozen=True)
class SensorKind:
    """One kind of sensor channel and its model.

    Attributes:
        name: the kind's name (``SensorChannel.kind``, a scenario's ``[[sensors]] kind``).
        unit: the unit of what it measures.
        description: what it measures, one line.
        locations: where it may sit, or :data:`ON_STRUCTURE` (a mount point).
        axis: it measures along an axis (x or y, frame brake_backing_plate).
        presets: transducer preset classes by name (``ideal`` among them).
        default_preset: the preset a scenario gets when it names none.
        faults: the sensor-fault kinds it can carry (:data:`.sensor_faults.FAULT_KINDS`).
        inputs: the sample-block columns its true value reads, for a channel.
        true_value: its model: the true value (channel unit) from those columns, by name,
            and the structure's output for the channel (n,) (accelerometers; else None).
        reads_structure: it measures the structure (the bank builds one for it).
        tone_ring: its outputs are a tone ring's pulse and index (no analog path).
    """

    name: str
    unit: str
    description: str
    locations: tuple[str, ...]
    axis: bool
    presets: dict[str, Transducer]
    default_preset: str
    faults: tuple[str, ...]
    inputs: Callable[[Channel], tuple[str, ...]]
    true_value: Callable[[Channel, Columns, np.ndarray | None], np.ndarray]
    reads_structure: bool = False
    tone_ring: bool = False

    def output_names(self, name: str) -> tuple[str, ...]:
        """The sampled series a channel ``name`` of this kind gives."""
        return (name, f"{name}_index") if self.tone_ring else (name,)


def _structure(channel: Channel, columns: Columns, structure: np.ndarray | None):
    assert structure is not None  # the bank passes the channel's structure output
    return structure


def _load_pin_inputs(channel: Channel) -> tuple[str, ...]:
    return (f"{channel.location}_pivot_f{channel.axis}_n",)


def _load_pin(channel: Channel, columns: Columns, structure: np.ndarray | None):
    # the force on the plate: opposite of the pin's
    return -columns[f"{channel.location}_pivot_f{channel.axis}_n"]


_ACTUATION = ("left_actuation_force_n", "right_actuation_force_n")


def _line_pressure(channel: Channel, columns: Columns, structure: np.ndarray | None):
    # one wheel cylinder pushes both shoes: the mean force over the piston area (on the
    # service brake the mean piston force is the modelled line pressure times the area,
    # model/service.py, unless a piston sits at the residual force)
    area_m2 = math.pi * channel.piston_diameter_m**2 / 4.0
    mean_force = 0.5 * (columns["left_actuation_force_n"] + columns["right_actuation_force_n"])
    return mean_force / area_m2 / PA_PER_BAR


def _drum_angle(channel: Channel, columns: Columns, structure: np.ndarray | None):
    return columns["drum_angle_rad"]


_NO_LOOSE = tuple(k for k in sf.FAULT_KINDS if k != "loose_mount")
SENSOR_KINDS: dict[str, SensorKind] = {
    k.name: k
    for k in (
        SensorKind(
            "accelerometer",
            "m/s^2",
            "acceleration along the axis at a mount point of the structure",
            ON_STRUCTURE,
            True,
            {
                "adxl1002_class": accel("adxl1002_class", 25.0, 11e3, 21e3, 50.0, 24, 0.45),
                "adxl1001_class": accel("adxl1001_class", 30.0, 11e3, 21e3, 100.0, 24, 0.45),
                "consumer_imu_class": accel("consumer_imu_class", 300.0, 1e3, None, 16.0, 16, None),
                "ideal": IDEAL,
            },
            "adxl1002_class",
            sf.FAULT_KINDS,
            lambda channel: (),
            _structure,
            reads_structure=True,
        ),
        SensorKind(
            "load_pin",
            "N",
            "the force on the structure at a pivot pin along the axis",
            SIDES,
            True,
            {
                "strain_gauge_pin": Transducer(
                    "strain_gauge_pin", 0.2, 2_000.0, None, 0.05, -20_000.0, 20_000.0, 16
                ),
                "ideal": IDEAL,
            },
            "strain_gauge_pin",
            _NO_LOOSE,
            _load_pin_inputs,
            _load_pin,
        ),
        SensorKind(
            "line_pressure",
            "bar",
            "brake line pressure: the mean actuation force over the piston area",
            (LINE_PRESSURE_LOCATION,),
            False,
            {
                "pressure_transducer": Transducer(
                    "pressure_transducer", 0.003, 1_000.0, None, 0.05, 0.0, 250.0, 16
                ),
                "ideal": IDEAL,
            },
            "pressure_transducer",
            _NO_LOOSE,
            lambda channel: _ACTUATION,
            _line_pressure,
        ),
        SensorKind(
            "wheel_speed",
            "1",
            "an ABS tone ring read from the drum angle: a pulse and an index series",
            (TONE_RING_LOCATION,),
            False,
            {"abs_tone_ring": IDEAL, "ideal": IDEAL},
            "abs_tone_ring",
            ("dropout", "stuck"),
            lambda channel: ("drum_angle_rad",),
            _drum_angle,
            tone_ring=True,
        ),
    )
}


def sensor_kind(name: str, channel: str = "") -> SensorKind:
    """The entry of the kind ``name``; a kind without one is refused, in one line."""
    kind = SENSOR_KINDS.get(name)
    if kind is None:
        raise ParameterError(
            f"sensor {channel!r}: kind = {name!r} is invalid: allowed one of"
            f" {list(SENSOR_KINDS)} (a kind needs its model: sensing/kinds.py)"
        )
    return kind


@contextmanager
def registered(kind: SensorKind) -> Iterator[SensorKind]:
    """``kind`` in the registry for the ``with`` block (a test's kind)."""
    if kind.name in SENSOR_KINDS:
        raise ParameterError(f"sensor kind {kind.name!r} is registered already")
    if kind.default_preset not in kind.presets or not set(kind.faults) <= set(sf.FAULT_KINDS):
        raise ParameterError(f"sensor kind {kind.name!r}: a default preset and known faults")
    SENSOR_KINDS[kind.name] = kind
    try:
        yield kind
    finally:
        del SENSOR_KINDS[kind.name]
