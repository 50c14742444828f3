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

from collections.abc import Callable
from typing import TypeVar

from brake_sim_ros.fleet.scatter import NOMINAL_UNIT, unit_parameters, unit_sensors
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.sensing.sensors import SensorSet

_KEPT = 256  # distinct (nominal, unit, seed) keys kept per kind; then the memory starts over
_BRAKES: dict[tuple[str, str, int], BrakeParameters] = {}
_SENSORS: dict[tuple[str, str, int], SensorSet] = {}

_T = TypeVar("_T")


def _remembered(
    memory: dict[tuple[str, str, int], _T],
    draw: Callable[[_T, str, int], _T],
    nominal: _T,
    unit_id: str,
    fleet_seed: int,
) -> _T:
    """``draw(nominal, unit_id, fleet_seed)``, kept in ``memory`` (its errors are not);
    unit "nominal" is ``nominal`` itself, as in :mod:`~brake_sim_ros.fleet.scatter`."""
    if unit_id == NOMINAL_UNIT:
        return nominal
    key = (repr(nominal), unit_id, fleet_seed)
    drawn = memory.get(key)
    if drawn is None:
        drawn = draw(nominal, unit_id, fleet_seed)
        if len(memory) >= _KEPT:
            memory.clear()
        memory[key] = drawn
    return drawn


def unit_brake(nominal: BrakeParameters, unit_id: str, fleet_seed: int) -> BrakeParameters:
    """:func:`~brake_sim_ros.fleet.scatter.unit_parameters`, remembered."""
    return _remembered(_BRAKES, unit_parameters, nominal, unit_id, fleet_seed)


def unit_sensor_set(nominal: SensorSet, unit_id: str, fleet_seed: int) -> SensorSet:
    """:func:`~brake_sim_ros.fleet.scatter.unit_sensors`, remembered."""
    return _remembered(_SENSORS, unit_sensors, nominal, unit_id, fleet_seed)
