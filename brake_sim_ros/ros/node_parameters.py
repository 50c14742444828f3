"""The node's ROS parameters: declared from the tables, changes checked and handed on.

:class:`NodeParameters` is the parameter half of :class:`~brake_sim_ros.ros.node.
BrakeSimNode` (a mixin of that one class). Run parameters are declared from
:data:`~brake_sim_ros.stream.run_parameters.RUN_PARAMETERS` and model parameters from the
core (:func:`~brake_sim_ros.stream.parameters.model_parameter_specs`); a change is
refused when the table fixes it at start, when the node could no longer keep real time,
or when the run session refuses it (:meth:`~brake_sim_ros.stream.session.RunSession.
apply`, the core's reason for a model change); an accepted one is applied by the session,
then to the node's pacing and timers, and handed to the sinks that record changes.
"""

from __future__ import annotations

import contextlib
import dataclasses
import difflib
from collections.abc import Iterable, Iterator

from rcl_interfaces.msg import SetParametersResult
from rclpy.exceptions import ParameterException
from rclpy.parameter import Parameter

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.ros.descriptors import descriptor
from brake_sim_ros.scenarios import Scenario
from brake_sim_ros.solvers.realtime import check_chunk_work
from brake_sim_ros.stream import conversion, run_parameters
from brake_sim_ros.stream import parameters as ros_params
from brake_sim_ros.stream.parameters import ParamSpec

# declared by the publishers (their QoS overrides), after the node's own parameters
_QOS_OVERRIDES = "qos_overrides."
_SHOWN_CHARS = 64  # at most this much of a caller's text is echoed back
# what the real-time check looks at (resuming a paused run included)
_RATES = frozenset({"chunk_rate_hz", "state_rate_hz", "real_time_factor", "paused"})
# The brake the running scenario simulates, for a client that must know it (brake-sim
# monitor refuses a detector fitted on the other brake's samples). Not the descriptor's
# read_only: the node itself sets it at a ~/reset to a scenario of the other brake.
BRAKE = ParamSpec(
    "brake",
    "study",
    "The brake the running scenario simulates (its top-level key brake): study or"
    " service; follows a ~/reset to a scenario of the other brake. Read-only: set from the"
    " scenario, a change (at start-up too) is refused.",
    constraints="study or service (the scenario's)",
)


class NodeParameters:
    """Parameter plumbing of :class:`~brake_sim_ros.ros.node.BrakeSimNode`."""

    _internal_update = False

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

    def _refuse_unknown_overrides(self, *, publishers: bool = False) -> None:
        """A ``--ros-args -p`` name this node does not declare is a typo: refuse to start.

        rclpy keeps the overrides it was given (``/**`` ones too) in ``_parameter_overrides``
        and ignores undeclared ones silently; there is no public accessor. The publishers'
        ``qos_overrides.*`` names are checked once they exist (``publishers``).
        """
        unknown = sorted(
            name
            for name in getattr(self, "_parameter_overrides", {})
            if not self.has_parameter(name) and (publishers or not name.startswith(_QOS_OVERRIDES))
        )
        if unknown:
            raise ParameterError(f"--ros-args override refused: {self._unknown_reason(unknown)}")

    def _declare(self, specs: Iterable) -> list[str]:
        """Declare each spec (name, default, descriptor); their names."""
        names = []
        for spec in specs:
            try:
                self.declare_parameter(spec.name, spec.default, descriptor(spec))
            except ParameterException as exc:  # a bad --ros-args override
                raise ParameterError(f"--ros-args override refused: {exc}") from None
            names.append(spec.name)
        return names

    def _declare_brake(self, scenario: Scenario) -> None:
        """Declare ``brake`` at ``scenario``'s; a ``--ros-args`` override of it that says
        another brake is refused (ParameterError): the scenario chooses the brake."""
        brake = scenario.setup.params.brake
        self._declare([dataclasses.replace(BRAKE, default=brake)])
        given = self._param(BRAKE.name)
        if given != brake:
            shown = str(given)[:_SHOWN_CHARS]
            raise ParameterError(
                f"--ros-args override refused: brake={shown!r}: read-only, scenario"
                f" '{scenario.name}' runs the {brake} brake (its top-level key brake sets it)"
            )

    def _declare_model(self, scenario: Scenario) -> list[str]:
        setup = scenario.setup
        return self._declare(ros_params.model_parameter_specs(setup.params, setup.defects))

    def _follow_brake(self, scenario: Scenario) -> None:
        """The model parameters of ``scenario``'s brake, before its values are set: those
        only the other brake has (a service brake's ``service.*``) undeclared, its own
        declared (at the new scenario's values), so that ``ros2 param list`` never shows a
        parameter the running brake does not read."""
        setup = scenario.setup
        specs = ros_params.model_parameter_specs(setup.params, setup.defects)
        names = [spec.name for spec in specs]
        with self._internally():
            for name in set(self._model_names) - set(names):
                self.undeclare_parameter(name)
                self._double_names.discard(name)
            for spec in specs:
                if spec.name not in self._model_names:
                    self.declare_parameter(spec.name, spec.default, descriptor(spec))
                    if isinstance(spec.default, float):
                        self._double_names.add(spec.name)
        self._model_names = names

    @contextlib.contextmanager
    def _internally(self) -> Iterator[None]:
        """Parameters declared or set inside: not validated again, not counted."""
        self._internal_update = True
        try:
            yield
        finally:
            self._internal_update = False

    def _set_internal(self, values: dict) -> None:
        """Set parameters from inside the node (not validated again, not counted)."""
        with self._internally():
            self.set_parameters([Parameter(k, value=v) for k, v in values.items()])

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

    def _rates_refusal(self, changes: dict) -> str | None:
        """Why new chunk/state rates or real-time factor cannot be held, or None; a paused
        run (stepped on request) needs no real time: its settings are checked when it is
        resumed (``paused`` set false)."""
        session = self.session
        chunk = session.samples_per("chunk_rate_hz", changes.get("chunk_rate_hz"))
        stride = session.samples_per("state_rate_hz", changes.get("state_rate_hz"))
        factor = changes.get("real_time_factor", self._pacer.real_time_factor)
        stepper = session.stepper
        work = check_chunk_work(stepper.substeps, chunk, stepper.physics_step_s)
        if work:
            return work
        if not self._paced(factor, changes.get("paused")):
            return None
        verdict = self._pipeline_verdict(
            chunk_samples=chunk, state_stride=stride, real_time_factor=factor
        )
        return None if verdict.ok else f"cannot keep real time: {verdict.message}"

    def _on_set_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        """Validate a change as a whole; apply it only if all of it is valid."""
        if self._internal_update:
            return SetParametersResult(successful=True)
        changes = {p.name: p.value for p in parameters}
        if BRAKE.name in changes:
            return SetParametersResult(
                successful=False,
                reason="brake is read-only: the running scenario's brake (switch scenarios"
                " with the ~/reset service)",
            )
        for name in changes.keys() & run_parameters.fixed_at_start():
            hint = (
                " (switch scenarios with the ~/reset service)"
                if name == "scenario"
                else " (restart the node to change it)"
            )
            return SetParametersResult(
                successful=False, reason=f"{name} is fixed at start-up{hint}"
            )
        reason = self._rates_refusal(changes) if changes.keys() & _RATES else None
        if reason is None:
            try:
                messages = self.session.apply(changes)
            except ParameterError as exc:
                reason = str(exc)
        if reason is not None:
            return SetParametersResult(successful=False, reason=reason)
        model = changes.keys() & set(self._model_names)
        if model:
            self._log_step_change("new model parameters")
        self._apply_pacing(changes)
        self._record_change(changes)
        for message in messages:
            self._emit(*message)
        pending = sorted(model & ros_params.INITIAL_CONDITIONS)
        if pending:
            self.get_logger().info(
                f"{', '.join(pending)}: initial condition, applies at the next ~/reset"
            )
        return SetParametersResult(successful=True)

    def _apply_pacing(self, changes: dict) -> None:
        """The node's share of an accepted change: pacing, timers, the end of the run."""
        now = self._wall()
        step = self.session.sample_index
        self._account_free_run(now)
        if "real_time_factor" in changes:
            self._pacer.set_real_time_factor(changes["real_time_factor"], now, step)
        if "paused" in changes:
            self._pacer.set_paused(changes["paused"], now, step)
            if changes["paused"]:
                self._flush_measured()
        if "diagnostics_period_s" in changes:
            self._diag_timer.timer_period_ns = int(changes["diagnostics_period_s"] * 1e9)
        before_end = step < self.session.end_sample
        if self._finished and before_end and changes.keys() & {"duration_s", "continuous"}:
            self._finished = False
            self._pacer.restart(now, step)
        if changes.keys() & {"real_time_factor", "paused", "chunk_rate_hz", "duration_s",
                             "continuous"}:  # fmt: skip
            self._retime_tick()

    def _record_change(self, changes: dict) -> None:
        """Hand an accepted parameter change to the sinks that record changes (a
        recording: ``parameter_change``), at the sample it takes effect at (the next)."""
        index = self.session.sample_index
        ns = conversion.stamp_ns(index, self.session.period_s)
        self._out.parameter_change(changes, index, ns)
