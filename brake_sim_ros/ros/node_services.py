"""The node's services, ``~/step`` and ``~/reset``, over its run session.

:class:`NodeServices` is the service half of :class:`~brake_sim_ros.ros.node.BrakeSimNode`
(a mixin of that one class): ``~/step`` advances a paused run by whole chunks within the
wall-time budget of one call; ``~/reset`` starts a new run of the same scenario, of a new
seed's draw, or of another scenario (:meth:`~brake_sim_ros.stream.session.RunSession.
prepare` and ``switch``), refused in one line when the node could not hold it.
"""

from __future__ import annotations

import math

from brake_sim_msgs.srv import ResetSimulation, StepSimulation

from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.ros.budget import step_costs
from brake_sim_ros.ros.pacing import Pacer
from brake_sim_ros.scenarios import Scenario
from brake_sim_ros.scenarios.requested import load_requested_scenario
from brake_sim_ros.stream.build import require_measured

MAX_LAG_S = 0.5  # wall seconds of backlog that are caught up (see pacing)


class NodeServices:
    """``~/step`` and ``~/reset`` of :class:`~brake_sim_ros.ros.node.BrakeSimNode`."""

    def _step_refusal(self, steps: int, duration: float) -> tuple[int, str]:
        """The samples a ``~/step`` request asks for, and why it is refused (or "")."""
        dt = self.session.period_s
        if not self._pacer.paused:
            return steps, "the simulation is running: set the parameter paused to true first"
        if self._failure:
            return steps, f"the simulation failed ({self._failure}); call ~/reset"
        if (steps == 0) == (duration == 0.0):
            return steps, "give either steps or duration_s (the other 0)"
        if not (math.isfinite(duration) and duration >= 0.0):
            return steps, f"duration_s={duration!r}: allowed a finite time >= 0 s"
        steps = steps or round(duration / dt)
        budget, session = self._budget, self.session
        stride = session.samples_per("state_rate_hz")
        most = budget.max_step_samples(session.chunk_samples, stride, dt)
        if steps < 1:
            return steps, f"duration_s={duration:g} s is shorter than half a sample ({dt:g} s)"
        if steps > most:
            per_sample = budget.sample_cost_s(session.chunk_samples, stride)
            return steps, (
                f"{steps} samples = {steps * dt:g} s: allowed at most {most} samples ="
                f" {most * dt:g} s per call (one call may hold the node for"
                f" {budget.step_call_wall_s:g} s of wall time, a sample costs"
                f" {1e6 * per_sample:.1f} us here, and at most"
                f" {budget.max_step_request_s:g} s of simulated time); call ~/step again"
                " for more"
            )
        return steps, ""

    def _on_step(
        self, request: StepSimulation.Request, response: StepSimulation.Response
    ) -> StepSimulation.Response:
        steps, error = self._step_refusal(int(request.steps), float(request.duration_s))
        wall0 = self._wall()
        if not error:
            done = 0
            while done < steps:
                n = min(self.session.chunk_samples, steps - done)
                if not self._advance_and_publish(n, free_run=False):
                    error = f"the simulation failed: {self._failure}"
                    break
                done += n
            self._flush_measured()  # ~/measured holds every sample this call stepped
        response.success = not error
        index, dt = self.session.sample_index, self.session.period_s
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
        scenario = self.session.scenario
        try:
            if seed < -1:
                raise BrakeSimError(f"seed={seed}: allowed -1 (keep) or a seed >= 0")
            if request.scenario:
                new = load_requested_scenario(request.scenario, self._scenario_dirs)
                new = self._as_unit(new, seed=seed if seed >= 0 else None)
                self._switch_scenario(new, request.scenario)
            elif seed >= 0 and seed != scenario.seed and scenario.drawn:
                # the seed draws the operating conditions: a new seed, another setup
                self._switch_scenario(scenario.with_unit(seed=seed), self._param("scenario"))
        except BrakeSimError as exc:
            response.success, response.message = False, f"reset refused: {exc}"
            return response
        except Exception as exc:  # a bug, not the request: the node must run on
            self.get_logger().error(f"~/reset failed: {type(exc).__name__}")
            response.success = False
            response.message = f"reset refused: internal error ({type(exc).__name__})"
            return response
        self._flush_measured()  # the old run's last samples, before its successor's
        if self.session.reset(seed=seed):
            self.stats.commands_dropped += 1
        self._log_step_change("reset")
        now = self._wall()
        self._account_free_run(now)
        self._failure = ""
        self._finished = False
        self._pacer.restart(now, 0)
        self._retime_tick()
        for message in self.session.start():
            self._emit(*message)
        response.success = True
        response.message = (
            f"reset to t = 0 with scenario '{self.session.scenario.name}' (seed"
            f" {self.session.seed}), run id {self.session.run_id}"
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
        session = self.session
        if session.settings["publish_measured"]:
            require_measured(scenario, "publish_measured is on")
        prepared = session.prepare(scenario)
        dt = prepared.stepper.sample_period_s
        chunk = max(1, round(1.0 / (dt * session.settings["chunk_rate_hz"])))
        stride = max(1, round(1.0 / (dt * session.settings["state_rate_hz"])))
        costs = step_costs(
            self,
            prepared.stepper,
            label=f"scenario '{scenario.name}'",
            chunk_samples=chunk,
            force_n=float(self._param("max_actuation_force_n")),
            sensors=None,
            publishing=self._budget.costs,
        )
        if self._paced():
            verdict = self._pipeline_verdict(
                costs=costs,
                sample_period_s=dt,
                chunk_samples=chunk,
                state_stride=stride,
                label=f"scenario '{scenario.name}'",
            )
            if not verdict.ok:
                raise BrakeSimError(f"cannot keep real time: {verdict.message}")
        self._budget.costs = costs
        session.switch(prepared)
        self._follow_brake(scenario)
        values = {**session.model, "scenario": name_or_path, "brake": scenario.setup.params.brake}
        for name in ("max_actuation_force_n", "duration_s", *self._drive_names):
            values[name] = session.settings[name]
        self._set_internal(values)
        self._log_step_change(f"scenario '{scenario.name}'")
        self._pacer = Pacer(
            dt,
            real_time_factor=self._pacer.real_time_factor,
            paused=self._pacer.paused,
            max_lag_s=MAX_LAG_S,
        )
        self._retime_tick()
