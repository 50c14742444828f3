"""The simulator as a ROS 2 node: the class :class:`BrakeSimNode` (a leaf adapter).

Run it with ``python -m brake_sim_ros.app.node`` or ``brake-sim node``: the composition
root :mod:`brake_sim_ros.app.node` parses the options, handles signals and wires the
recorder and Rerun sinks in through ``sink_openers``. This module imports neither
recording nor viz.

Topics (node name ``brake_sim``; ``~`` = ``/brake_sim``; QoS in :mod:`.qos`):
    ~/pivot_forces   brake_sim_msgs/PivotForceChunk   every physics sample, in chunks
    ~/measured       brake_sim_msgs/MeasuredChunk     the scenario's sensors, the same samples
                                                      (publish_measured)
    ~/state          brake_sim_msgs/BrakeState        at state_rate_hz (simulated)
    ~/joint_states   sensor_msgs/JointState           flywheel, drum, left_shoe, right_shoe
    ~/contact_events brake_sim_msgs/ContactEvent      every contact onset and separation of
                                                      either shoe, at full sample rate: the
                                                      onset at its sample, the separation
                                                      with the episode's peak pivot force
    ~/defects        brake_sim_msgs/DefectState       ground truth, transient local
    /clock           rosgraph_msgs/Clock              simulated time (publish_clock)
    /diagnostics     diagnostic_msgs/DiagnosticArray  every diagnostics_period_s (wall)
    ~/actuation      brake_sim_msgs/ActuationCommand  (subscribed) overrides the profile
    ~/drive          brake_sim_msgs/DriveCommand      (subscribed) drives the vehicle: coast,
                                                      a torque or a target speed, held until
                                                      the next (a scenario with a [vehicle]
                                                      and no [cycle]; coasting at start and
                                                      after a reset)
Services:
    ~/step   brake_sim_msgs/StepSimulation   advance N samples or a duration while paused
    ~/reset  brake_sim_msgs/ResetSimulation  back to t = 0, optionally a new scenario/seed
                                             (a new seed draws new noise and a
                                             scenario's [conditions] again; the unit
                                             stays the same brake)

The sample rate is the scenario's. The stepper takes whole physics substeps per sample,
re-picked from the step limit at every model change and for any accepted actuation force
above the one the limit was computed for; /diagnostics says which step it uses.

Every header stamp is simulated time (sample index x sample period), frame
``brake_backing_plate``.
Timers run on the steady wall clock, whatever ``use_sim_time`` says. Parameters: see
:mod:`.parameters`; command semantics: :mod:`.commands`; pacing: :mod:`.pacing`.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import sys
import time
from collections.abc import Callable, Iterable

from brake_sim_msgs.msg import (
    ActuationCommand,
    DriveCommand,
)
from brake_sim_msgs.srv import ResetSimulation, StepSimulation
from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import Clock, ClockType
from rclpy.exceptions import ParameterException
from rclpy.node import Node
from rclpy.parameter import Parameter

from brake_sim_ros import stream
from brake_sim_ros.analysis.contact_events import ContactEventDetector
from brake_sim_ros.errors import BrakeSimError, ParameterError, ScenarioError
from brake_sim_ros.model.sensors import SensorBank
from brake_sim_ros.model.trajectory import BrakeSetup, SampleBlock
from brake_sim_ros.ros import qos
from brake_sim_ros.ros.budget import measure_publishing, measure_stepping
from brake_sim_ros.ros.commands import (
    ActuationPlanner,
    CommandPolicy,
    TimeoutBehaviour,
    check_command,
    describe_drive,
    drive_command,
)
from brake_sim_ros.ros.descriptors import descriptor
from brake_sim_ros.ros.diagnostics import RunStats, RunView, diagnostic_array, summary
from brake_sim_ros.ros.messages import message_class
from brake_sim_ros.ros.pacing import Pacer, PacingMode
from brake_sim_ros.scenarios import Scenario, load_scenario
from brake_sim_ros.scenarios.requested import allowed_dirs, load_requested_scenario
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.solvers.realtime import (
    PipelineCosts,
    RealtimeVerdict,
    check_chunk_work,
    check_pipeline,
)
from brake_sim_ros.stream import MessageSink, Topic, conversion
from brake_sim_ros.stream import parameters as ros_params
from brake_sim_ros.stream.build import require_measured, sensor_bank_for, stepper_for
from brake_sim_ros.stream.ground_truth import TruthUpdates, recorded_wear, state_wear

NODE_NAME = "brake_sim"
MAX_LAG_S = 0.5  # wall seconds of backlog that are caught up (see pacing)
AFAP_TICK_BUDGET_S = 0.02  # wall time per tick as fast as possible (stays responsive)
MAX_STEP_REQUEST_S = 60.0  # simulated time one ~/step call may advance
# wall time one ~/step call may hold the executor (stepping and publishing, measured costs)
STEP_CALL_WALL_S = 0.5
# parameters rclpy declares or reads for any node: never "unknown"
_ROS_PARAMETER_PREFIXES = ("qos_overrides.",)
_SHOWN_CHARS = 64  # at most this much of a caller's text is echoed back


class BrakeSimNode(Node):
    """Steps the brake model on a wall-clock timer and publishes what it produces.

    Args:
        node_name: ROS node name.
        sink_openers: called with the node once it is set up, before its first message;
            each returns a sink that then receives everything (a recorder). One that
            raises BrakeSimError is reported and the node runs on without it.
        **kwargs: forwarded to :class:`rclpy.node.Node` (context, parameter_overrides, ...).

    Raises:
        BrakeSimError: at start-up, for a scenario that cannot be loaded, invalid
            parameter overrides, or a pathological step limit (StepSizeError). The
            message is one line, fit to show the user.
    """

    def __init__(
        self,
        node_name: str = NODE_NAME,
        *,
        sink_openers: Iterable[Callable[[BrakeSimNode], MessageSink]] = (),
        **kwargs,
    ) -> None:
        super().__init__(node_name, **kwargs)
        self.done = False  # set when exit_at_end and the run ended
        self.stats = RunStats()
        self._internal_update = False
        self._failure = ""
        self._finished = False
        self._wall = time.monotonic
        self._steady = Clock(clock_type=ClockType.STEADY_TIME)

        # -- parameters and the model they describe ---------------------------------------
        self._run_specs = {s.name: s for s in ros_params.run_parameter_specs()}
        self._declare(self._run_specs.values())
        try:  # fixed at start: where ~/reset requests may read scenario files
            self._scenario_dirs = allowed_dirs([self._param("scenario_dirs")])
        except ScenarioError as exc:
            raise ParameterError(str(exc)) from None
        # the operator's choice (command line or parameter): any file, not a request
        self._unit_id = self._param("unit_id")  # "" = each scenario's own
        self.scenario: Scenario = self._as_unit(load_scenario(self._param("scenario")))
        self._seed = self.scenario.seed
        # the run id of the ground truth: the parameter's, or a fresh one per run (reset)
        self._run_id_fixed = ros_params.check_run_id(self._param("run_id"))
        self.run_id = self._run_id_fixed or conversion.new_run_id()
        self._duration_explicit = self._param("duration_s") > 0.0
        self._max_force_explicit = self._param("max_actuation_force_n") > 0.0
        self._model_names = self._declare_model(self.scenario)
        self._refuse_unknown_overrides()
        # the scenario's values and any --ros-args overrides, checked by the core here
        values = self._model_values()
        scenario_values = ros_params.model_values(
            self.scenario.setup.params, self.scenario.setup.defects
        )
        overridden = {k: v for k, v in values.items() if v != scenario_values[k]}
        implied = {
            k: v
            for k, v in ros_params.complete_actuation_share(overridden).items()
            if k not in overridden
        }
        # a live drive's settings: the scenario's [vehicle], or these parameters when > 0
        self._drive_overrides = {n: self._param(n) for n in ros_params.DRIVE_LIMIT_NAMES}
        setup = ros_params.node_setup(
            self.scenario.setup, {**values, **implied}, self._drive_overrides
        )
        self._stepper = self._make_stepper(setup, self.scenario, self._param("chunk_rate_hz"))
        self._publish_measured = bool(self._param("publish_measured"))
        self._awaited_subscribers = self._measured_subscribers()
        if self._publish_measured:  # asked for what the scenario's plan does not build
            require_measured(self.scenario, "publish_measured true refused")
        # the sensors, their state carried between blocks; new at each reset
        self._measured = self._new_measured_stream()
        self._run_initial_angles = self._initial_angles(setup)
        self._double_names = {
            name
            for name in self._model_names + list(self._run_specs)
            if isinstance(self.get_parameter(name).value, float)
        }
        self._set_internal(
            {
                **implied,
                "duration_s": self._duration_s(),
                "max_actuation_force_n": self._max_force_n(setup),
                **self._drive_values(setup),
            }
        )
        self._exit_at_end = bool(self._param("exit_at_end"))
        self._continuous = bool(self._param("continuous"))
        try:
            policy = self._policy_from_params()
        except ValueError as exc:  # a bad --ros-args override
            raise ParameterError(str(exc)) from None
        self._planner = ActuationPlanner(self._stepper.sample_period_s, policy)
        self._pacer = Pacer(
            self._stepper.sample_period_s,
            real_time_factor=self._param("real_time_factor"),
            paused=self._param("paused"),
            max_lag_s=MAX_LAG_S,
        )
        self._publish_clock = bool(self._param("publish_clock"))
        self._chunk_samples = self._samples_per(self._param("chunk_rate_hz"))
        self._state_stride = self._samples_per(self._param("state_rate_hz"))
        self._costs = self._measure_costs()
        self._observed_sample_cost_s = 0.0  # moving average over whole chunks, s
        self._check_keeps_up()
        # open contact episodes carried between published blocks; reset with the stepper
        self._contact_events = ContactEventDetector()
        self.add_pre_set_parameters_callback(self._pre_set_parameters)
        self.add_on_set_parameters_callback(self._on_set_parameters)

        # -- interfaces ----------------------------------------------------------------------
        # canonical topic -> (publisher, the topic under the name this node resolved)
        self._outputs: dict[Topic, tuple] = {}
        for topic in stream.TOPICS:
            if topic.published and (topic is not stream.MEASURED or self._publish_measured):
                pub = self.create_publisher(
                    message_class(topic.type_name), topic.relative, qos.for_topic(topic)
                )
                self._outputs[topic] = (pub, dataclasses.replace(topic, name=pub.topic_name))
        self._sinks: list[MessageSink] = []
        sub = self.create_subscription(
            ActuationCommand,
            stream.ACTUATION.relative,
            self._on_actuation,
            qos.for_topic(stream.ACTUATION),
        )
        self._actuation_topic = dataclasses.replace(stream.ACTUATION, name=sub.topic_name)
        sub = self.create_subscription(
            DriveCommand, stream.DRIVE.relative, self._on_drive, qos.for_topic(stream.DRIVE)
        )
        self._drive_topic = dataclasses.replace(stream.DRIVE, name=sub.topic_name)
        self.create_service(StepSimulation, "~/step", self._on_step)
        self.create_service(ResetSimulation, "~/reset", self._on_reset)
        self._tick_timer = self.create_timer(
            self._tick_period_s(), self._on_tick, clock=self._steady
        )
        self._diag_timer = self.create_timer(
            self._param("diagnostics_period_s"), self._on_diagnostics, clock=self._steady
        )

        now = self._wall()
        self._pacer.restart(now, 0)
        self._last_run_tick: float | None = now
        self._ticking = False
        self._diag_last = (now, 0, 0)  # wall, samples_done, deadline misses
        self._measured_rtf = 0.0
        for open_sink in sink_openers:
            try:
                self.add_sink(open_sink(self))
            except BrakeSimError as exc:
                self.stats.sink_failures += 1
                self.get_logger().error(f"{exc}; the node runs on without it")
        self._truth = TruthUpdates(self._stepper.setup.defects)
        self._publish_defects()
        if self._publish_clock:
            self._emit(stream.CLOCK, conversion.clock(0), 0)
        self._substeps_logged = self._stepper.substeps
        self.get_logger().info(
            f"run {self.run_id}, scenario '{self.scenario.name}' ({self.scenario.source}):"
            f" {self._stepper.describe_step()}; max_actuation_force_n"
            f" {self._param('max_actuation_force_n'):g} N, duration {self._duration_s():g} s,"
            f" {self._chunk_samples} samples per chunk"
            + (
                f"; waiting for {self._awaited_subscribers} ~/measured subscriber(s)"
                if self._awaited_subscribers
                else ""
            )
        )

    @property
    def stepper(self) -> FixedStepStepper:
        """The stepper in use (read it; the node alone advances and changes it)."""
        return self._stepper

    def _measure_costs(self) -> PipelineCosts:
        """Stepping and publishing costs on this machine, measured now (some ms).

        Stepping: a calibration of the stepper at max_actuation_force_n (at the substeps that
        force needs; :func:`~brake_sim_ros.ros.budget.measure_stepping` also refuses chunks
        too large for one callback). Publishing: on hidden publishers, no subscriber.
        """
        costs = self._step_costs(self._stepper, self.scenario.name, self._chunk_samples, None)
        self.get_logger().info(
            f"measured costs: stepping {1e6 * costs.step_per_sample_s:.2f} us per sample;"
            f" publishing a chunk {1e6 * costs.chunk_fixed_s:.0f} us +"
            f" {1e6 * costs.chunk_per_sample_s:.2f} us per sample, a state row"
            f" {1e6 * costs.state_row_s:.0f} us"
        )
        return costs

    def _step_costs(
        self,
        stepper: FixedStepStepper,
        name: str,
        chunk_samples: int,
        publishing: PipelineCosts | None,
    ) -> PipelineCosts:
        """Calibrate ``stepper``; publishing measured too unless ``publishing`` is given."""
        try:
            per_sample, block = measure_stepping(
                stepper.fresh(),
                chunk_samples,
                force_n=float(self._param("max_actuation_force_n")),
            )
        except BrakeSimError as exc:
            raise BrakeSimError(f"scenario '{name}': {exc}") from None
        if publishing is None:
            return measure_publishing(self, block, per_sample, self._new_sensor_bank())
        return dataclasses.replace(publishing, step_per_sample_s=per_sample)

    def _pipeline_verdict(
        self,
        *,
        costs: PipelineCosts | None = None,
        sample_period_s: float | None = None,
        chunk_samples: int | None = None,
        state_stride: int | None = None,
        real_time_factor: float | None = None,
        label: str | None = None,
    ) -> RealtimeVerdict:
        """The budget check for these settings (the current ones where None)."""
        return check_pipeline(
            costs or self._costs,
            sample_period_s=sample_period_s or self._stepper.sample_period_s,
            chunk_samples=chunk_samples or self._chunk_samples,
            state_stride=state_stride or self._state_stride,
            real_time_factor=(
                self._pacer.real_time_factor if real_time_factor is None else real_time_factor
            ),
            label=label or f"scenario '{self.scenario.name}'",
        )

    def _check_keeps_up(self) -> None:
        """Refuse to start when this machine cannot step and publish the chunks in real time.

        The figures are measured at start (:meth:`_measure_costs`); the budget logic is
        :func:`brake_sim_ros.solvers.realtime.check_pipeline`.
        """
        if self._pacer.real_time_factor == 0.0:
            return  # as fast as possible: nothing to keep up with
        verdict = self._pipeline_verdict()
        if not verdict.ok:
            raise BrakeSimError(
                f"cannot keep real time: {verdict.message} (real_time_factor:=0.0 runs as"
                " fast as possible)"
            )
        self.get_logger().info(f"real-time check: {verdict.message}")

    def _rates_refusal(self, changes: dict) -> str | None:
        """Why new chunk/state rates or real-time factor cannot be held, or None."""
        chunk = self._samples_per(changes.get("chunk_rate_hz", self._param("chunk_rate_hz")))
        stride = self._samples_per(changes.get("state_rate_hz", self._param("state_rate_hz")))
        factor = changes.get("real_time_factor", self._pacer.real_time_factor)
        work = check_chunk_work(self._stepper.substeps, chunk, self._stepper.physics_step_s)
        if work:
            return work
        if factor == 0.0:
            return None
        verdict = self._pipeline_verdict(
            chunk_samples=chunk, state_stride=stride, real_time_factor=factor
        )
        return None if verdict.ok else f"cannot keep real time: {verdict.message}"

    def _step_sample_cost_s(self) -> float:
        """Wall cost of one sample, stepped and published: the larger of the start-up
        estimate (no subscriber) and what whole chunks have cost so far (with the real
        subscribers, contact events and sinks)."""
        estimate = self._costs.per_sample_s(self._chunk_samples, self._state_stride)
        return max(estimate, self._observed_sample_cost_s)

    def _max_step_samples(self) -> int:
        """Most samples one ~/step call may advance: STEP_CALL_WALL_S of measured work (at
        least one chunk), at most MAX_STEP_REQUEST_S of simulated time."""
        per_sample = self._step_sample_cost_s()
        by_wall = max(self._chunk_samples, int(STEP_CALL_WALL_S / per_sample))
        return min(by_wall, math.floor(MAX_STEP_REQUEST_S / self._stepper.sample_period_s))

    # -- parameter plumbing ----------------------------------------------------------------------
    def _param(self, name: str):
        return self.get_parameter(name).value

    def _unknown_reason(self, names: list[str]) -> str:
        """One line naming unknown parameters and the closest known names."""
        known = list(self._parameters)
        parts = []
        for name in names:
            shown = name if len(name) <= _SHOWN_CHARS else name[:_SHOWN_CHARS] + "..."
            close = difflib.get_close_matches(name, known, n=3)
            hint = f" (did you mean {', '.join(close)}?)" if close else ""
            parts.append(f"{shown!r}{hint}")
        return (
            f"unknown parameter {'; '.join(parts)}: not declared by this node"
            " (ros2 param list shows those it has)"
        )

    def _refuse_unknown_overrides(self) -> None:
        """A ``--ros-args -p`` name this node does not declare is a typo: refuse to start.

        rclpy keeps the overrides it was given (``/**`` ones too) in ``_parameter_overrides``
        and ignores undeclared ones silently; there is no public accessor.
        """
        unknown = sorted(
            name
            for name in getattr(self, "_parameter_overrides", {})
            if not self.has_parameter(name) and not name.startswith(_ROS_PARAMETER_PREFIXES)
        )
        if unknown:
            raise ParameterError(f"--ros-args override refused: {self._unknown_reason(unknown)}")

    def _declare_model(self, scenario: Scenario) -> list[str]:
        specs = ros_params.model_parameter_specs(scenario.setup.params, scenario.setup.defects)
        self._declare(specs)
        return [spec.name for spec in specs]

    def _declare(self, specs) -> None:
        for spec in specs:
            try:
                self.declare_parameter(spec.name, spec.default, descriptor(spec))
            except ParameterException as exc:  # a bad --ros-args override
                raise ParameterError(f"--ros-args override refused: {exc}") from None

    def _model_values(self, changes: dict | None = None) -> dict:
        values = {name: self._param(name) for name in self._model_names}
        values.update(changes or {})
        return values

    def _set_internal(self, values: dict) -> None:
        """Set parameters from inside the node (not validated again, not counted)."""
        self._internal_update = True
        try:
            self.set_parameters([Parameter(k, value=v) for k, v in values.items()])
        finally:
            self._internal_update = False

    @staticmethod
    def _make_stepper(
        setup: BrakeSetup, scenario: Scenario, chunk_rate_hz: float
    ) -> FixedStepStepper:
        """The scenario's stepper (:func:`stepper_for`) for ``setup`` (its values with any
        ROS parameter overrides), refused when one chunk would be too much work."""
        stepper = stepper_for(scenario, setup=setup)
        chunk = max(1, round(1.0 / (stepper.sample_period_s * chunk_rate_hz)))
        reason = check_chunk_work(stepper.substeps, chunk, stepper.physics_step_s)
        if reason:
            raise BrakeSimError(f"scenario '{scenario.name}': {reason}")
        stepper.advance(0)  # loads the compiled kernel now (ms), not during the first chunk
        return stepper

    def _new_sensor_bank(self) -> SensorBank | None:
        """The scenario's sensors from sample 0, seeded with the run's seed (None when
        publish_measured is off; it is refused on a scenario whose plan has no sensors),
        as the offline stream builds them."""
        if not self._publish_measured:
            return None
        return sensor_bank_for(self.scenario, seed=self._seed)

    def _new_measured_stream(self) -> stream.MeasuredStream | None:
        """The scenario's sensors (:meth:`_new_sensor_bank`) cut into ~/measured chunks of
        measured_rate_hz; None when publish_measured is off."""
        bank = self._new_sensor_bank()
        if bank is None:
            return None
        return stream.MeasuredStream(bank, self._samples_per(self._param("measured_rate_hz")))

    def _flush_measured(self) -> None:
        """Publish the measured samples still pending (:class:`~brake_sim_ros.stream.
        MeasuredStream`): the stream stops here, for now or for good."""
        if self._measured is None:
            return
        try:
            messages = list(self._measured.flush())
        except Exception as exc:  # the sensors' failure must not stop the node
            self.get_logger().error(f"measured samples lost: {type(exc).__name__}: {exc}")
            return
        for topic, msg, ns in messages:
            self._emit(topic, msg, ns)

    @staticmethod
    def _drive_values(setup: BrakeSetup) -> dict[str, float]:
        """The live-drive parameters as in force for ``setup``: its vehicle's settings, or
        0 for a run that takes no live drive."""
        drives = setup.vehicle is not None and setup.cycle is None
        return {
            name: float(getattr(setup.vehicle, name)) if drives else 0.0
            for name in ros_params.DRIVE_LIMIT_NAMES
        }

    def _max_force_n(self, setup: BrakeSetup) -> float:
        """max_actuation_force_n: as set at start-up, or 2 x the scenario's peak."""
        if self._max_force_explicit:
            return float(self._param("max_actuation_force_n"))
        return ros_params.auto_max_actuation_force(setup)

    def _log_step_change(self, why: str) -> None:
        """Say so when the stepper picked other substeps (a model change, a large force)."""
        if self._stepper.substeps != self._substeps_logged:
            self._substeps_logged = self._stepper.substeps
            self.get_logger().info(f"{why}: {self._stepper.describe_step()}")

    @staticmethod
    def _initial_angles(setup: BrakeSetup) -> tuple[float, float]:
        return (setup.defects.left.initial_angle_deg, setup.defects.right.initial_angle_deg)

    def _policy_from_params(self, changes: dict | None = None) -> CommandPolicy:
        values = {
            name: self._param(name)
            for name in ("command_timeout_s", "on_command_timeout", "command_ramp_rate_n_per_s")
        }
        values.update(changes or {})
        return CommandPolicy(
            timeout_s=values["command_timeout_s"],
            behaviour=TimeoutBehaviour.parse(values["on_command_timeout"]),
            ramp_rate_n_per_s=values["command_ramp_rate_n_per_s"],
        )

    def _duration_s(self) -> float:
        value = self._param("duration_s")
        return value if value > 0.0 else self.scenario.duration_s

    def _end_step(self) -> int:
        """The sample index at which the free run ends (never, while ``continuous``)."""
        if self._continuous:
            return sys.maxsize
        return round(self._duration_s() / self._stepper.sample_period_s)

    def _sample_rate_hz(self) -> float:
        return conversion.sample_rate_hz(self._stepper.sample_period_s)

    def _samples_per(self, rate_hz: float) -> int:
        return stream.samples_per(rate_hz, self._stepper.sample_period_s)

    def _tick_period_s(self) -> float:
        if self._pacer.mode is PacingMode.REAL_TIME:
            half_chunk = 0.5 * self._pacer.chunk_wall_period_s(self._chunk_samples)
            return min(0.01, max(0.001, half_chunk))
        return 0.001 if self._pacer.mode is PacingMode.AS_FAST_AS_POSSIBLE else 0.01

    def _max_chunks_per_tick(self) -> int:
        if self._pacer.mode is not PacingMode.REAL_TIME:
            return 64
        per_tick = self._tick_period_s() / self._pacer.chunk_wall_period_s(self._chunk_samples)
        return max(2, 4 * math.ceil(per_tick))

    def set_parameters_atomically(self, parameter_list):
        """Count every refused external change (descriptor checks included)."""
        unknown = [p.name for p in parameter_list if not self.has_parameter(p.name)]
        if unknown:  # rclpy would raise, with an empty list in the message
            reason = self._unknown_reason(unknown)
            self._count_parameter_result(False, reason)
            return SetParametersResult(successful=False, reason=reason)
        result = super().set_parameters_atomically(parameter_list)
        self._count_parameter_result(result.successful, result.reason)
        return result

    def _count_parameter_result(self, ok: bool, reason: str) -> None:
        if self._internal_update:
            return
        if ok:
            self.stats.parameter_changes_accepted += 1
        else:
            self.stats.parameter_changes_refused += 1
            self.stats.last_parameter_refusal = reason
            self.get_logger().warning(
                f"parameter change refused: {reason}", throttle_duration_sec=1.0
            )

    def _pre_set_parameters(self, parameters: list[Parameter]) -> list[Parameter]:
        """Accept integers for double parameters; complete a lone actuation-share change."""
        if self._internal_update:
            return parameters
        out = []
        for p in parameters:
            if p.name in self._double_names and p.type_ is Parameter.Type.INTEGER:
                p = Parameter(p.name, Parameter.Type.DOUBLE, float(p.value))
            out.append(p)
        changes = {p.name: p.value for p in out}
        for name, value in ros_params.complete_actuation_share(changes).items():
            if name not in changes:
                out.append(Parameter(name, Parameter.Type.DOUBLE, float(value)))
        return out

    def _on_set_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        """Validate a change as a whole through the core; apply it only if all of it is valid."""
        if self._internal_update:
            return SetParametersResult(successful=True)
        changes = {p.name: p.value for p in parameters}
        for name in changes.keys() & ros_params.FIXED_AT_START:
            hint = (
                " (switch scenarios with the ~/reset service)"
                if name == "scenario"
                else " (restart the node to change it)"
            )
            return SetParametersResult(
                successful=False, reason=f"{name} is fixed at start-up{hint}"
            )
        try:
            policy = self._policy_from_params(changes)
        except ValueError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        if "duration_s" in changes and not changes["duration_s"] > 0.0:
            return SetParametersResult(
                successful=False, reason="duration_s must be > 0 s at run time"
            )
        if changes.keys() & {"chunk_rate_hz", "state_rate_hz", "real_time_factor"}:
            reason = self._rates_refusal(changes)
            if reason:
                return SetParametersResult(successful=False, reason=reason)
        model_changes = {k: v for k, v in changes.items() if k in self._model_names}
        if model_changes:
            old_setup = self._stepper.setup
            try:
                setup = ros_params.changed_setup(old_setup, self._model_values(model_changes))
                self._stepper.replace_setup(setup)  # validates, or changes nothing
            except BrakeSimError as exc:
                return SetParametersResult(successful=False, reason=str(exc))
            work = check_chunk_work(
                self._stepper.substeps, self._chunk_samples, self._stepper.physics_step_s
            )
            if work:
                self._stepper.replace_setup(old_setup)
                return SetParametersResult(successful=False, reason=work)
            self._log_step_change("new model parameters")
        self._apply_run_changes(changes, policy)
        self._record_change(changes)
        if model_changes:
            self._publish_defects()
            pending = sorted(model_changes.keys() & ros_params.INITIAL_CONDITIONS)
            if pending:
                self.get_logger().info(
                    f"{', '.join(pending)}: initial condition, applies at the next ~/reset"
                )
        return SetParametersResult(successful=True)

    def _apply_run_changes(self, changes: dict, policy: CommandPolicy) -> None:
        now = self._wall()
        step = self._stepper.sample_index
        self._account_free_run(now)
        self._planner.policy = policy
        if "real_time_factor" in changes:
            self._pacer.set_real_time_factor(changes["real_time_factor"], now, step)
        if "paused" in changes:
            self._pacer.set_paused(changes["paused"], now, step)
            if changes["paused"]:
                self._flush_measured()
        if "chunk_rate_hz" in changes:
            self._chunk_samples = self._samples_per(changes["chunk_rate_hz"])
        if "state_rate_hz" in changes:
            self._state_stride = self._samples_per(changes["state_rate_hz"])
        if "publish_clock" in changes:
            self._publish_clock = bool(changes["publish_clock"])
        if "diagnostics_period_s" in changes:
            self._diag_timer.timer_period_ns = int(changes["diagnostics_period_s"] * 1e9)
        if "duration_s" in changes:
            self._duration_explicit = True
            if (
                self._finished
                and round(changes["duration_s"] / self._stepper.sample_period_s) > step
            ):
                self._finished = False
                self._pacer.restart(now, step)
        if "continuous" in changes:
            self._continuous = bool(changes["continuous"])
        if self._continuous and self._finished:
            self._finished = False
            self._pacer.restart(now, step)
        if changes.keys() & {"real_time_factor", "paused", "chunk_rate_hz"}:
            self._tick_timer.timer_period_ns = int(self._tick_period_s() * 1e9)

    # -- commands ----------------------------------------------------------------------------------
    def _on_actuation(self, msg: ActuationCommand) -> None:
        reason = check_command(
            msg.left_force_n, msg.right_force_n, float(self._param("max_actuation_force_n"))
        )
        if reason is None and self._stepper.setup.cycle is not None:
            reason = (
                f"scenario '{self.scenario.name}' has a drive cycle ([cycle]), which commands"
                " the brake: actuation commands are allowed only without one"
            )
        if reason is not None:
            self.stats.commands_rejected += 1
            self.stats.last_command_rejection = reason
            self.get_logger().warning(
                f"actuation command rejected: {reason}", throttle_duration_sec=1.0
            )
            return
        self.stats.commands_accepted += 1
        if self._failure or (self._finished and not self._pacer.paused):
            self.stats.commands_dropped += 1  # no physics will run to use it
            return
        forces = (msg.left_force_n, msg.right_force_n)
        if self._planner.command(forces, self._stepper.sample_index):
            self.stats.commands_dropped += 1
        self._record_command(self._actuation_topic, msg)

    def _on_drive(self, msg: DriveCommand) -> None:
        """A drive command: from the next sample on, until the next one or a reset."""
        drive, reason = drive_command(msg.mode, msg.drive_torque_n_m, msg.target_speed_m_s)
        if reason is None:
            refusal = self._stepper.drive_refusal(drive)
            if refusal is not None:
                reason = f"scenario '{self.scenario.name}': {refusal}"
        if reason is not None:
            self.stats.drive_commands_rejected += 1
            self.stats.last_drive_rejection = reason
            self.get_logger().warning(
                f"drive command rejected: {reason}", throttle_duration_sec=1.0
            )
            return
        self.stats.drive_commands_accepted += 1
        if self._failure or (self._finished and not self._pacer.paused):
            self.stats.drive_commands_dropped += 1  # no physics will run to use it
            return
        self._stepper.drive(drive)
        self._record_command(self._drive_topic, msg)

    def _record_change(self, changes: dict) -> None:
        """Hand an accepted parameter change to the sinks that record changes (a
        recording: ``parameter_change``), at the sample it takes effect at (the next)."""
        index = self._stepper.sample_index
        ns = conversion.stamp_ns(index, self._stepper.sample_period_s)
        for sink in list(self._sinks):
            note = getattr(sink, "parameter_change", None)
            if note is None:
                continue
            try:
                note(changes, index, ns)
            except Exception as exc:  # a sink's failure must not stop the simulation
                self._drop_sink(sink, f"{type(exc).__name__}: {exc}")

    def _record_command(self, topic: Topic, msg) -> None:
        """Hand a command that takes effect to the sinks, stamped with the sample it takes
        effect at (the next one: the stepper's sample index), so that a recording can be
        re-simulated (brake-sim resim): a command is applied at that sample and holds
        until a later one. A command replaced before its sample (two in one chunk) is
        recorded at the same sample, before the one that replaced it."""
        ns = conversion.stamp_ns(self._stepper.sample_index, self._stepper.sample_period_s)
        self._to_sinks(topic, msg, ns)

    # -- stepping and publishing --------------------------------------------------------------
    def _measured_subscribers(self) -> int:
        """The ``measured_subscribers`` parameter, checked (ParameterError otherwise)."""
        n = int(self._param("measured_subscribers"))
        if not 0 <= n <= 64:
            raise ParameterError(f"measured_subscribers={n}: allowed 0 to 64 subscribers")
        if n and not self._publish_measured:
            raise ParameterError(
                f"measured_subscribers={n} without publish_measured: allowed 0 (there is no"
                " ~/measured to wait for), or set publish_measured:=true"
            )
        return n

    def _waiting_for_subscribers(self) -> bool:
        """True while ~/measured has fewer subscribers than ``measured_subscribers``: the
        first sample waits, so no subscriber misses the run's start."""
        if not self._awaited_subscribers:
            return False
        count = self._outputs[stream.MEASURED][0].get_subscription_count()
        if count < self._awaited_subscribers:
            return True
        self.get_logger().info(f"~/measured has {count} subscriber(s): the run starts")
        self._awaited_subscribers = 0
        return False

    def _on_tick(self) -> None:
        if self._failure or self._finished or self._waiting_for_subscribers():
            return
        now = self._wall()
        if not self._ticking:  # pace from the first tick: start-up costs are not lateness
            self._ticking = True
            self._pacer.restart(now, self._stepper.sample_index)
            self._last_run_tick = now
        mode = self._pacer.mode
        if mode is PacingMode.PAUSED:
            return
        end = self._end_step()
        self._account_free_run(now)
        if mode is PacingMode.AS_FAST_AS_POSSIBLE:
            while self._stepper.sample_index < end and self._wall() - now < AFAP_TICK_BUDGET_S:
                n = min(self._chunk_samples, end - self._stepper.sample_index)
                if not self._advance_and_publish(n, free_run=True):
                    return
        else:
            plan = self._pacer.plan(
                now,
                self._stepper.sample_index,
                self._chunk_samples,
                self._max_chunks_per_tick(),
                end,
            )
            if plan.slipped_steps:
                self.stats.slips += 1
                self.stats.slipped_s += plan.slipped_steps * self._stepper.sample_period_s
            # a chunk is late when published more than a chunk period after its last sample
            # was due, or two ticks (what tick granularity alone costs at high factors)
            tolerance = max(
                self._pacer.chunk_wall_period_s(self._chunk_samples), 2.0 * self._tick_period_s()
            )
            remaining = plan.steps
            while remaining > 0:
                n = min(self._chunk_samples, remaining)
                if not self._advance_and_publish(n, free_run=True):
                    return
                remaining -= n
                late = self._wall() - self._pacer.deadline_s(self._stepper.sample_index)
                if late > tolerance:
                    self.stats.deadline_misses += 1
        if self._stepper.sample_index >= end:
            self._finish()

    def _account_free_run(self, now: float) -> None:
        """Add the wall time since the last accounting to the free run's, if it was running."""
        running = not (self._failure or self._finished or self._pacer.paused)
        if running and self._last_run_tick is not None:
            self.stats.free_run_wall_s += now - self._last_run_tick
        self._last_run_tick = now

    def _advance_and_publish(self, n_steps: int, *, free_run: bool) -> bool:
        """Take ``n_steps`` samples (at most one chunk) and publish them. False on failure."""
        wall0 = self._wall()
        step0 = self._stepper.sample_index
        blocks = []
        try:
            for count, forces in self._planner.segments(step0, n_steps):
                blocks.append(self._stepper.advance(count, actuation_n=forces))
                self.stats.physics_steps_done += count * self._stepper.substeps
        except BrakeSimError as exc:
            self._fail(str(exc))
            return False
        self._log_step_change("actuation above the force of the step limit")
        block = blocks[0] if len(blocks) == 1 else SampleBlock.concatenate(blocks)
        self.stats.samples_done += n_steps
        if free_run:
            self.stats.free_run_sim_s += n_steps * self._stepper.sample_period_s
        if len(block) != n_steps or not conversion.all_finite(block):
            self._fail(
                f"non-finite or missing samples between samples {step0} and"
                f" {step0 + n_steps}; nothing of them was published"
            )
            return False
        self._publish_block(block)
        if n_steps == self._chunk_samples:  # whole chunks: the cost ~/step bounds use
            cost = (self._wall() - wall0) / n_steps
            previous = self._observed_sample_cost_s or cost
            self._observed_sample_cost_s = 0.8 * previous + 0.2 * cost
        return True

    def _publish_block(self, block: SampleBlock) -> None:
        states = 0
        for row in self._truth.due_rows(block.time_s, recorded_wear(block)):
            self._publish_defects(block.first_index + row, recorded_wear(block, row))
        messages = stream.block_messages(
            block,
            self._state_stride,
            with_clock=self._publish_clock,
            contact_events=self._contact_events,
            run_id=self.run_id,
            measured=self._measured,
        )
        for topic, msg, ns in messages:
            self._emit(topic, msg, ns)
            states += topic is stream.STATE
        self.stats.samples_published += len(block)
        self.stats.chunks_published += 1
        self.stats.states_published += states

    def _emit(self, topic: Topic, msg, ns: int) -> None:
        """Publish ``msg`` on ``topic`` and hand it to every sink, at simulated time ``ns``.

        A publisher that raises costs that message, counted in ``publish_failures``; a
        chunk published while nothing subscribes is counted in ``chunks_unheard``.
        """
        pub, resolved = self._outputs[topic]
        try:
            if topic is stream.PIVOT_FORCES and pub.get_subscription_count() == 0:
                self.stats.chunks_unheard += 1
            pub.publish(msg)
        except Exception as exc:  # the simulation and the sinks go on without it
            self.stats.publish_failures += 1
            self.get_logger().error(
                f"publishing on {resolved.name} failed: {type(exc).__name__}",
                throttle_duration_sec=1.0,
            )
        self._to_sinks(resolved, msg, ns)

    def _to_sinks(self, topic: Topic, msg, ns: int) -> None:
        for sink in list(self._sinks):
            try:
                sink.write(topic, msg, ns)
            except Exception as exc:  # a sink's failure must not stop the simulation
                self._drop_sink(sink, f"{type(exc).__name__}: {exc}")

    def add_sink(self, sink: MessageSink) -> None:
        """Receive every message from now on (what is published and accepted commands)."""
        self._sinks.append(sink)

    def _drop_sink(self, sink: MessageSink, reason: str) -> None:
        self._sinks.remove(sink)
        self.stats.sink_failures += 1
        self.get_logger().error(f"{sink!r} stopped: {reason}; the simulation goes on")
        try:
            sink.close()
        except Exception as exc:
            self.get_logger().error(f"{sink!r} could not be closed: {exc}")

    def close_sinks(self) -> None:
        """Close every sink (flushes recordings); each failure is logged, none is raised.
        Measured samples still pending are published first."""
        self._flush_measured()
        for sink in list(self._sinks):
            self._sinks.remove(sink)
            try:
                sink.close()
            except Exception as exc:
                self.stats.sink_failures += 1
                self.get_logger().error(f"{sink!r} could not be closed: {exc}")

    def _fail(self, message: str) -> None:
        self._flush_measured()  # the samples published before the failure
        self._failure = message
        self.get_logger().error(f"simulation stopped: {message}")

    def _finish(self) -> None:
        self._flush_measured()
        if not self._finished:
            self._account_free_run(self._wall())
            self._finished = True
            self.get_logger().info(f"reached duration_s = {self._duration_s():g} s")
        if self._exit_at_end:
            self.done = True

    # -- services -------------------------------------------------------------------------------
    def _on_step(
        self, request: StepSimulation.Request, response: StepSimulation.Response
    ) -> StepSimulation.Response:
        dt = self._stepper.sample_period_s
        steps, duration = int(request.steps), float(request.duration_s)
        error = ""
        if not self._pacer.paused:
            error = "the simulation is running: set the parameter paused to true first"
        elif self._failure:
            error = f"the simulation failed ({self._failure}); call ~/reset"
        elif (steps == 0) == (duration == 0.0):
            error = "give either steps or duration_s (the other 0)"
        elif not (math.isfinite(duration) and duration >= 0.0):
            error = f"duration_s={duration!r}: allowed a finite time >= 0 s"
        else:
            steps = steps or round(duration / dt)
            most = self._max_step_samples()
            if steps < 1:
                error = f"duration_s={duration:g} s is shorter than half a sample ({dt:g} s)"
            elif steps > most:
                per_sample = self._step_sample_cost_s()
                error = (
                    f"{steps} samples = {steps * dt:g} s: allowed at most {most} samples ="
                    f" {most * dt:g} s per call (one call may hold the node for"
                    f" {STEP_CALL_WALL_S:g} s of wall time, a sample costs"
                    f" {1e6 * per_sample:.1f} us here, and at most {MAX_STEP_REQUEST_S:g} s"
                    " of simulated time); call ~/step again for more"
                )
        wall0 = self._wall()
        if not error:
            done = 0
            while done < steps:
                n = min(self._chunk_samples, steps - done)
                if not self._advance_and_publish(n, free_run=False):
                    error = f"the simulation failed: {self._failure}"
                    break
                done += n
            self._flush_measured()  # ~/measured holds every sample this call stepped
        response.success = not error
        index = self._stepper.sample_index
        response.message = error or (
            f"advanced {steps} samples to t = {index * dt:.9g} s in"
            f" {self._wall() - wall0:.3f} s of wall time"
        )
        response.sample_index = max(0, index - 1)
        response.sim_time_s = index * dt
        return response

    def _on_reset(
        self, request: ResetSimulation.Request, response: ResetSimulation.Response
    ) -> ResetSimulation.Response:
        seed = int(request.seed)
        try:
            if seed < -1:
                raise BrakeSimError(f"seed={seed}: allowed -1 (keep) or a seed >= 0")
            if request.scenario:
                scenario = load_requested_scenario(request.scenario, self._scenario_dirs)
                scenario = self._as_unit(scenario, seed=seed if seed >= 0 else None)
                self._switch_scenario(scenario, request.scenario)
            elif seed >= 0 and seed != self.scenario.seed and self.scenario.drawn:
                # the seed draws the operating conditions: a new seed, another setup
                scenario = self.scenario.with_unit(seed=seed)
                self._switch_scenario(scenario, self._param("scenario"))
            else:
                self._stepper.reset()
                self._log_step_change("reset")
        except BrakeSimError as exc:
            response.success, response.message = False, f"reset refused: {exc}"
            return response
        except Exception as exc:  # a bug, not the request: the node must run on
            self.get_logger().error(f"~/reset failed: {type(exc).__name__}")
            response.success = False
            response.message = f"reset refused: internal error ({type(exc).__name__})"
            return response
        self._contact_events.reset()
        self.run_id = self._run_id_fixed or conversion.new_run_id()
        if seed >= 0:
            self._seed = seed
        self._flush_measured()  # the old run's last samples, before its successor's
        self._measured = self._new_measured_stream()
        if self._planner.clear():
            self.stats.commands_dropped += 1
        now = self._wall()
        self._account_free_run(now)
        self._failure = ""
        self._finished = False
        self._run_initial_angles = self._initial_angles(self._stepper.setup)
        self._pacer.restart(now, 0)
        self._publish_defects()
        if self._publish_clock:
            self._emit(stream.CLOCK, conversion.clock(0), 0)
        response.success = True
        response.message = (
            f"reset to t = 0 with scenario '{self.scenario.name}' (seed {self._seed}),"
            f" run id {self.run_id}"
        )
        return response

    def _as_unit(self, scenario: Scenario, *, seed: int | None = None) -> Scenario:
        """``scenario`` as the node's ``unit_id`` parameter's unit (empty: its own), drawn
        with ``seed`` (None: the scenario's)."""
        if not self._unit_id and seed is None:
            return scenario
        return scenario.with_unit(self._unit_id or None, seed=seed)

    def _switch_scenario(self, scenario: Scenario, name_or_path: str) -> None:
        """Replace scenario, stepper and timing; on error nothing changes.

        The new scenario's stepping is calibrated (some ms) and checked against the work
        bounds and, in real time, against the budget (the publishing costs measured at
        start); a scenario the node cannot hold is refused, and so is one whose fidelity
        plan has no sensors while publish_measured is on (its ~/measured would go silent).
        """
        if self._publish_measured:
            require_measured(scenario, "publish_measured is on")
        chunk_rate = self._param("chunk_rate_hz")
        setup = ros_params.with_drive_limits(scenario.setup, self._drive_overrides)
        stepper = self._make_stepper(setup, scenario, chunk_rate)
        dt = stepper.sample_period_s
        chunk = max(1, round(1.0 / (dt * chunk_rate)))
        stride = max(1, round(1.0 / (dt * self._param("state_rate_hz"))))
        costs = self._step_costs(stepper, scenario.name, chunk, self._costs)
        if self._pacer.real_time_factor > 0.0:
            verdict = self._pipeline_verdict(
                costs=costs,
                sample_period_s=dt,
                chunk_samples=chunk,
                state_stride=stride,
                label=f"scenario '{scenario.name}'",
            )
            if not verdict.ok:
                raise BrakeSimError(f"cannot keep real time: {verdict.message}")
        self._costs = costs
        self.scenario, self._stepper, self._seed = scenario, stepper, scenario.seed
        values = ros_params.model_values(scenario.setup.params, scenario.setup.defects)
        values["scenario"] = name_or_path
        values["max_actuation_force_n"] = self._max_force_n(scenario.setup)
        values.update(self._drive_values(setup))
        if not self._duration_explicit:
            values["duration_s"] = scenario.duration_s
        self._set_internal(values)
        self._log_step_change(f"scenario '{scenario.name}'")
        self._planner.sample_period_s = dt
        self._pacer = Pacer(
            dt,
            real_time_factor=self._pacer.real_time_factor,
            paused=self._pacer.paused,
            max_lag_s=MAX_LAG_S,
        )
        self._chunk_samples = self._samples_per(self._param("chunk_rate_hz"))
        self._state_stride = self._samples_per(self._param("state_rate_hz"))
        self._tick_timer.timer_period_ns = int(self._tick_period_s() * 1e9)

    # -- ground truth and diagnostics --------------------------------------------------------
    def _publish_defects(
        self, sample_index: int | None = None, wear_m: dict[str, float] | None = None
    ) -> None:
        """Publish the ground truth at ``sample_index`` (default: the next sample, for the
        start, a reset or a change of the defects; a sample of a block for a growing
        defect, :class:`~brake_sim_ros.stream.ground_truth.TruthUpdates`, with the linings'
        wear recorded there, ``wear_m``; default the stepper's wear state now)."""
        setup = self._stepper.setup
        index = self._stepper.sample_index if sample_index is None else sample_index
        period = self._stepper.sample_period_s
        ns = conversion.stamp_ns(index, period)
        if wear_m is None:
            wear_m = state_wear(self._stepper.state)
        msg = conversion.defect_state(
            scenario=self.scenario.name,
            defects=setup.defects,
            initial_angles_deg=self._run_initial_angles,
            ns=ns,
            run_id=self.run_id,
            seed=self._seed,
            unit_id=self.scenario.unit_id,
            time_s=index * period,
            wear_m=wear_m,
        )
        if sample_index is None:
            self._truth.published(setup.defects, index * period, wear_m)
        self._emit(stream.DEFECTS, msg, ns)

    def run_view(self) -> RunView:
        if self._failure:
            state = "failed"
        elif self._finished:
            state = "finished"
        elif self._pacer.paused:
            state = "paused"
        else:
            state = "running"
        stepper = self._stepper
        step = stepper.sample_index
        return RunView(
            node_name=self.get_name(),
            scenario=self.scenario.name,
            state=state,
            message=self._failure,
            sim_time_s=step * stepper.sample_period_s,
            sample_index=step,
            sample_rate_hz=self._sample_rate_hz(),
            duration_s=self._duration_s(),
            target_real_time_factor=self._pacer.real_time_factor,
            measured_real_time_factor=self._measured_rtf,
            actuation_source=self._planner.source(step),
            drive="none" if stepper.drive_refusal() else describe_drive(stepper.live_drive),
            stop_time_s=stepper.stop_time_s,
            physics_step_s=stepper.physics_step_s,
            substeps=stepper.substeps,
            step_limit_s=stepper.limit.max_step_s,
            step_limit_force_n=stepper.limit_force_n,
            max_actuation_force_n=float(self._param("max_actuation_force_n")),
            seed=self._seed,
            run_id=self.run_id,
        )

    def _on_diagnostics(self) -> None:
        now = self._wall()
        last_wall, last_samples, last_misses = self._diag_last
        if now > last_wall:
            sim = (self.stats.samples_done - last_samples) * self._stepper.sample_period_s
            self._measured_rtf = sim / (now - last_wall)
        new_misses = self.stats.deadline_misses - last_misses
        self._diag_last = (now, self.stats.samples_done, self.stats.deadline_misses)
        ns = conversion.stamp_ns(self._stepper.sample_index, self._stepper.sample_period_s)
        self._emit(
            stream.DIAGNOSTICS,
            diagnostic_array(self.run_view(), self.stats, ns=ns, new_misses=new_misses),
            ns,
        )

    def summary(self) -> str:
        return summary(self.run_view(), self.stats)
