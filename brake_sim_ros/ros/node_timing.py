"""The node's wall-clock side: what this machine can hold, the tick loop, diagnostics.

:class:`NodeTiming` is a mixin of :class:`~brake_sim_ros.ros.node.BrakeSimNode` (that one
class): it measures the costs of stepping and publishing at start and refuses settings
the machine cannot hold in real time (:func:`~brake_sim_ros.solvers.realtime.
check_pipeline`); on each steady-clock tick it asks the :class:`~.pacing.Pacer` how many
samples are due and has the node advance its run session by whole chunks (as fast as
possible: within :data:`AFAP_TICK_BUDGET_S` per tick); it reports the run on
/diagnostics. Simulated time alone decides what the samples are: the wall clock only
decides when they are stepped.
"""

from __future__ import annotations

import math

from brake_sim_ros import stream
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.ros.budget import step_costs
from brake_sim_ros.ros.diagnostics import RunView, diagnostic_array
from brake_sim_ros.ros.pacing import PacingMode
from brake_sim_ros.solvers.realtime import PipelineCosts, RealtimeVerdict, check_pipeline
from brake_sim_ros.stream import conversion
from brake_sim_ros.stream.commands import describe_drive

AFAP_TICK_BUDGET_S = 0.02  # wall time per tick as fast as possible (stays responsive)
# paused, finished or failed: nothing to step, so tick slowly (a 1 ms tick as fast as
# possible would keep a finished node at 60 % of a core); a change that resumes the run
# restarts the tick at once (:meth:`NodeTiming._retime_tick`)
IDLE_TICK_S = 0.1


class NodeTiming:
    """Costs, the tick loop and diagnostics of :class:`~brake_sim_ros.ros.node.BrakeSimNode`."""

    # -- what this machine can hold ---------------------------------------------------------
    def _measure_costs(self) -> PipelineCosts:
        """Stepping and publishing costs on this machine, measured now (some ms), at
        max_actuation_force_n (:func:`~brake_sim_ros.ros.budget.step_costs`)."""
        session = self.session
        costs = step_costs(
            self,
            session.stepper,
            label=f"scenario '{session.scenario.name}'",
            chunk_samples=session.chunk_samples,
            force_n=float(session.settings["max_actuation_force_n"]),
            sensors=session.new_sensor_bank(),
        )
        self.get_logger().info(
            f"measured costs: stepping {1e6 * costs.step_per_sample_s:.2f} us per sample;"
            f" publishing a chunk {1e6 * costs.chunk_fixed_s:.0f} us +"
            f" {1e6 * costs.chunk_per_sample_s:.2f} us per sample, a state row"
            f" {1e6 * costs.state_row_s:.0f} us"
        )
        return costs

    def _pipeline_verdict(self, **given) -> RealtimeVerdict:
        """The budget check for these settings (the current ones where not given)."""
        session = self.session
        return check_pipeline(
            given.get("costs") or self._budget.costs,
            sample_period_s=given.get("sample_period_s") or session.period_s,
            chunk_samples=given.get("chunk_samples") or session.chunk_samples,
            state_stride=given.get("state_stride") or session.samples_per("state_rate_hz"),
            real_time_factor=given.get("real_time_factor", self._pacer.real_time_factor),
            label=given.get("label") or f"scenario '{session.scenario.name}'",
        )

    def _paced(self, real_time_factor: float | None = None, paused: bool | None = None) -> bool:
        """Whether a run at ``real_time_factor`` (default: the pacer's), ``paused`` or not
        (default: the pacer's), keeps to the wall clock, so that the real-time budget
        applies: not as fast as possible (factor 0) and not paused (stepped on request;
        checked when it is resumed)."""
        factor = self._pacer.real_time_factor if real_time_factor is None else real_time_factor
        return factor > 0.0 and not (self._pacer.paused if paused is None else paused)

    def _check_keeps_up(self) -> None:
        """Refuse to start when this machine cannot step and publish the chunks in real
        time (:func:`brake_sim_ros.solvers.realtime.check_pipeline`). A node started
        paused (stepped on request) is checked when its run is resumed instead."""
        if not self._paced():
            if self._pacer.paused and self._pacer.real_time_factor > 0.0:
                self.get_logger().info("started paused: the real-time check runs at resume")
            return
        verdict = self._pipeline_verdict()
        if not verdict.ok:
            raise BrakeSimError(
                f"cannot keep real time: {verdict.message} (real_time_factor:=0.0 runs as"
                " fast as possible)"
            )
        self.get_logger().info(f"real-time check: {verdict.message}")

    def _waiting_for_subscribers(self) -> bool:
        """True while ~/measured has fewer subscribers than ``measured_subscribers``: the
        first sample waits, so no subscriber misses the run's start."""
        if not self._awaited_subscribers:
            return False
        count = self._out.subscriber_count(stream.MEASURED)
        if count < self._awaited_subscribers:
            return True
        self.get_logger().info(f"~/measured has {count} subscriber(s): the run starts")
        self._awaited_subscribers = 0
        return False

    def _on_tick(self) -> None:
        if self._failure or self._finished or self._waiting_for_subscribers():
            return
        now = self._wall()
        session = self.session
        if not self._ticking:  # pace from the first tick: start-up costs are not lateness
            self._ticking = True
            self._pacer.restart(now, session.sample_index)
            self._last_run_tick = now
        mode = self._pacer.mode
        if mode is PacingMode.PAUSED:
            return
        end = session.end_sample
        self._account_free_run(now)
        if mode is PacingMode.AS_FAST_AS_POSSIBLE:
            while session.sample_index < end and self._wall() - now < AFAP_TICK_BUDGET_S:
                n = min(session.chunk_samples, end - session.sample_index)
                if not self._advance_and_publish(n, free_run=True):
                    return
        elif not self._paced_tick(now, end):
            return
        if session.sample_index >= end:
            self._finish()

    def _paced_tick(self, now: float, end: int) -> bool:
        """The chunks due at wall time ``now`` in real time; False on failure."""
        chunk = self.session.chunk_samples
        plan = self._pacer.plan(
            now, self.session.sample_index, chunk, self._max_chunks_per_tick(), end
        )
        if plan.slipped_steps:
            self.stats.slips += 1
            self.stats.slipped_s += plan.slipped_steps * self.session.period_s
        # a chunk is late when published more than a chunk period after its last sample
        # was due, or two ticks (what tick granularity alone costs at high factors)
        tolerance = max(self._pacer.chunk_wall_period_s(chunk), 2.0 * self._tick_period_s())
        remaining = plan.steps
        while remaining > 0:
            n = min(chunk, remaining)
            if not self._advance_and_publish(n, free_run=True):
                return False
            remaining -= n
            late = self._wall() - self._pacer.deadline_s(self.session.sample_index)
            if late > tolerance:
                self.stats.deadline_misses += 1
        return True

    def _account_free_run(self, now: float) -> None:
        """Add the wall time since the last accounting to the free run's, if it was running."""
        running = not (self._failure or self._finished or self._pacer.paused)
        if running and self._last_run_tick is not None:
            self.stats.free_run_wall_s += now - self._last_run_tick
        self._last_run_tick = now

    def _tick_period_s(self) -> float:
        chunk = self.session.chunk_samples
        mode = self._pacer.mode
        if self._failure or self._finished or mode is PacingMode.PAUSED:
            return IDLE_TICK_S
        if mode is PacingMode.REAL_TIME:
            half_chunk = 0.5 * self._pacer.chunk_wall_period_s(chunk)
            return min(0.01, max(0.001, half_chunk))
        return 0.001

    def _retime_tick(self) -> None:
        """Tick at the period the run's state needs now, the next tick one period from now."""
        if getattr(self, "_tick_timer", None) is None:
            return  # not ticking yet: the timer starts at this period
        self._tick_timer.timer_period_ns = int(self._tick_period_s() * 1e9)
        self._tick_timer.reset()

    def _max_chunks_per_tick(self) -> int:
        if self._pacer.mode is not PacingMode.REAL_TIME:
            return 64
        chunk = self.session.chunk_samples
        per_tick = self._tick_period_s() / self._pacer.chunk_wall_period_s(chunk)
        return max(2, 4 * math.ceil(per_tick))

    # -- diagnostics ---------------------------------------------------------------------------
    def run_view(self) -> RunView:
        if self._failure:
            state = "failed"
        elif self._finished:
            state = "finished"
        elif self._pacer.paused:
            state = "paused"
        else:
            state = "running"
        session = self.session
        stepper, step = session.stepper, session.sample_index
        return RunView(
            node_name=self.get_name(),
            scenario=session.scenario.name,
            state=state,
            message=self._failure,
            sim_time_s=step * stepper.sample_period_s,
            sample_index=step,
            sample_rate_hz=conversion.sample_rate_hz(stepper.sample_period_s),
            duration_s=session.settings["duration_s"],
            target_real_time_factor=self._pacer.real_time_factor,
            measured_real_time_factor=self._measured_rtf,
            actuation_source=session.planner.source(step),
            drive="none" if stepper.drive_refusal() else describe_drive(stepper.live_drive),
            stop_time_s=stepper.stop_time_s,
            physics_step_s=stepper.physics_step_s,
            substeps=stepper.substeps,
            step_limit_s=stepper.limit.max_step_s,
            step_limit_force_n=stepper.limit_force_n,
            max_actuation_force_n=float(session.settings["max_actuation_force_n"]),
            seed=session.seed,
            run_id=session.run_id,
        )

    def _on_diagnostics(self) -> None:
        now = self._wall()
        last_wall, last_samples, last_misses = self._diag_last
        if now > last_wall:
            sim = (self.stats.samples_done - last_samples) * self.session.period_s
            self._measured_rtf = sim / (now - last_wall)
        new_misses = self.stats.deadline_misses - last_misses
        self._diag_last = (now, self.stats.samples_done, self.stats.deadline_misses)
        ns = conversion.stamp_ns(self.session.sample_index, self.session.period_s)
        self._emit(
            stream.DIAGNOSTICS,
            diagnostic_array(self.run_view(), self.stats, ns=ns, new_misses=new_misses),
            ns,
        )
