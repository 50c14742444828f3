"""One run of a scenario, transport-free: the loop the node, the offline stream and
re-simulation all drive.

:class:`RunSession` owns what a run is made of: the stepper, the command planner, the
contact-event detector, the sensors of ~/measured, the ground truth's schedule, the run
parameters in force (``settings``, :mod:`.run_parameters`) and the model's flat values
(:mod:`.parameters`). Its verbs are the run's: :meth:`~RunSession.start` (the messages
of a start or reset), :meth:`~RunSession.advance` and :meth:`~RunSession.messages`
(step samples, then the messages they make), :meth:`~RunSession.apply` (a parameter
change, checked as a whole), :meth:`~RunSession.command` and :meth:`~RunSession.drive`,
:meth:`~RunSession.reset` and :meth:`~RunSession.switch` (a new run, perhaps of another
scenario), and :meth:`~RunSession.record_values` (what the ``brake_sim_run`` record says
of the run parameters). Every message is ``(topic, message, time_ns)`` in simulated
time; the caller publishes, records or yields it. Pacing, costs and the wall clock are
the node's, not the session's.
"""

from __future__ import annotations

import sys
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from brake_sim_ros import stream
from brake_sim_ros.analysis.contact_events import ContactEventDetector
from brake_sim_ros.errors import BrakeSimError, ParameterError, SimulationError
from brake_sim_ros.model.cycle import LiveDrive
from brake_sim_ros.model.run_setup import BrakeSetup, SampleBlock
from brake_sim_ros.scenarios import Scenario
from brake_sim_ros.sensing.sensors import SensorBank
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.solvers.realtime import check_chunk_work
from brake_sim_ros.stream import conversion, run_parameters
from brake_sim_ros.stream import parameters as ros_params
from brake_sim_ros.stream.build import sensor_bank_for, stepper_for
from brake_sim_ros.stream.commands import (
    ActuationPlanner,
    CommandPolicy,
    TimeoutBehaviour,
    check_command,
)
from brake_sim_ros.stream.ground_truth import TruthUpdates, recorded_wear, state_wear
from brake_sim_ros.stream.run_parameters import Affects

Message = tuple[stream.Topic, Any, int]
_POLICY = ("command_timeout_s", "on_command_timeout", "command_ramp_rate_n_per_s")


def command_policy(values: Mapping[str, Any]) -> CommandPolicy:
    """The command timeout policy of the run parameters ``values`` (by name).

    Raises:
        ValueError: a value of the wrong type, or one the policy refuses (one line).
    """
    for key in ("command_timeout_s", "command_ramp_rate_n_per_s"):
        value = values[key]
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueError(f"{key}={value!r}: allowed a number")
    return CommandPolicy(
        timeout_s=float(values["command_timeout_s"]),
        behaviour=TimeoutBehaviour.parse(str(values["on_command_timeout"])),
        ramp_rate_n_per_s=float(values["command_ramp_rate_n_per_s"]),
    )


def drive_values(setup: BrakeSetup) -> dict[str, float]:
    """The live-drive parameters as in force for ``setup``: its vehicle's settings, or 0
    for a run that takes no live drive."""
    drives = setup.vehicle is not None and setup.cycle is None
    return {
        name: float(getattr(setup.vehicle, name)) if drives else 0.0
        for name in ros_params.DRIVE_LIMIT_NAMES
    }


@dataclass(frozen=True)
class Prepared:
    """A scenario's stepper built for a session, not yet in use (:meth:`RunSession.switch`)."""

    scenario: Scenario
    stepper: FixedStepStepper


class RunSession:
    """A run of ``scenario``: its stepper, commands, sensors and ground truth.

    Args:
        scenario: what runs (its unit and seed as drawn).
        settings: run parameters by name (:mod:`.run_parameters`; the rest default).
            ``duration_s`` and ``max_actuation_force_n`` 0 mean the scenario's; the
            drive settings 0 the scenario's [vehicle]'s.
        model: the model's flat values (every model parameter: a node's, with any
            overrides; :func:`.parameters.node_setup`); None = the scenario's setup.
        run_id: the run id of the ground truth (default a fresh one).
        seed: the run's seed, which seeds the sensors (default the scenario's).
        stepper: a stepper to use for ``scenario`` (it is reset); default built here.

    Raises:
        BrakeSimError: a model or drive setting the core refuses (one line).
    """

    def __init__(
        self,
        scenario: Scenario,
        *,
        settings: Mapping[str, Any] | None = None,
        model: Mapping[str, Any] | None = None,
        run_id: str | None = None,
        seed: int | None = None,
        stepper: FixedStepStepper | None = None,
    ) -> None:
        self.settings: dict[str, Any] = {**run_parameters.defaults(), **(settings or {})}
        drive = self._drive_start = self._drive_overrides()
        if model is None:
            setup = ros_params.with_drive_limits(scenario.setup, drive)
        else:
            setup = ros_params.node_setup(scenario.setup, dict(model), drive)
        if stepper is None:
            stepper = stepper_for(scenario, setup=setup)
        stepper.reset()
        stepper.advance(0)  # loads the compiled kernel now (ms), not in the first chunk
        self.scenario, self.stepper = scenario, stepper
        setup = stepper.setup
        self.model = ros_params.model_values(setup.params, setup.defects)
        self.model.update(model or {})
        self.seed = scenario.seed if seed is None else seed
        self._run_id_fixed = run_id
        self.run_id = run_id or conversion.new_run_id()
        # 0 = the scenario's: follows a switch of scenario until set at run time
        self.duration_explicit = self.settings["duration_s"] > 0.0
        self._auto_max_force = not self.settings["max_actuation_force_n"]
        self._scenario_defaults()
        self.planner = ActuationPlanner(self.period_s, command_policy(self.settings))
        self.truth = TruthUpdates(self.stepper.setup.defects)
        self.physics_steps = 0  # physics steps the last advance took
        self._new_run()

    # -- what the run is now ----------------------------------------------------------------
    @property
    def period_s(self) -> float:
        return self.stepper.sample_period_s

    @property
    def sample_index(self) -> int:
        """The next sample to step (the samples stepped so far)."""
        return self.stepper.sample_index

    def samples_per(self, name: str, value: float | None = None) -> int:
        """Samples per message of the rate parameter ``name`` (Hz; ``value`` or its own)."""
        return stream.samples_per(self.settings[name] if value is None else value, self.period_s)

    @property
    def chunk_samples(self) -> int:
        return self.samples_per("chunk_rate_hz")

    @property
    def end_sample(self) -> int:
        """The sample index at which the free run ends (never, while ``continuous``)."""
        if self.settings["continuous"]:
            return sys.maxsize
        return round(self.settings["duration_s"] / self.period_s)

    def work_refusal(self, stepper: FixedStepStepper | None = None, chunk: int = 0) -> str | None:
        """Why one chunk of ``chunk`` samples (default the session's) would be too much
        work for ``stepper`` (default the session's), or None."""
        stepper = stepper or self.stepper
        return check_chunk_work(
            stepper.substeps, chunk or self.chunk_samples, stepper.physics_step_s
        )

    def new_sensor_bank(self) -> SensorBank | None:
        """The scenario's sensors from sample 0 seeded with the run's seed (None when
        publish_measured is off), as every path builds them."""
        if not self.settings["publish_measured"]:
            return None
        return sensor_bank_for(self.scenario, seed=self.seed)

    # -- start, step, messages ----------------------------------------------------------------
    def _new_run(self) -> None:
        """The per-run state, fresh: contact episodes, sensors, the initial angles."""
        self.contact_events = ContactEventDetector()
        bank = self.new_sensor_bank()
        rate = self.samples_per("measured_rate_hz")
        self.measured = None if bank is None else stream.MeasuredStream(bank, rate)
        defects = self.stepper.setup.defects
        self.initial_angles = (defects.left.initial_angle_deg, defects.right.initial_angle_deg)

    def start(self) -> list[Message]:
        """The messages of a (re)start: the ground truth at the next sample, /clock at 0."""
        out = [self.truth_message()]
        if self.settings["publish_clock"]:
            out.append((stream.CLOCK, conversion.clock(0), 0))
        return out

    def truth_message(
        self, sample_index: int | None = None, wear_m: dict[str, float] | None = None
    ) -> Message:
        """The ground truth (DefectState) at ``sample_index`` (default the next sample: a
        start, reset or change of the defects, which restarts its schedule), with the
        linings' wear ``wear_m`` recorded there (default the stepper's now)."""
        index = self.sample_index if sample_index is None else sample_index
        ns = conversion.stamp_ns(index, self.period_s)
        if wear_m is None:
            wear_m = state_wear(self.stepper.state)
        defects = self.stepper.setup.defects
        msg = conversion.defect_state(
            scenario=self.scenario.name,
            defects=defects,
            initial_angles_deg=self.initial_angles,
            ns=ns,
            run_id=self.run_id,
            seed=self.seed,
            unit_id=self.scenario.unit_id,
            time_s=index * self.period_s,
            wear_m=wear_m,
        )
        if sample_index is None:
            self.truth.published(defects, index * self.period_s, wear_m)
        return stream.DEFECTS, msg, ns

    def advance(self, n_samples: int) -> SampleBlock:
        """Step ``n_samples`` (at most a chunk) under the commands in force.

        Raises:
            BrakeSimError: the stepper's failure, or SimulationError for non-finite or
                missing samples (nothing of them is to be published).
        """
        step0 = self.sample_index
        blocks = []
        self.physics_steps = 0
        for count, forces in self.planner.segments(step0, n_samples):
            blocks.append(self.stepper.advance(count, actuation_n=forces))
            self.physics_steps += count * self.stepper.substeps
        block = blocks[0] if len(blocks) == 1 else SampleBlock.concatenate(blocks)
        if len(block) != n_samples or not conversion.all_finite(block):
            raise SimulationError(
                f"non-finite or missing samples between samples {step0} and"
                f" {step0 + n_samples}; nothing of them was published"
            )
        return block

    def messages(self, block: SampleBlock) -> list[Message]:
        """Every message of a stepped ``block``: ground truth due in it, then the node's
        chunk, states, /clock, contact events and ~/measured."""
        out = [
            self.truth_message(block.first_index + row, recorded_wear(block, row))
            for row in self.truth.due_rows(block.time_s, recorded_wear(block))
        ]
        out.extend(
            stream.block_messages(
                block,
                self.samples_per("state_rate_hz"),
                with_clock=self.settings["publish_clock"],
                contact_events=self.contact_events,
                run_id=self.run_id,
                measured=self.measured,
            )
        )
        return out

    def flush(self) -> list[Message]:
        """The measured samples still pending: the stream stops here, for now or for good."""
        return [] if self.measured is None else list(self.measured.flush())

    # -- parameters ---------------------------------------------------------------------------
    def apply(self, changes: Mapping[str, Any]) -> list[Message]:
        """Apply a change of run and model parameters from the next sample on, as a whole
        or not at all; the messages it makes (the ground truth, for a model change).

        Raises:
            ParameterError: one line, nothing changed: an unknown parameter, one fixed at
                start, a value refused (the core's reason for a model change).
        """
        table = run_parameters.by_name()
        unknown = [k for k in changes if k not in table and k not in self.model]
        if unknown:
            raise ParameterError(f"unknown parameter {unknown[0][:64]!r}")
        for name in changes.keys() & run_parameters.fixed_at_start():
            raise ParameterError(f"{name} is fixed at start-up")
        settings = {k: v for k, v in changes.items() if k in table}
        try:
            policy = command_policy({**self.settings, **settings})
        except ValueError as exc:
            raise ParameterError(str(exc)) from None
        if "duration_s" in settings and not settings["duration_s"] > 0.0:
            raise ParameterError("duration_s must be > 0 s at run time")
        chunk = self.samples_per("chunk_rate_hz", settings.get("chunk_rate_hz"))
        model = {k: v for k, v in changes.items() if k in self.model}
        out: list[Message] = []
        if model:
            self._apply_model(model, chunk)
            out.append(self.truth_message())
        elif "chunk_rate_hz" in settings:
            work = self.work_refusal(chunk=chunk)
            if work:
                raise ParameterError(work)
        self.settings.update(settings)
        self.duration_explicit |= "duration_s" in settings
        self.planner.policy = policy
        return out

    def _apply_model(self, model: Mapping[str, Any], chunk: int) -> None:
        old = self.stepper.setup
        try:
            setup = ros_params.changed_setup(old, {**self.model, **model})
            self.stepper.replace_setup(setup)  # validates, or changes nothing
        except BrakeSimError as exc:
            raise ParameterError(str(exc)) from None
        work = self.work_refusal(chunk=chunk)
        if work:
            self.stepper.replace_setup(old)
            raise ParameterError(work)
        self.model.update(model)

    def _scenario_defaults(self) -> None:
        """The settings that follow the scenario: its duration (unless set), twice its
        peak force (unless set), its live drive's settings in force."""
        if not self.duration_explicit:
            self.settings["duration_s"] = self.scenario.duration_s
        if self._auto_max_force:
            force = ros_params.auto_max_actuation_force(self.stepper.setup)
            self.settings["max_actuation_force_n"] = force
        self.settings.update(drive_values(self.stepper.setup))

    def _drive_overrides(self) -> dict[str, float]:
        return {n: float(self.settings[n]) for n in ros_params.DRIVE_LIMIT_NAMES}

    # -- commands -----------------------------------------------------------------------------
    def actuation_refusal(self, forces: tuple[float, float]) -> str | None:
        """Why an actuation command must be rejected, or None."""
        reason = check_command(*forces, float(self.settings["max_actuation_force_n"]))
        if reason is None and self.stepper.setup.cycle is not None:
            reason = (
                f"scenario '{self.scenario.name}' has a drive cycle ([cycle]), which commands"
                " the brake: actuation commands are allowed only without one"
            )
        return reason

    def command(self, forces: tuple[float, float]) -> bool:
        """Actuation ``forces`` (N, per shoe) from the next sample on; True when it
        replaced a command that never took effect."""
        return self.planner.command(forces, self.sample_index)

    def drive_refusal(self, drive: LiveDrive) -> str | None:
        refusal = self.stepper.drive_refusal(drive)
        return None if refusal is None else f"scenario '{self.scenario.name}': {refusal}"

    def drive(self, drive: LiveDrive) -> None:
        """A live drive command from the next sample on, until the next one or a reset."""
        self.stepper.drive(drive)

    # -- reset and scenario switch -----------------------------------------------------------
    def prepare(self, scenario: Scenario) -> Prepared:
        """``scenario``'s stepper with this session's drive settings, checked for a chunk's
        work, not yet in use (BrakeSimError naming the scenario)."""
        setup = ros_params.with_drive_limits(scenario.setup, self._drive_start)
        stepper = stepper_for(scenario, setup=setup)
        chunk = stream.samples_per(self.settings["chunk_rate_hz"], stepper.sample_period_s)
        reason = self.work_refusal(stepper, chunk)
        if reason:
            raise BrakeSimError(f"scenario '{scenario.name}': {reason}")
        stepper.advance(0)
        return Prepared(scenario, stepper)

    def switch(self, prepared: Prepared) -> None:
        """Run ``prepared``'s scenario from now on (call :meth:`reset` next): its model,
        its seed, and the settings that follow the scenario (:meth:`_scenario_defaults`)."""
        scenario, self.stepper = prepared.scenario, prepared.stepper
        self.scenario, self.seed = scenario, scenario.seed
        self.model = ros_params.model_values(scenario.setup.params, scenario.setup.defects)
        self._scenario_defaults()
        self.planner.sample_period_s = self.period_s

    def reset(self, *, seed: int | None = None) -> bool:
        """Back to sample 0: a new run (new run id unless fixed, fresh sensors, no
        command in force; ``seed`` >= 0 replaces the run's). True when a pending command
        was dropped. Call :meth:`start` for its first messages."""
        self.stepper.reset()
        if seed is not None and seed >= 0:
            self.seed = seed
        self.run_id = self._run_id_fixed or conversion.new_run_id()
        self._new_run()
        return self.planner.clear()

    # -- the run record -----------------------------------------------------------------------
    def record_values(self) -> dict[str, Any]:
        """The run parameters the ``brake_sim_run`` record carries (in force now): every
        recorded entry of the table (:func:`.run_parameters.recorded`); a live drive's
        settings only for a run that takes one."""
        drives = self.stepper.drive_refusal() is None
        return {
            p.name: self.settings[p.name]
            for p in run_parameters.RUN_PARAMETERS
            if run_parameters.recorded(p) and (p.affects is not Affects.DRIVE or drives)
        }
