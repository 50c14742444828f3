"""Run counters, the /diagnostics status built from them, and the end-of-run summary.

No rclpy: the node fills :class:`RunStats` and :class:`RunView`; the functions here turn
them into a ``diagnostic_msgs/DiagnosticArray`` or a one-paragraph summary.

Counters (cumulative since the node started; a reset does not clear them):
    samples_done: samples stepped (sample intervals advanced).
    physics_steps_done: physics steps taken (each sample takes the substeps in use then).
    samples_published / chunks_published / states_published: what went out.
    deadline_misses: chunks published, in real-time mode, later than one chunk period
        (wall) after their last sample was due, or two timer ticks at high real-time
        factors, whichever is longer (10 ms at the defaults).
    slips / slipped_s: times the node fell more than ``max_lag_s`` behind and dropped the
        backlog, and the simulated time skipped that way (pacing re-anchored; the sample
        stream itself has no gap).
    drive_commands_accepted / drive_commands_rejected / drive_commands_dropped: the same
        for ~/drive commands (rejected: an unknown mode, a bad value, or a run that takes
        none: one with a drive cycle or without a vehicle).
    commands_accepted: valid commands. commands_rejected: invalid ones (NaN, inf,
        negative, above max_actuation_force_n). commands_dropped: accepted commands that
        never reached the physics (replaced by a newer one before the next sample, arrived
        after the end or a failure of the run, or cleared by a reset).
    parameter_changes_accepted / parameter_changes_refused: set-parameter requests
        (external ones; the node's own updates are not counted).
    sink_failures: recorders/viewers that raised and were dropped (their later messages
        are lost to them).
    publish_failures: messages the node did not publish because rclpy's publish raised.
    chunks_unheard: pivot-force chunks published while the publisher had no matched
        subscription (``get_subscription_count() == 0``): nobody could have received them.

    What these counters cannot see: losses inside DDS. A best-effort subscriber that
    falls behind, a full history queue (``depth``) or a lost UDP fragment drops messages
    without the publisher knowing; rclpy exposes no event for it on the publishing side.
    A subscriber sees such a loss as a gap in ``first_sample_index`` (as
    ``harness.SimClient.gaps`` counts). A node that falls behind does not skip samples
    either: ``slips`` re-anchor the pacing, the stream stays complete.
"""

from __future__ import annotations

from dataclasses import dataclass

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

from brake_sim_ros.stream.conversion import header

HARDWARE_ID = "brake_sim"


@dataclass
class RunStats:
    samples_done: int = 0
    physics_steps_done: int = 0
    samples_published: int = 0
    chunks_published: int = 0
    states_published: int = 0
    deadline_misses: int = 0
    slips: int = 0
    slipped_s: float = 0.0
    commands_accepted: int = 0
    commands_rejected: int = 0
    commands_dropped: int = 0
    parameter_changes_accepted: int = 0
    parameter_changes_refused: int = 0
    last_command_rejection: str = ""
    drive_commands_accepted: int = 0
    drive_commands_rejected: int = 0
    drive_commands_dropped: int = 0
    last_drive_rejection: str = ""
    last_parameter_refusal: str = ""
    sink_failures: int = 0  # recorders/viewers that failed and were dropped
    publish_failures: int = 0  # messages not published: the publisher raised
    chunks_unheard: int = 0  # chunks published while no subscriber was matched
    free_run_sim_s: float = 0.0  # simulated time advanced by the paced free run
    free_run_wall_s: float = 0.0  # wall time spent in the paced free run

    @property
    def achieved_real_time_factor(self) -> float:
        """Simulated / wall time over the free run so far (0 before any)."""
        return self.free_run_sim_s / self.free_run_wall_s if self.free_run_wall_s > 0 else 0.0


@dataclass(frozen=True)
class RunView:
    """What the node is doing, for one diagnostics message or the summary."""

    node_name: str
    scenario: str
    state: str  # "running", "paused", "finished", "failed"
    message: str  # failure reason, or ""
    sim_time_s: float
    sample_index: int
    sample_rate_hz: float
    duration_s: float
    target_real_time_factor: float  # 0 = as fast as possible
    measured_real_time_factor: float  # over the last diagnostics period
    actuation_source: str
    stop_time_s: float | None
    physics_step_s: float  # the step in use: sample period / substeps
    substeps: int  # physics steps per sample, from the step limit now
    step_limit_s: float
    step_limit_force_n: float  # the actuation force the step limit is computed for
    max_actuation_force_n: float
    seed: int
    run_id: str  # of the run in progress (changes at each ~/reset unless fixed)
    # the live drive in force (commands.describe_drive); "none": a run that takes none
    drive: str = "none"


def _level(view: RunView, stats: RunStats, new_misses: int) -> tuple[bytes, str]:
    if view.state == "failed":
        return DiagnosticStatus.ERROR, f"simulation failed: {view.message}"
    if view.state == "paused":
        return DiagnosticStatus.OK, f"paused at t = {view.sim_time_s:.6f} s"
    if view.state == "finished":
        return DiagnosticStatus.OK, f"finished at t = {view.sim_time_s:.6f} s"
    target = view.target_real_time_factor
    if target == 0.0:
        return DiagnosticStatus.OK, (
            f"running as fast as possible, {view.measured_real_time_factor:.2f}x real time"
        )
    text = f"running at {view.measured_real_time_factor:.3f}x real time (target {target:g}x)"
    if new_misses:
        return DiagnosticStatus.WARN, f"{text}; {new_misses} deadline misses in the last period"
    return DiagnosticStatus.OK, text


def diagnostic_array(
    view: RunView, stats: RunStats, *, ns: int, new_misses: int
) -> DiagnosticArray:
    """One DiagnosticStatus named ``<node>: simulation``; stamp = simulated time ``ns``."""
    level, message = _level(view, stats, new_misses)
    values = {
        "scenario": view.scenario,
        "state": view.state,
        "sim_time_s": f"{view.sim_time_s:.9f}",
        "sample_index": str(view.sample_index),
        "sample_rate_hz": f"{view.sample_rate_hz:g}",
        "duration_s": f"{view.duration_s:g}",
        "real_time_factor_target": f"{view.target_real_time_factor:g}",
        "real_time_factor_measured": f"{view.measured_real_time_factor:.4f}",
        "real_time_factor_achieved": f"{stats.achieved_real_time_factor:.4f}",
        "deadline_misses": str(stats.deadline_misses),
        "slips": str(stats.slips),
        "slipped_s": f"{stats.slipped_s:.6f}",
        "samples_done": str(stats.samples_done),
        "physics_steps_done": str(stats.physics_steps_done),
        "samples_published": str(stats.samples_published),
        "chunks_published": str(stats.chunks_published),
        "states_published": str(stats.states_published),
        "commands_accepted": str(stats.commands_accepted),
        "commands_rejected": str(stats.commands_rejected),
        "commands_dropped": str(stats.commands_dropped),
        "last_command_rejection": stats.last_command_rejection,
        "drive_commands_accepted": str(stats.drive_commands_accepted),
        "drive_commands_rejected": str(stats.drive_commands_rejected),
        "drive_commands_dropped": str(stats.drive_commands_dropped),
        "last_drive_rejection": stats.last_drive_rejection,
        "drive": view.drive,
        "parameter_changes_accepted": str(stats.parameter_changes_accepted),
        "parameter_changes_refused": str(stats.parameter_changes_refused),
        "last_parameter_refusal": stats.last_parameter_refusal,
        "sink_failures": str(stats.sink_failures),
        "publish_failures": str(stats.publish_failures),
        "chunks_unheard": str(stats.chunks_unheard),
        "actuation_source": view.actuation_source,
        "stop_time_s": "" if view.stop_time_s is None else f"{view.stop_time_s:.6f}",
        "physics_step_s": f"{view.physics_step_s:.9g}",
        "substeps_per_sample": str(view.substeps),
        "step_limit_s": f"{view.step_limit_s:.6g}",
        "step_limit_force_n": f"{view.step_limit_force_n:g}",
        "max_actuation_force_n": f"{view.max_actuation_force_n:g}",
        "seed": str(view.seed),
        "run_id": view.run_id,
        "failure": view.message if view.state == "failed" else "",
    }
    status = DiagnosticStatus(
        level=level,
        name=f"{view.node_name}: simulation",
        message=message,
        hardware_id=HARDWARE_ID,
        values=[KeyValue(key=k, value=v) for k, v in values.items()],
    )
    return DiagnosticArray(header=header(ns), status=[status])


def summary(view: RunView, stats: RunStats) -> str:
    """One paragraph for the end of a run (``--exit-at-end``)."""
    if view.stop_time_s is None:
        stop = "the drum had not stopped"
    else:
        stop = f"the drum stopped at t = {view.stop_time_s:.4f} s"
    target = (
        "as fast as possible"
        if view.target_real_time_factor == 0
        else f"target {view.target_real_time_factor:g}"
    )
    failed = f" The simulation FAILED: {view.message}." if view.state == "failed" else ""
    if stats.sink_failures:
        failed += f" {stats.sink_failures} recorder/viewer failure(s): see the log."
    return (
        f"brake_sim: run {view.run_id}, scenario '{view.scenario}' ended at simulated time"
        f" {view.sim_time_s:.4f} s ({view.sample_index} samples at {view.sample_rate_hz:g} Hz);"
        f" published {stats.samples_published} samples in {stats.chunks_published} chunks and"
        f" {stats.states_published} states; commands accepted {stats.commands_accepted},"
        f" rejected {stats.commands_rejected}, dropped {stats.commands_dropped}; parameter"
        f" changes refused {stats.parameter_changes_refused}; {stop}; real-time factor"
        f" achieved {stats.achieved_real_time_factor:.3f} ({target}) with"
        f" {stats.deadline_misses} deadline misses.{failed}"
    )
