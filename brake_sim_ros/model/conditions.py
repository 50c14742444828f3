"""Operating conditions that vary from run to run, drawn from ranges with the run's seed.

A scenario may give, in ``[conditions]``, a range ``[low, high]`` for any of the
conditions in :data:`CONDITIONS`; each run draws each uniformly within its range from its
seed (its own generator: :func:`~brake_sim_ros.model.units.keyed_uniform` of the seed,
``brake_sim_ros operating conditions`` and the condition's name, so a condition's draw
does not depend on which others the scenario gives). A condition without a range keeps the
scenario's value. What each one sets:

* ``initial_speed_rad_s``: flywheel and drum speed at the start, rad/s (the published
  event: 103.5 rad/s, 100 km/h).
* ``load_factor``: the vehicle's mass over the mass the scenario's flywheel inertia stands
  for (dimensionless; the published 17.1 kg m^2 is a 1000 kg car). The flywheel carries
  the brake's share of the vehicle's inertia, which grows with its mass at the same rolling
  radius: ``I_f = load_factor x I_f(scenario)``. The share per brake is kept: the load
  transfer to the front axle in a stop is not modelled.
* ``peak_force_n``: the actuation profile's peak, N: both shoes' profiles scaled by one
  factor so that their largest force is this (the ramp's timing kept).

Temperature is not a condition here: the model has no thermal state and no law of friction
against temperature it could state honestly; fade (TESTBED: fade and contamination can
halve the friction) belongs with the defects, as a change of friction, not here.

Pure: no numerics beyond the draw.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.actuation import MAX_ACTUATION_FORCE_N, Actuation, ForceProfile
from brake_sim_ros.model.trajectory import BrakeSetup
from brake_sim_ros.model.units import keyed_uniform

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
        0.5,
        3.0,
        "vehicle mass over the scenario's; the flywheel inertia scales with it",
    ),
    Condition(
        "peak_force_n",
        "N",
        0.0,
        MAX_ACTUATION_FORCE_N,
        "the actuation profile's peak; both shoes scaled by one factor",
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
    return dataclasses.replace(setup, params=params, actuation=actuation)
