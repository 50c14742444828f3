"""Sensor kinds carry their model (sensing/kinds.py): a channel of a kind the
registry does not hold is refused, never computed as another kind; a kind registered in a
test is built, loaded from a scenario and measured by its own model."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from brake_sim_ros.errors import ParameterError, ScenarioError
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.scenarios import parse_scenario
from brake_sim_ros.sensing import faults as sf
from brake_sim_ros.sensing.kinds import (
    IDEAL,
    LINE_PRESSURE_LOCATION,
    PA_PER_BAR,
    SENSOR_KINDS,
    SensorKind,
    registered,
)
from brake_sim_ros.sensing.sensors import SensorBank, SensorChannel, SensorSet

FS = 2560.0
COLUMNS = ("time_s", "drum_angle_rad", "left_actuation_force_n", "right_actuation_force_n")

# a kind the product does not have: the drum's angle from an encoder, in revolutions
ENCODER = SensorKind(
    "drum_encoder",
    "rev",
    "the drum's angle read by an encoder, in revolutions",
    ("drum",),
    False,
    {"ideal": IDEAL},
    "ideal",
    ("dropout", "stuck"),
    lambda channel: ("drum_angle_rad",),
    lambda channel, columns, structure: columns["drum_angle_rad"] / (2.0 * math.pi),
)


def _block(n: int = 64) -> SampleBlock:
    t = np.arange(n) / FS
    data = np.column_stack([t, 30.0 * t, 1000.0 + 10.0 * t, 1100.0 - 5.0 * t])
    return SampleBlock(data, 0, 1.0 / FS, COLUMNS)


def test_an_unknown_kind_is_refused_where_the_channel_is_built():
    with pytest.raises(ParameterError, match=r"kind = 'strain_rosette' is invalid: allowed one"):
        SensorChannel("rosette", "strain_rosette", LINE_PRESSURE_LOCATION)
    with pytest.raises(ScenarioError, match="strain_rosette"):
        parse_scenario(
            'name = "x"\n[[sensors]]\nname = "r"\nkind = "strain_rosette"\n'
            f'location = "{LINE_PRESSURE_LOCATION}"\n'
        )


def test_a_channel_whose_kind_has_no_model_is_never_measured_as_line_pressure():
    """Before the kinds carried their model, the bank computed line pressure for any kind
    it did not know; now the bank refuses the channel in one line."""
    channel = SensorChannel("p", "line_pressure", LINE_PRESSURE_LOCATION)
    object.__setattr__(channel, "kind", "strain_rosette")  # past the channel's own check
    sensors = SensorSet(channels=(SensorChannel("q", "line_pressure", LINE_PRESSURE_LOCATION),))
    object.__setattr__(sensors, "channels", (channel,))
    with pytest.raises(ParameterError, match="'strain_rosette' is invalid") as info:
        SensorBank(sensors, FS, seed=1)
    assert "\n" not in str(info.value)


def test_line_pressure_is_its_kinds_model():
    sensors = SensorSet(channels=(SensorChannel("p", "line_pressure", LINE_PRESSURE_LOCATION),))
    frame = SensorBank(sensors, FS, seed=1).advance(_block())
    block = _block()
    area = math.pi * 0.01905**2 / 4.0
    mean = 0.5 * (block["left_actuation_force_n"] + block["right_actuation_force_n"])
    np.testing.assert_allclose(frame["p"].values, mean / area / PA_PER_BAR, rtol=1e-12)


def test_a_kind_registered_in_a_test_is_loaded_and_measured_by_its_own_model():
    with registered(ENCODER):
        scenario = parse_scenario(
            'name = "x"\nduration_s = 0.2\n[[sensors]]\nname = "enc"\nkind = "drum_encoder"\n'
            'location = "drum"\n'
        )
        (channel,) = scenario.sensors.channels
        assert (channel.kind, channel.unit) == ("drum_encoder", "rev")
        frame = SensorBank(SensorSet(channels=(channel,)), FS, seed=1).advance(_block())
        np.testing.assert_array_equal(
            frame["enc"].values, _block()["drum_angle_rad"] / (2.0 * math.pi)
        )
        with pytest.raises(ParameterError, match="location"):
            SensorChannel("enc", "drum_encoder", "left")
        with pytest.raises(ParameterError, match="fault"):
            SensorChannel(
                "enc", "drum_encoder", "drum", faults=(sf.SensorFault("bias_drift", 0.1),)
            )
    assert "drum_encoder" not in SENSOR_KINDS
    with pytest.raises(ParameterError, match="drum_encoder"):
        SensorChannel("enc", "drum_encoder", "drum")


def test_a_kind_without_its_default_preset_or_with_unknown_faults_is_refused():
    for bad in (
        dataclasses.replace(ENCODER, default_preset="optical"),
        dataclasses.replace(ENCODER, faults=("cosmic_ray",)),
        dataclasses.replace(ENCODER, name="line_pressure"),
    ):
        with pytest.raises(ParameterError), registered(bad):
            pass
    assert set(SENSOR_KINDS) == {"accelerometer", "load_pin", "line_pressure", "wheel_speed"}
