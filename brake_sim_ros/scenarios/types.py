"""The scenario types: :class:`Scenario` (a braking event to run) and
:class:`SolverSettings` (how it is integrated), with the sample-rate and step limits a
scenario file or the command line may set.

A :class:`Scenario` is built by the loader (:mod:`.loader`) from a file, or in code; its
``with_*`` methods give it another brake unit, run seed, solver or defects, with the same
checks as the file.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
from dataclasses import dataclass, field
from typing import Any

from brake_sim_ros.errors import BrakeSimError, ScenarioError
from brake_sim_ros.fleet import conditions as operating
from brake_sim_ros.fleet.scatter import NOMINAL_UNIT, UnitValue, unit_values
from brake_sim_ros.model.actuation import Actuation
from brake_sim_ros.model.assembly import pack
from brake_sim_ros.model.cycle import pack_drive
from brake_sim_ros.model.defects import Defects
from brake_sim_ros.model.fidelity import Needs, plan
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.scenarios.checker import Checker
from brake_sim_ros.scenarios.unit_draws import unit_brake, unit_sensor_set
from brake_sim_ros.sensing.sensors import SensorSet, default_sensor_set
from brake_sim_ros.solvers.fixed_step import MIN_PHYSICS_STEP_S
from brake_sim_ros.solvers.methods import FIXED_STEP_METHODS, SOLVER_METHODS
from brake_sim_ros.solvers.presets import DEFAULT_PRESET, PRESETS

# The output sample rate of a scenario that does not set one: 25.6 kHz, the common
# condition-monitoring rate (a power-of-two number of samples per 10 ms chunk: 256).
DEFAULT_SAMPLE_RATE_HZ = 25_600.0
SAMPLE_RATE_RANGE_HZ = (1.0, 1e6)

# The largest physics step a scenario or the command line may set, s: from the smallest step
# the stepper takes (a smaller bound would ask for billions of substeps) to 10 ms.
MAX_STEP_RANGE_S = (MIN_PHYSICS_STEP_S, 1e-2)


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
        ctx = Checker(self.source)
        ctx.identifier(unit_id, "unit_id")
        for key, value in (("seed", seed), ("fleet_seed", fleet_seed)):
            ctx.seed(value, key)
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
