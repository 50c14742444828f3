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
from brake_sim_ros.stream.offline import (
    Change,
    StreamSettings,
    offline_messages,
    offline_session,
)
from brake_sim_ros.stream.session import RunSession


class RecordedNode(Protocol):
    """What :func:`node_recorder` reads of a live node (``ros.node.BrakeSimNode`` has it).

    A protocol, not an import: recording sits beside ros, below the composition root, and
    imports nothing of it.
    """

    @property
    def session(self) -> RunSession: ...

    def get_parameters_by_prefix(self, prefix: str) -> dict[str, Any]: ...

    def get_fully_qualified_name(self) -> str: ...


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
    changes: Sequence[Change] = (),
) -> OfflineRecording:
    """Write the node's stream for ``scenario`` (minus /diagnostics) to ``path``, as fast as
    the CPU goes.

    ``run_id`` is the id in the ground-truth messages and the ``brake_sim_run`` record:
    default a fresh one; give a live run's (its recording's ``brake_sim_run`` record says
    it) to write the same bytes as that run. ``changes``: parameter changes at their
    samples (:func:`~brake_sim_ros.stream.offline.offline_messages`), recorded as a
    node records those it accepts.

    Raises:
        RecordingError: the file cannot be written (nothing else is left half done: the
            partial file holds every chunk written before the failure).
        FidelityError: ``settings.publish_measured`` on a scenario whose fidelity plan has
            no sensors (refused before the file is opened).
    """
    settings = settings or StreamSettings()
    session = offline_session(scenario, duration_s=duration_s, settings=settings, run_id=run_id)
    dt = session.period_s
    live_only = (stream.DIAGNOSTICS, stream.ACTUATION, stream.DRIVE)
    off = () if settings.publish_measured else (stream.MEASURED,)
    topics = [t for t in stream.TOPICS if t not in live_only + off]
    cpu0, wall0 = time.process_time(), time.perf_counter()
    samples = 0
    recorder = McapRecorder(
        path,
        records=metadata.run_records(session, mode="offline"),
        options=options or RecordingOptions(durable=False),
        topics=topics,
        custom_data=metadata.custom_data(session, "offline"),
    )
    try:
        for sample, values in changes:  # for a re-simulation of this one
            recorder.parameter_change(values, sample, conversion.stamp_ns(sample, dt))
        messages = offline_messages(scenario, changes=changes, session=session)
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

    The model and the run parameters come from the node's session (which the node keeps
    equal to its ROS parameters).

    Raises:
        RecordingError: the file cannot be created or written.
    """
    values = {name: p.value for name, p in node.get_parameters_by_prefix("").items()}
    session = node.session
    extra = {
        "node": node.get_fully_qualified_name(),
        "real_time_factor": values["real_time_factor"],
        "paused_at_start": values["paused"],
    }
    records = metadata.run_records(session, mode="live", extra=extra)
    records[metadata.ROS_PARAMETERS] = {k: repr(v) for k, v in sorted(values.items())}
    return recorder_class(
        path,
        records=records,
        options=options,
        custom_data=metadata.custom_data(session, "live"),
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
