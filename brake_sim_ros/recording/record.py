"""Record a run: offline (``brake-sim simulate S --mcap F``) or from a live node (``--record``).

Both write the node's stream with :class:`~.writer.McapRecorder`; only the ``brake_sim_run``
record's ``mode`` (and the live-only keys) tell the files apart, and /diagnostics, a
wall-clock report, exists only live.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from brake_sim_ros import stream
from brake_sim_ros.recording import metadata
from brake_sim_ros.recording.writer import McapRecorder, RecordingOptions
from brake_sim_ros.scenarios import Scenario
from brake_sim_ros.stream import MessageSink, conversion
from brake_sim_ros.stream import parameters as ros_params
from brake_sim_ros.stream.build import require_measured, stepper_for
from brake_sim_ros.stream.offline import StreamSettings, offline_messages


class RecordedNode(Protocol):
    """What :func:`node_recorder` reads of a live node (``ros.node.BrakeSimNode`` has it).

    A protocol, not an import: recording sits beside ros, below the composition root, and
    imports nothing of it.
    """

    @property
    def scenario(self) -> Scenario: ...

    @property
    def stepper(self) -> Any: ...

    def run_view(self) -> Any: ...

    def get_parameters_by_prefix(self, prefix: str) -> dict[str, Any]: ...

    def get_fully_qualified_name(self) -> str: ...


def _custom_data(scenario: Scenario, seed: int, mode: str, run_id: str) -> dict[str, str]:
    return {
        "brake_sim_run_id": run_id,
        "brake_sim_scenario": scenario.name,
        "brake_sim_unit_id": scenario.unit_id,
        "brake_sim_seed": str(seed),
        "brake_sim_mode": mode,
        "brake_sim_version": metadata.software_version(),
    }


@dataclass(frozen=True)
class OfflineRecording:
    """What :func:`record_offline` wrote."""

    path: str
    messages: int
    per_topic: dict[str, int]
    samples: int
    sim_s: float
    cpu_s: float
    wall_s: float
    size_bytes: int

    def describe(self) -> str:
        topics = ", ".join(f"{k} {v}" for k, v in self.per_topic.items())
        return (
            f"recording: {self.path} ({self.size_bytes / 1e6:.3f} MB): {self.messages} messages"
            f" ({topics}); {self.samples} samples = {self.sim_s:g} s simulated in"
            f" {self.cpu_s:.3f} s CPU ({self.sim_s / max(self.wall_s, 1e-9):.0f}x real time)"
        )


def record_offline(
    scenario: Scenario,
    path: str | os.PathLike[str],
    *,
    duration_s: float | None = None,
    options: RecordingOptions | None = None,
    settings: StreamSettings | None = None,
    also: Sequence[MessageSink] = (),
    run_id: str | None = None,
) -> OfflineRecording:
    """Write the node's stream for ``scenario`` (minus /diagnostics) to ``path``, as fast as
    the CPU goes.

    ``run_id`` is the id in the ground-truth messages and the ``brake_sim_run`` record:
    default a fresh one; give a live run's (its recording's ``brake_sim_run`` record says
    it) to write the same bytes as that run.

    Raises:
        RecordingError: the file cannot be written (nothing else is left half done: the
            partial file holds every chunk written before the failure).
        FidelityError: ``settings.publish_measured`` on a scenario whose fidelity plan has
            no sensors (refused before the file is opened).
    """
    settings = settings or StreamSettings()
    if settings.publish_measured:  # before the file is opened
        require_measured(scenario, "publish_measured")
    run_id = conversion.new_run_id() if run_id is None else run_id
    duration = scenario.duration_s if duration_s is None else duration_s
    stepper = stepper_for(scenario)
    dt = stepper.sample_period_s
    params, defects = scenario.setup.params, scenario.setup.defects
    records = {
        metadata.MODEL: metadata.model_record(params, defects),
        metadata.SCENARIO: metadata.scenario_record(scenario),
        metadata.UNIT: metadata.unit_record(scenario),
        metadata.RUN: metadata.run_record(
            mode="offline",
            run_id=run_id,
            seed=scenario.seed,
            scenario=scenario,
            stepper=stepper,
            duration_s=duration,
            chunk_rate_hz=settings.chunk_rate_hz,
            state_rate_hz=settings.state_rate_hz,
            publish_clock=settings.publish_clock,
            publish_measured=settings.publish_measured,
            measured_rate_hz=settings.measured_rate_hz,
        ),
    }
    live_only = (stream.DIAGNOSTICS, stream.ACTUATION, stream.DRIVE)
    off = () if settings.publish_measured else (stream.MEASURED,)
    topics = [t for t in stream.TOPICS if t not in live_only + off]
    cpu0, wall0 = time.process_time(), time.perf_counter()
    samples = 0
    recorder = McapRecorder(
        path,
        records=records,
        options=options or RecordingOptions(durable=False),
        topics=topics,
        custom_data=_custom_data(scenario, scenario.seed, "offline", run_id),
    )
    try:
        messages = offline_messages(
            scenario, duration_s=duration, settings=settings, stepper=stepper, run_id=run_id
        )
        for topic, msg, ns in messages:
            recorder.write(topic, msg, ns)
            for sink in also:  # e.g. Rerun: one simulation feeds every output
                sink.write(topic, msg, ns)
            if topic is stream.PIVOT_FORCES:
                samples += len(msg.left_fx_n)
    finally:
        recorder.close()
    return OfflineRecording(
        path=str(path),
        messages=recorder.stats.messages,
        per_topic=dict(recorder.stats.per_topic),
        samples=samples,
        sim_s=samples * dt,
        cpu_s=time.process_time() - cpu0,
        wall_s=time.perf_counter() - wall0,
        size_bytes=os.path.getsize(path),
    )


def node_recorder(
    node: RecordedNode,
    path: str | os.PathLike[str],
    options: RecordingOptions | None = None,
    *,
    recorder_class: type[McapRecorder] = McapRecorder,
) -> McapRecorder:
    """A recorder for ``node``'s stream, its metadata taken from the node as it is now.

    The model comes from the node's ROS parameters (the scenario's values with any
    overrides: the node keeps them equal to what it steps), the run settings likewise.

    Raises:
        RecordingError: the file cannot be created or written.
    """
    values = {name: p.value for name, p in node.get_parameters_by_prefix("").items()}
    scenario = node.scenario
    names = ros_params.model_values(scenario.setup.params, scenario.setup.defects)
    params, defects = ros_params.build_model({k: values[k] for k in names})
    view = node.run_view()
    records = {
        metadata.MODEL: metadata.model_record(params, defects),
        metadata.SCENARIO: metadata.scenario_record(scenario),
        metadata.UNIT: metadata.unit_record(scenario),
        metadata.RUN: metadata.run_record(
            mode="live",
            run_id=view.run_id,
            seed=view.seed,
            scenario=scenario,
            stepper=node.stepper,
            duration_s=view.duration_s,
            chunk_rate_hz=values["chunk_rate_hz"],
            state_rate_hz=values["state_rate_hz"],
            publish_clock=values["publish_clock"],
            publish_measured=values["publish_measured"],
            measured_rate_hz=values["measured_rate_hz"],
            extra={
                "node": node.get_fully_qualified_name(),
                "real_time_factor": values["real_time_factor"],
                "paused_at_start": values["paused"],
            },
        ),
        metadata.ROS_PARAMETERS: {k: repr(v) for k, v in sorted(values.items())},
    }
    return recorder_class(
        path,
        records=records,
        options=options,
        custom_data=_custom_data(scenario, view.seed, "live", view.run_id),
    )


class _NodeRecorder(McapRecorder):
    """A node's recorder: says what it wrote when it is closed (stdout, after the summary)."""

    def close(self) -> None:
        was_open = not self._closed
        super().close()
        if was_open:
            print(f"brake_sim: recorded {self.describe()}", flush=True)


def open_node_recorder(
    path: str | os.PathLike[str], compression: str = "zstd", flush_interval_s: float = 1.0
) -> Callable[[RecordedNode], McapRecorder]:
    """A ``sink_openers`` entry for :class:`~brake_sim_ros.ros.node.BrakeSimNode` (``--record``).

    Bad options raise RecordingError at once; the file is opened when the node calls it.
    """
    options = RecordingOptions(compression=compression, flush_interval_s=flush_interval_s)

    def open_for(node: RecordedNode) -> McapRecorder:
        return node_recorder(node, path, options, recorder_class=_NodeRecorder)

    return open_for
