"""A :class:`~brake_sim_ros.stream.MessageSink` that logs the simulator's stream to Rerun.

It reads messages by attribute only, so it takes the node's rclpy messages and the
objects ``mcap_ros2`` decodes from a recording alike (arrays may be lists,
``array.array`` or numpy arrays). Messages are dispatched on their ROS type, so a renamed
node's topics work too, to what draws them (paths in :mod:`.entities`, one ``sim_time``
timeline taken from the messages' stamps: :mod:`.timeline`):

* :mod:`.series`: pivot forces at every sample (or their envelope live) and the
  BrakeState scalars, sent as columns;
* :mod:`.measured`: what the sensors measured, a series per channel, sensor-fault events;
* :mod:`.contact`: impacts (markers and events), separations, regime changes;
* :mod:`.scene`: the 2-D drawing at ``drawing_rate_hz`` of simulated time;
* :mod:`.annotations`: the defect ground truth, actuation commands, diagnostics.

Memory: the sink holds at most ``batch_s`` of samples (plus the pivot-force samples
since the previous state); what the recording stream does with them depends on where it
sends them (see :mod:`.targets`).
"""

from __future__ import annotations

from typing import Any

import rerun as rr

from brake_sim_ros import stream
from brake_sim_ros.model.defects import Defects
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.stream import Topic
from brake_sim_ros.viz import entities as E
from brake_sim_ros.viz.annotations import (
    log_actuation_command,
    log_defects,
    log_diagnostics,
    shoe_defects,
)
from brake_sim_ros.viz.contact import ContactMarkers
from brake_sim_ros.viz.measured import MeasuredSeries
from brake_sim_ros.viz.pivot_samples import PivotChunk, RecentPivotForces
from brake_sim_ros.viz.scene import BrakeScene
from brake_sim_ros.viz.series import TimeSeries, envelope_positions
from brake_sim_ros.viz.settings import FILE_SETTINGS, LIVE_SETTINGS, RerunSinkError, SinkSettings
from brake_sim_ros.viz.styles import log_series_styles
from brake_sim_ros.viz.timeline import log_event, stamp_ns

__all__ = [
    "FILE_SETTINGS",
    "LIVE_SETTINGS",
    "RerunSink",
    "RerunSinkError",
    "SinkSettings",
    "envelope_positions",
]

_BUILT_IN_GEOMETRY = "the drawing uses the built-in brake geometry (none was given)"


class RerunSink:
    """Logs the simulator's message stream to one Rerun recording stream.

    Args:
        recording: where to log; the sink owns it from now on (``close`` flushes and
            disconnects it).
        params: the brake's parameters for the drawing (default: the built-in ones,
            announced as such in the event log).
        defects: defects at the start (DefectState messages update them).
        settings: what to send (``FILE_SETTINGS`` for files, ``LIVE_SETTINGS`` for
            viewers).
        run_text: markdown describing the run (scenario, source), logged once.
    """

    def __init__(
        self,
        recording: rr.RecordingStream,
        *,
        params: BrakeParameters | None = None,
        defects: Defects | None = None,
        settings: SinkSettings = FILE_SETTINGS,
        run_text: str = "",
    ) -> None:
        self.rec = recording
        self.settings = settings
        self._recent = RecentPivotForces()
        self._series = TimeSeries(
            recording, batch_s=settings.batch_s, force_envelope_hz=settings.force_envelope_hz
        )
        self._contact = ContactMarkers(recording, self._recent)
        self._measured = MeasuredSeries(recording, envelope_hz=settings.force_envelope_hz)
        self._scene = BrakeScene(
            recording,
            params=params or BrakeParameters(),
            defects=defects or Defects(),
            drawing_rate_hz=settings.drawing_rate_hz,
            pivot_forces=self._recent,
        )
        self.samples_logged = 0  # pivot-force samples received (all of them are in files)
        self.states_logged = 0
        self.first_ns: int | None = None
        self.last_ns: int | None = None
        self.closed = False
        recording.set_log_time_enabled(False)  # sim_time only: no wall clock in the log
        recording.set_log_tick_enabled(False)
        log_series_styles(recording)
        if run_text:
            self.rec.log(
                f"{E.RUN}/scenario",
                rr.TextDocument(run_text, media_type=rr.MediaType.MARKDOWN),
                static=True,
            )
        if params is None:
            log_event(recording, 0, _BUILT_IN_GEOMETRY, "WARN")

    @property
    def impacts(self) -> dict[str, int]:
        """Contact onsets seen per side."""
        return self._contact.impacts

    # -- MessageSink ------------------------------------------------------------------------
    def write(self, topic: Topic, msg: Any, time_ns: int) -> None:
        """Log one message (dispatched on ``topic.type_name``); other types are ignored."""
        if self.closed:
            raise RerunSinkError("write() after close()")
        kind = topic.type_name
        if kind == stream.PIVOT_FORCES.type_name:
            self._on_chunk(PivotChunk.from_msg(msg))
        elif kind == stream.MEASURED.type_name:
            self._measured.on_chunk(msg)
            self._seen(stamp_ns(msg))
        elif kind == stream.STATE.type_name:
            self._on_state(msg)
        elif kind == stream.CONTACT_EVENTS.type_name:
            if self._contact.on_contact_event(msg, rate_hz=self._series.rate_hz):
                self._seen(stamp_ns(msg))
        elif kind == stream.DEFECTS.type_name:
            ns = stamp_ns(msg)
            shoes = shoe_defects(msg)
            self._scene.set_defects(shoes, ns)
            log_defects(self.rec, msg, ns, shoes)
            self._seen(ns)
        elif kind == stream.ACTUATION.type_name:
            log_actuation_command(self.rec, msg, int(time_ns))
        elif kind == stream.DIAGNOSTICS.type_name:
            log_diagnostics(self.rec, msg, int(time_ns))
        # JointState repeats BrakeState; /clock carries no data to show

    def close(self) -> None:
        """Send everything buffered, then flush and disconnect the recording stream."""
        if self.closed:
            return
        self._series.flush(final=True)
        self.closed = True
        self.rec.flush()
        self.rec.disconnect()

    # -- dispatch ---------------------------------------------------------------------------
    def _seen(self, ns: int) -> None:
        self.first_ns = ns if self.first_ns is None else min(self.first_ns, ns)
        self.last_ns = ns if self.last_ns is None else max(self.last_ns, ns)

    def _on_chunk(self, chunk: PivotChunk) -> None:
        first, expected = chunk.first_index, self._series.next_index
        if expected is not None and first < expected:
            self._series.flush(final=True)
            self._recent.clear()
            self._contact.restart()
            self._measured.restart()
            self._scene.restart()
            msg = f"simulation restarted at sample {first} (reset)"
            log_event(self.rec, chunk.start_ns, msg, "WARN")
        elif expected is not None and first > expected:
            msg = f"{first - expected} pivot-force samples lost before {first}"
            log_event(self.rec, chunk.start_ns, msg, "WARN")
        self._series.add_pivot(chunk)
        if chunk.size == 0:
            return
        self._recent.add(chunk)
        self.samples_logged += chunk.size
        self._seen(chunk.start_ns)
        self._seen(chunk.end_ns)
        self._series.due(chunk.end_ns)

    def _on_state(self, msg: Any) -> None:
        ns = stamp_ns(msg)
        self._series.add_state(msg, ns)
        self._contact.on_state(msg, ns, rate_hz=self._series.rate_hz)
        self._scene.on_state(msg, ns)
        # keep only the pivot samples after this state (the next impact's window)
        self._recent.keep_after(int(msg.sample_index))
        self.states_logged += 1
        self._seen(ns)
        self._series.due(ns)
