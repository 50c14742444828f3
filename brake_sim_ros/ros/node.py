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
:mod:`brake_sim_ros.stream.run_parameters` and :mod:`.node_parameters`; command semantics:
:mod:`brake_sim_ros.stream.commands`; pacing: :mod:`.pacing`; services:
:mod:`.node_services`.

The run itself (stepping, commands, parameter changes, resets, the ground truth) is the
transport-free :class:`~brake_sim_ros.stream.session.RunSession` that the offline stream
and ``brake-sim resim`` drive too; this class paces it on the wall clock and publishes
what it makes.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Iterable

from brake_sim_msgs.msg import ActuationCommand, DriveCommand
from brake_sim_msgs.srv import ResetSimulation, StepSimulation
from rclpy.clock import Clock, ClockType
from rclpy.node import Node

from brake_sim_ros import stream
from brake_sim_ros.errors import BrakeSimError, ParameterError, ScenarioError, SimulationError
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.ros import qos
from brake_sim_ros.ros.budget import Budget
from brake_sim_ros.ros.diagnostics import RunStats, summary
from brake_sim_ros.ros.node_parameters import NodeParameters
from brake_sim_ros.ros.node_services import MAX_LAG_S, NodeServices
from brake_sim_ros.ros.node_timing import NodeTiming
from brake_sim_ros.ros.outputs import NodeOutputs
from brake_sim_ros.ros.pacing import Pacer
from brake_sim_ros.scenarios import Scenario, load_scenario
from brake_sim_ros.scenarios.requested import allowed_dirs
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.stream import MessageSink, Topic, conversion, run_parameters
from brake_sim_ros.stream import parameters as ros_params
from brake_sim_ros.stream.build import require_measured
from brake_sim_ros.stream.commands import drive_command
from brake_sim_ros.stream.session import RunSession

NODE_NAME = "brake_sim"
MAX_STEP_REQUEST_S = 60.0  # simulated time one ~/step call may advance
# wall time one ~/step call may hold the executor (stepping and publishing, measured costs)
STEP_CALL_WALL_S = 0.5


class BrakeSimNode(NodeParameters, NodeServices, NodeTiming, Node):
    """Paces a :class:`~brake_sim_ros.stream.session.RunSession` on a wall-clock timer
    and publishes what it makes.

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
        self._failure = ""
        self._finished = False
        self._wall = time.monotonic
        self._steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.session = self._start_session()
        session = self.session
        self._pacer = Pacer(
            session.period_s,
            real_time_factor=self._param("real_time_factor"),
            paused=self._param("paused"),
            max_lag_s=MAX_LAG_S,
        )
        self._budget = Budget(
            self._measure_costs(),
            step_call_wall_s=STEP_CALL_WALL_S,
            max_step_request_s=MAX_STEP_REQUEST_S,
        )
        self._check_keeps_up()
        self.add_pre_set_parameters_callback(self._pre_set_parameters)
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self._create_interfaces()
        self._refuse_unknown_overrides(publishers=True)
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
        for message in session.start():
            self._emit(*message)
        self._substeps_logged = session.stepper.substeps
        self.get_logger().info(
            f"run {session.run_id}, scenario '{session.scenario.name}'"
            f" ({session.scenario.source}): {session.stepper.describe_step()};"
            f" max_actuation_force_n {session.settings['max_actuation_force_n']:g} N,"
            f" duration {session.settings['duration_s']:g} s,"
            f" {session.chunk_samples} samples per chunk"
            + (
                f"; waiting for {self._awaited_subscribers} ~/measured subscriber(s)"
                if self._awaited_subscribers
                else ""
            )
        )

    def _start_session(self) -> RunSession:
        """Declare the parameters and start the run they describe (the scenario's values
        and any --ros-args overrides, checked by the core)."""
        table = self._declare(run_parameters.RUN_PARAMETERS)
        self._drive_names = ros_params.DRIVE_LIMIT_NAMES
        try:  # fixed at start: where ~/reset requests may read scenario files
            self._scenario_dirs = allowed_dirs([self._param("scenario_dirs")])
        except ScenarioError as exc:
            raise ParameterError(str(exc)) from None
        # the operator's choice (command line or parameter): any file, not a request
        self._unit_id = self._param("unit_id")  # "" = each scenario's own
        scenario = self._as_unit(load_scenario(self._param("scenario")))
        run_id = run_parameters.check_run_id(self._param("run_id"))
        self._declare_brake(scenario)
        self._model_names = self._declare_model(scenario)
        self._refuse_unknown_overrides()
        values = {name: self._param(name) for name in self._model_names}
        scenario_values = ros_params.model_values(scenario.setup.params, scenario.setup.defects)
        overridden = {k: v for k, v in values.items() if v != scenario_values[k]}
        implied = {
            k: v
            for k, v in ros_params.complete_actuation_share(overridden).items()
            if k not in overridden
        }
        settings = {name: self._param(name) for name in table}
        if settings["publish_measured"]:  # asked for what the scenario's plan does not build
            require_measured(scenario, "publish_measured true refused")
        try:
            session = RunSession(
                scenario, settings=settings, model={**values, **implied}, run_id=run_id or None
            )
        except BrakeSimError:
            raise
        except ValueError as exc:  # a bad --ros-args override of the command policy
            raise ParameterError(str(exc)) from None
        work = session.work_refusal()
        if work:
            raise BrakeSimError(f"scenario '{scenario.name}': {work}")
        self._awaited_subscribers = _measured_subscribers(session.settings)
        self._double_names = {
            name
            for name in self._model_names + table
            if isinstance(self.get_parameter(name).value, float)
        }
        fills = ("duration_s", "max_actuation_force_n", *self._drive_names)
        self._set_internal({**implied, **{name: session.settings[name] for name in fills}})
        return session

    def _create_interfaces(self) -> None:
        """Publishers, subscriptions, services and timers."""
        with self._internally():  # the publishers declare their qos_overrides.* parameters
            self._out = NodeOutputs(
                self, self.stats, measured=self.session.settings["publish_measured"]
            )
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

    @property
    def scenario(self) -> Scenario:
        """The scenario running now."""
        return self.session.scenario

    @property
    def stepper(self) -> FixedStepStepper:
        """The stepper in use (read it; the session alone advances and changes it)."""
        return self.session.stepper

    @property
    def run_id(self) -> str:
        return self.session.run_id

    # -- commands ----------------------------------------------------------------------------
    def _on_actuation(self, msg: ActuationCommand) -> None:
        forces = (msg.left_force_n, msg.right_force_n)
        reason = self.session.actuation_refusal(forces)
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
        if self.session.command(forces):
            self.stats.commands_dropped += 1
        self._record_command(self._actuation_topic, msg)

    def _on_drive(self, msg: DriveCommand) -> None:
        """A drive command: from the next sample on, until the next one or a reset."""
        drive, reason = drive_command(msg.mode, msg.drive_torque_n_m, msg.target_speed_m_s)
        if reason is None:
            reason = self.session.drive_refusal(drive)
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
        self.session.drive(drive)
        self._record_command(self._drive_topic, msg)

    def _record_command(self, topic: Topic, msg) -> None:
        """Hand a command that takes effect to the sinks, stamped with the sample it takes
        effect at (the next one), so that a recording can be re-simulated (brake-sim
        resim): a command is applied at that sample and holds until a later one. A command
        replaced before its sample (two in one chunk) is recorded at the same sample,
        before the one that replaced it."""
        ns = conversion.stamp_ns(self.session.sample_index, self.session.period_s)
        self._out.to_sinks(topic, msg, ns)

    # -- stepping and publishing --------------------------------------------------------------
    def _advance_and_publish(self, n_steps: int, *, free_run: bool) -> bool:
        """Take ``n_steps`` samples (at most one chunk) and publish them. False on failure."""
        wall0 = self._wall()
        session = self.session
        try:
            block = session.advance(n_steps)
        except SimulationError as exc:  # non-finite or missing: stepped, not published
            self._count_stepped(n_steps, free_run)
            self._fail(str(exc))
            return False
        except BrakeSimError as exc:
            self.stats.physics_steps_done += session.physics_steps
            self._fail(str(exc))
            return False
        self._log_step_change("actuation above the force of the step limit")
        self._count_stepped(n_steps, free_run)
        self._publish_block(block)
        if n_steps == session.chunk_samples:  # whole chunks: the cost ~/step bounds use
            self._budget.observe((self._wall() - wall0) / n_steps)
        return True

    def _count_stepped(self, n_steps: int, free_run: bool) -> None:
        self.stats.physics_steps_done += self.session.physics_steps
        self.stats.samples_done += n_steps
        if free_run:
            self.stats.free_run_sim_s += n_steps * self.session.period_s

    def _publish_block(self, block: SampleBlock) -> None:
        states = 0
        for topic, msg, ns in self.session.messages(block):
            self._emit(topic, msg, ns)
            states += topic is stream.STATE
        self.stats.samples_published += len(block)
        self.stats.chunks_published += 1
        self.stats.states_published += states

    def _emit(self, topic: Topic, msg, ns: int) -> None:
        self._out.emit(topic, msg, ns)

    def add_sink(self, sink: MessageSink) -> None:
        """Receive every message from now on (what is published and accepted commands)."""
        self._out.sinks.append(sink)

    def close_sinks(self) -> None:
        """Close every sink (flushes recordings); each failure is logged, none is raised.
        Measured samples still pending are published first."""
        self._flush_measured()
        self._out.close()

    def _flush_measured(self) -> None:
        """Publish the measured samples still pending (the stream stops here, for now or
        for good); the sensors' failure is logged, it must not stop the node."""
        try:
            messages = self.session.flush()
        except Exception as exc:
            self.get_logger().error(f"measured samples lost: {type(exc).__name__}: {exc}")
            return
        for message in messages:
            self._emit(*message)

    def _fail(self, message: str) -> None:
        self._flush_measured()  # the samples published before the failure
        self._failure = message
        self._retime_tick()
        self.get_logger().error(f"simulation stopped: {message}")

    def _finish(self) -> None:
        self._flush_measured()
        if not self._finished:
            self._account_free_run(self._wall())
            self._finished = True
            self._retime_tick()
            self.get_logger().info(
                f"reached duration_s = {self.session.settings['duration_s']:g} s"
            )
        if self.session.settings["exit_at_end"]:
            self.done = True

    def _log_step_change(self, why: str) -> None:
        """Say so when the stepper picked other substeps (a model change, a large force)."""
        stepper = self.session.stepper
        if stepper.substeps != self._substeps_logged:
            self._substeps_logged = stepper.substeps
            self.get_logger().info(f"{why}: {stepper.describe_step()}")

    def summary(self) -> str:
        return summary(self.run_view(), self.stats)


def _measured_subscribers(settings: dict) -> int:
    """The ``measured_subscribers`` setting, refused (ParameterError) without
    ``publish_measured``: there would be no ~/measured to wait for."""
    n = int(settings["measured_subscribers"])
    if n and not settings["publish_measured"]:
        raise ParameterError(
            f"measured_subscribers={n} without publish_measured: allowed 0 (there is no"
            " ~/measured to wait for), or set publish_measured:=true"
        )
    return n
