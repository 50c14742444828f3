"""Operating conditions that vary from run to run, drawn from ranges with the run's seed.

A scenario may give, in ``[conditions]``, a range ``[low, high]`` for any of the
conditions in :data:`CONDITIONS`; each run draws each uniformly within its range from its
seed (its own generator: :func:`~brake_sim_ros.fleet.scatter.keyed_uniform` of the seed,
``brake_sim_ros operating conditions`` and the condition's name, so a condition's draw
does not depend on which others the scenario gives). A condition without a range keeps the
scenario's value. What each one sets:

* ``initial_speed_rad_s``: flywheel and drum speed at the start, rad/s (the published
  event: 103.5 rad/s, 100 km/h).
* ``load_factor``: the vehicle's mass over the mass the scenario's flywheel inertia stands
  for (dimensionless; the published 17.1 kg m^2 is a 1000 kg car). The flywheel carries
  the brake's share of the vehicle's inertia, which grows with its mass at the same rolling
  radius: ``I_f = load_factor x I_f(scenario)``. The share per brake is kept: the load
  transfer to the front axle in a stop is not modelled. A drive cycle may instead change
  it per stop, at its standing holds (model/cycle.py); not both.
* ``peak_force_n``: the actuation profile's peak, N: both shoes' profiles scaled by one
  factor so that their largest force is this (the ramp's timing kept).
* ``brake_temperature_c``: the linings' and drum's temperature, deg C. Without a thermal
  state (no ``[thermal]`` table) it is held over the run (a stop heats a passenger drum
  by some 25 K: 92 kJ into 8 kg of cast iron) and acts through the fade law
  :data:`~brake_sim_ros.model.thermal.FADE` on both linings' friction coefficient; with
  one it is the state's temperature at the start, and the state moves it.
* ``ambient_temperature_c``: the air's, deg C; a run that draws no brake temperature has
  its brake at the ambient (a cold brake). With a thermal state it is the air the brake
  cools to. Below the fade law's onset a temperature leaves the friction as it is, so the
  ambient alone changes no physics of a held brake: it is ground truth for a detector's
  features (and sets a cold brake's temperature).
* ``road_friction``: the road's sliding friction coefficient under the service brake's
  tyre (model/tyre.py; the scenario's top-level ``road_friction`` otherwise, dry asphalt
  0.8 by default); refused on the study brake, which has no tyre.

Fade and contamination can halve a lining's friction (``TESTBED.md``); the fade law and
its assumption are in model/thermal.py. A lining whose curve is known is better given as
a ``friction_change`` defect.

Pure: no numerics beyond the draw.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.fleet.scatter import keyed_uniform
from brake_sim_ros.model.actuation import MAX_ACTUATION_FORCE_N, Actuation, ForceProfile
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.model.service_parameters import ROAD_FRICTION_RANGE
from brake_sim_ros.model.thermal import FADE
from brake_sim_ros.model.vehicle import LOAD_FACTOR_RANGE

DOMAIN = "brake_sim_ros operating conditions"


@dataclass(frozen=True)
class Condition:
    """One operating condition a scenario may draw per run.

    Attributes:
        name: its key in ``[conditions]`` and in the ground truth.
        unit: its unit ("1": dimensionless).
        low, high: the widest range a scenario may give (the model's limits).
        meaning: what it sets.
    """

    name: str
    unit: str
    low: float
    high: float
    meaning: str


CONDITIONS: tuple[Condition, ...] = (
    Condition(
        "initial_speed_rad_s",
        "rad/s",
        0.0,
        400.0,
        "flywheel and drum speed at the start (103.5 rad/s: 100 km/h)",
    ),
    Condition(
        "load_factor",
        "1",
        *LOAD_FACTOR_RANGE,
        "vehicle mass over the scenario's; the flywheel inertia scales with it",
    ),
    Condition(
        "peak_force_n",
        "N",
        0.0,
        MAX_ACTUATION_FORCE_N,
        "the actuation profile's peak; both shoes scaled by one factor",
    ),
    Condition(
        "brake_temperature_c",
        "degC",
        -40.0,
        600.0,
        "linings' and drum's temperature, held over the run; the friction by the fade law",
    ),
    Condition(
        "ambient_temperature_c",
        "degC",
        -40.0,
        50.0,
        "air temperature; the brake's too when brake_temperature_c is not drawn",
    ),
    Condition(
        "road_friction",
        "1",
        *ROAD_FRICTION_RANGE,
        "the road's sliding friction under the service brake's tyre (dry asphalt 0.8)",
    ),
)
CONDITION_BY_NAME: dict[str, Condition] = {c.name: c for c in CONDITIONS}


def check_range(name: str, low: float, high: float) -> None:
    """Raise ParameterError unless ``[low, high]`` is a range of condition ``name``."""
    c = CONDITION_BY_NAME.get(name)
    if c is None:
        raise ParameterError(f"condition {name!r}: allowed one of {list(CONDITION_BY_NAME)}")
    if not (math.isfinite(low) and math.isfinite(high) and c.low <= low <= high <= c.high):
        raise ParameterError(
            f"condition {name} range [{low!r}, {high!r}]: allowed low <= high within"
            f" [{c.low:g}, {c.high:g}] {c.unit}"
        )


def draw(ranges: Mapping[str, tuple[float, float]], seed: int) -> dict[str, float]:
    """Each condition of ``ranges`` drawn uniformly within its range for ``seed``, in
    :data:`CONDITIONS` order."""
    out = {}
    for c in CONDITIONS:
        if c.name in ranges:
            low, high = ranges[c.name]
            check_range(c.name, low, high)
            out[c.name] = low + keyed_uniform(seed, DOMAIN, c.name) * (high - low)
    return out


def _scaled(profile: ForceProfile, factor: float) -> ForceProfile:
    return ForceProfile(profile.times_s, tuple(f * factor for f in profile.forces_n))


def _on_road(params: BrakeParameters, friction: float) -> BrakeParameters:
    """``params`` with the service brake's tyre on a road of sliding ``friction``."""
    if params.service is None:
        raise ParameterError(
            'condition road_friction: the study brake has no tyre: allowed with brake = "service"'
        )
    tyre = dataclasses.replace(params.service.tyre, road_friction=friction)
    return dataclasses.replace(params, service=dataclasses.replace(params.service, tyre=tyre))


def apply(setup: BrakeSetup, drawn: Mapping[str, float]) -> BrakeSetup:
    """``setup`` under the drawn conditions (see the module doc); ``setup`` itself when
    none is drawn.

    Raises:
        ParameterError: a peak force for a profile that never pushes (no force to scale).
    """
    if not drawn:
        return setup
    driveline = setup.params.driveline
    changes = {}
    if "initial_speed_rad_s" in drawn:
        changes["initial_speed_rad_s"] = drawn["initial_speed_rad_s"]
    if "load_factor" in drawn:
        changes["flywheel_inertia_kg_m2"] = driveline.flywheel_inertia_kg_m2 * drawn["load_factor"]
    params = dataclasses.replace(setup.params, driveline=dataclasses.replace(driveline, **changes))
    if "road_friction" in drawn:
        params = _on_road(params, drawn["road_friction"])
    temperature = drawn.get("brake_temperature_c", drawn.get("ambient_temperature_c"))
    held = setup.held_temperature_c if temperature is None else temperature
    thermal = setup.thermal
    if thermal is not None:  # the state starts at the brake's temperature, in the air's
        air = drawn.get("ambient_temperature_c", thermal.ambient_c)
        start = drawn.get("brake_temperature_c", thermal.initial_c)
        thermal = dataclasses.replace(thermal, ambient_c=air, initial_c=start)
    elif temperature is not None and FADE.ratio(temperature) != 1.0:
        friction = params.friction
        params = dataclasses.replace(
            params,
            friction=dataclasses.replace(
                friction, coefficient=friction.coefficient * FADE.ratio(temperature)
            ),
        )
    actuation = setup.actuation
    if "peak_force_n" in drawn:
        peak = max(max(actuation.left.forces_n), max(actuation.right.forces_n))
        if peak <= 0.0:
            raise ParameterError(
                "condition peak_force_n: the actuation profile never pushes, so it has no"
                " peak to scale: allowed with a profile whose largest force is > 0 N"
            )
        factor = drawn["peak_force_n"] / peak
        actuation = Actuation(_scaled(actuation.left, factor), _scaled(actuation.right, factor))
    return dataclasses.replace(
        setup, params=params, actuation=actuation, thermal=thermal, held_temperature_c=held
    )
