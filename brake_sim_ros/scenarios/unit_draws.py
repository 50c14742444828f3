"""A unit's drawn brake and sensors, remembered per process.

Drawing a unit's manufacturing scatter (:func:`~brake_sim_ros.fleet.scatter.unit_parameters`,
:func:`~brake_sim_ros.fleet.scatter.unit_sensors`: a keyed generator per scattered value) was
over half of the time to parse a scenario, and a campaign resolves every run of a unit on
the same brake: planning 10,000 runs drew the same twenty brakes 500 times each. The draws are
pure functions of their arguments, so each is kept here, keyed by the ``repr`` of the
nominal values (which tells ``-0.0`` from ``0.0``, as ``==`` would not: the same bits in,
the same bits out), the unit id and the fleet seed.
"""

from __future__ import annotations

from brake_sim_ros.fleet.scatter import NOMINAL_UNIT, unit_parameters, unit_sensors
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.sensing.sensors import SensorSet

_KEPT = 256  # distinct (nominal, unit, seed) keys kept per kind; then the memory starts over
_BRAKES: dict[tuple[str, str, int], BrakeParameters] = {}
_SENSORS: dict[tuple[str, str, int], SensorSet] = {}


def unit_brake(nominal: BrakeParameters, unit_id: str, fleet_seed: int) -> BrakeParameters:
    """:func:`~brake_sim_ros.fleet.scatter.unit_parameters`, remembered (its errors are not);
    unit "nominal" is ``nominal`` itself, as there."""
    if unit_id == NOMINAL_UNIT:
        return nominal
    key = (repr(nominal), unit_id, fleet_seed)
    brake = _BRAKES.get(key)
    if brake is None:
        brake = unit_parameters(nominal, unit_id, fleet_seed)
        if len(_BRAKES) >= _KEPT:
            _BRAKES.clear()
        _BRAKES[key] = brake
    return brake


def unit_sensor_set(nominal: SensorSet, unit_id: str, fleet_seed: int) -> SensorSet:
    """:func:`~brake_sim_ros.fleet.scatter.unit_sensors`, remembered; unit "nominal" is
    ``nominal`` itself, as there."""
    if unit_id == NOMINAL_UNIT:
        return nominal
    key = (repr(nominal), unit_id, fleet_seed)
    sensors = _SENSORS.get(key)
    if sensors is None:
        sensors = unit_sensors(nominal, unit_id, fleet_seed)
        if len(_SENSORS) >= _KEPT:
            _SENSORS.clear()
        _SENSORS[key] = sensors
    return sensors
