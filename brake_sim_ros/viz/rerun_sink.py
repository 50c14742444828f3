"""A :class:`~brake_sim_ros.stream.MessageSink` that logs the simulator's stream to Rerun.

It reads messages by attribute only, so it takes the node's rclpy messages and the
objects ``mcap_ros2`` decodes from a recording alike (arrays may be lists,
``array.array`` or numpy arrays). Messages are dispatched on their ROS type, so a renamed
node's topics work too. What is logged (paths in :mod:`.entities`, one ``sim_time``
timeline taken from the messages' stamps):

* pivot forces of both shoes, |F|, fx, fy (N): every sample, sent as columns
  (``send_columns``) once ``batch_s`` of simulated time is buffered; with
  ``force_envelope_hz`` (live viewers) only the smallest and largest sample of each
  ``1 / force_envelope_hz`` bucket, at their own times, so every peak stays visible;
* BrakeState at the state rate: speeds, shoe angles, indentations, contact and
  actuation forces, contact flags and regime (also as columns);
* impacts, from ContactEvent messages (ground truth at the full sample rate): each onset
  is an event and a marker at its exact sample, valued |F_pivot| of that sample (when
  the chunk holding it was received); each separation is an event and a marker at the
  episode's peak |F_pivot| (``pivot_force/impacts/<side>/peak``). A stream without
  ContactEvents (an older recording) falls back to the state rate: a contact onset
  (:mod:`brake_sim_ros.analysis.onsets`) between two BrakeStates' contact flags gives an
  event and a marker at the largest |F_pivot| of that shoe since the previous state
  (raise ``state_rate_hz`` to resolve every bounce).
  Regime changes are events;
* the defect ground truth (markdown and scalars) when a DefectState arrives;
* the 2-D drawing (:mod:`.drawing`) at ``drawing_rate_hz`` of simulated time.

Memory: the sink holds at most ``batch_s`` of samples (plus the pivot-force samples
since the previous state); what the recording stream does with them depends on where it
sends them (see :mod:`.targets`).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np
import rerun as rr

from brake_sim_ros.analysis.onsets import contact_changes
from brake_sim_ros.errors import BrakeSimError, ParameterError
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.layout import REGIME_NAMES
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.stream import Topic
from brake_sim_ros.viz import entities as E
from brake_sim_ros.viz.drawing import FORCE_SCALE_M_PER_N, BrakeDrawing, contact_force_vectors

_NS_PER_S = 1_000_000_000
COLORS = {"left": (230, 120, 30), "right": (40, 120, 220)}
_TYPE_CHUNK = "brake_sim_msgs/msg/PivotForceChunk"
_TYPE_STATE = "brake_sim_msgs/msg/BrakeState"
_TYPE_DEFECTS = "brake_sim_msgs/msg/DefectState"
_TYPE_ACTUATION = "brake_sim_msgs/msg/ActuationCommand"
_TYPE_DIAGNOSTICS = "diagnostic_msgs/msg/DiagnosticArray"
_TYPE_CONTACT_EVENT = "brake_sim_msgs/msg/ContactEvent"
_KIND_ONSET = 0  # ContactEvent.KIND_ONSET; SHOE_LEFT = 0, SHOE_RIGHT = 1 index E.SIDES
_DIAG_LEVELS = {0: "INFO", 1: "WARN", 2: "ERROR", 3: "WARN"}


class RerunSinkError(BrakeSimError, ValueError):
    """A message the sink cannot log (inconsistent arrays, bad rate)."""


@dataclass(frozen=True)
class SinkSettings:
    """How much of the stream a :class:`RerunSink` sends.

    Attributes:
        force_envelope_hz: None = every pivot-force sample (files); else buckets of
            ``1 / force_envelope_hz`` s of simulated time reduced to their min and max
            samples (live viewers cannot draw 25 kHz series).
        drawing_rate_hz: frames of the 2-D drawing per simulated second (at most the
            state rate: a frame is drawn at a BrakeState).
        batch_s: simulated seconds of samples per ``send_columns`` call.
    """

    force_envelope_hz: float | None = None
    drawing_rate_hz: float = 50.0
    batch_s: float = 0.5

    def __post_init__(self) -> None:
        for name in ("drawing_rate_hz", "batch_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise RerunSinkError(f"{name}={value!r}: allowed a finite value > 0")
        env = self.force_envelope_hz
        if env is not None and not (math.isfinite(env) and env > 0):
            raise RerunSinkError(f"force_envelope_hz={env!r}: allowed None or a value > 0")


FILE_SETTINGS = SinkSettings()
LIVE_SETTINGS = SinkSettings(force_envelope_hz=500.0, drawing_rate_hz=25.0, batch_s=0.1)


def _stamp_ns(msg: Any) -> int:
    stamp = msg.header.stamp
    return int(stamp.sec) * _NS_PER_S + int(stamp.nanosec)


def _durations(ns: np.ndarray) -> np.ndarray:
    return np.asarray(ns, dtype=np.int64).astype("timedelta64[ns]")


def envelope_positions(values: np.ndarray, bucket: int) -> np.ndarray:
    """Positions of the smallest and largest value of each run of ``bucket`` samples, in
    increasing order (one position when they coincide). A last partial bucket counts."""
    n = values.size
    if bucket <= 1 or n == 0:
        return np.arange(n)
    starts = np.arange(0, n, bucket)
    lo = np.minimum.reduceat(values, starts)
    hi = np.maximum.reduceat(values, starts)
    ends = np.append(starts[1:], n)
    picks = []
    for s, e, vmin, vmax in zip(starts, ends, lo, hi, strict=True):
        seg = values[s:e]
        picks.append(s + int(np.argmax(seg == vmin)))
        picks.append(s + int(np.argmax(seg == vmax)))
    return np.unique(np.asarray(picks, dtype=np.int64))


class _Series:
    """Buffered scalar rows of one entity: times (ns) and values."""

    def __init__(self) -> None:
        self.ns: list[np.ndarray] = []
        self.values: list[np.ndarray] = []

    def add(self, ns: np.ndarray, values: np.ndarray) -> None:
        self.ns.append(ns)
        self.values.append(values)

    def take(self) -> tuple[np.ndarray, np.ndarray]:
        ns = np.concatenate(self.ns) if self.ns else np.zeros(0, np.int64)
        values = np.concatenate(self.values) if self.values else np.zeros(0)
        self.ns, self.values = [], []
        return ns, values


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
        self._params = params or BrakeParameters()
        self._drawing = BrakeDrawing(self._params, defects or Defects())
        self._series: dict[str, _Series] = {}
        self._batch_start_ns: int | None = None
        self._next_index: int | None = None
        self._rate_hz: float | None = None
        self._pending: dict[str, list[np.ndarray]] = {}  # raw pivot samples not yet sent
        self._pending_index: list[np.ndarray] = []
        # pivot samples since the previous state: (first index, {side: (fx, fy, |F|)})
        self._recent: deque[tuple[int, dict[str, tuple[np.ndarray, ...]]]] = deque()
        self._last_state: Any = None
        self._last_state_index: int | None = None
        self._next_frame_ns = 0
        self.samples_logged = 0  # pivot-force samples received (all of them are in files)
        self.states_logged = 0
        self.impacts = {side: 0 for side in E.SIDES}  # contact onsets seen
        # True once a ContactEvent arrived: impacts come from them, not from the states
        self._contact_events_seen = False
        self.first_ns: int | None = None
        self.last_ns: int | None = None
        self.closed = False
        recording.set_log_time_enabled(False)  # sim_time only: no wall clock in the log
        recording.set_log_tick_enabled(False)
        self._log_styles()
        if run_text:
            self.rec.log(
                f"{E.RUN}/scenario",
                rr.TextDocument(run_text, media_type=rr.MediaType.MARKDOWN),
                static=True,
            )
        if params is None:
            self._event(0, "the drawing uses the built-in brake geometry (none was given)", "WARN")

    # -- static styles --------------------------------------------------------------------
    def _log_styles(self) -> None:
        log = self.rec.log
        step = rr.components.InterpolationMode.StepAfter
        for side in E.SIDES:
            color = COLORS[side]
            for series in E.PIVOT_SERIES:
                unit = "|F|" if series == "magnitude" else series
                log(
                    E.pivot_path(side, series),
                    rr.SeriesLines(colors=[color], names=[f"{side} {unit} (N)"], widths=[1.0]),
                    static=True,
                )
            log(
                f"{E.IMPACTS}/{side}",
                rr.SeriesPoints(
                    colors=[color], names=[f"{side} impact"], markers=["Cross"], marker_sizes=[6]
                ),
                static=True,
            )
            log(
                E.impact_peak_path(side),
                rr.SeriesPoints(
                    colors=[color],
                    names=[f"{side} impact peak"],
                    markers=["Diamond"],
                    marker_sizes=[5],
                ),
                static=True,
            )
            for path, name, mode in (
                (f"{E.SHOE_ANGLE}/{side}", f"{side} (deg)", None),
                (f"{E.INDENTATION}/{side}", f"{side} (um)", None),
                (f"{E.CONTACT_FORCE}/{side}/normal", f"{side} normal (N)", None),
                (f"{E.CONTACT_FORCE}/{side}/friction", f"{side} friction (N)", None),
                (f"{E.ACTUATION}/{side}", f"{side} applied (N)", step),
                (f"{E.CONTACT}/{side}", f"{side} in contact (0/1)", step),
            ):
                log(
                    path,
                    rr.SeriesLines(colors=[color], names=[name], interpolation_mode=mode),
                    static=True,
                )
            log(
                f"{E.ACTUATION}/command/{side}",
                rr.SeriesPoints(colors=[color], names=[f"{side} command (N)"], markers=["Circle"]),
                static=True,
            )
        log(f"{E.SPEED}/flywheel", rr.SeriesLines(names=["flywheel (rad/s)"]), static=True)
        log(f"{E.SPEED}/drum", rr.SeriesLines(names=["drum (rad/s)"]), static=True)
        log(
            f"{E.CONTACT}/regime",
            rr.SeriesLines(
                colors=[(90, 90, 90)],
                names=["regime (0 free, 1 impacting, 2 contact, 3 stopped)"],
                interpolation_mode=step,
            ),
            static=True,
        )

    # -- MessageSink ------------------------------------------------------------------------
    def write(self, topic: Topic, msg: Any, time_ns: int) -> None:
        """Log one message (dispatched on ``topic.type_name``); other types are ignored."""
        if self.closed:
            raise RerunSinkError("write() after close()")
        kind = topic.type_name
        if kind == _TYPE_CHUNK:
            self._on_chunk(msg)
        elif kind == _TYPE_STATE:
            self._on_state(msg)
        elif kind == _TYPE_CONTACT_EVENT:
            self._on_contact_event(msg)
        elif kind == _TYPE_DEFECTS:
            self._on_defects(msg)
        elif kind == _TYPE_ACTUATION:
            self._on_actuation(msg, int(time_ns))
        elif kind == _TYPE_DIAGNOSTICS:
            self._on_diagnostics(msg, int(time_ns))
        # JointState repeats BrakeState; /clock carries no data to show

    def close(self) -> None:
        """Send everything buffered, then flush and disconnect the recording stream."""
        if self.closed:
            return
        self._flush(final=True)
        self.closed = True
        self.rec.flush()
        self.rec.disconnect()

    # -- helpers ----------------------------------------------------------------------------
    def _set_time(self, ns: int) -> None:
        self.rec.set_time(E.TIMELINE, duration=np.timedelta64(int(ns), "ns"))

    def _seen(self, ns: int) -> None:
        self.first_ns = ns if self.first_ns is None else min(self.first_ns, ns)
        self.last_ns = ns if self.last_ns is None else max(self.last_ns, ns)

    def _event(self, ns: int, text: str, level: str = "INFO") -> None:
        self._set_time(ns)
        self.rec.log(E.EVENTS, rr.TextLog(text, level=level))

    def _series_add(self, path: str, ns: np.ndarray, values: np.ndarray) -> None:
        self._series.setdefault(path, _Series()).add(ns, values)

    def _due(self, ns: int) -> None:
        """Flush once ``batch_s`` of simulated time is buffered."""
        if self._batch_start_ns is None:
            self._batch_start_ns = ns
        elif ns - self._batch_start_ns >= self.settings.batch_s * _NS_PER_S:
            self._flush(final=False)
            self._batch_start_ns = ns

    def _flush(self, *, final: bool) -> None:
        self._flush_pivot(final=final)
        for path, series in self._series.items():
            ns, values = series.take()
            if ns.size:
                self.rec.send_columns(
                    path,
                    indexes=[rr.TimeColumn(E.TIMELINE, duration=_durations(ns))],
                    columns=rr.Scalars.columns(scalars=values),
                )

    # -- pivot forces -----------------------------------------------------------------------
    def _on_chunk(self, msg: Any) -> None:
        rate = float(msg.sample_rate_hz)
        if not (math.isfinite(rate) and rate > 0):
            raise RerunSinkError(f"PivotForceChunk sample_rate_hz={rate!r}: allowed > 0")
        first = int(msg.first_sample_index)
        cols = {}
        for side in E.SIDES:
            for series, field in E.PIVOT_MESSAGE_FIELDS.items():
                cols[(side, series)] = np.asarray(getattr(msg, f"{side}_{field}"), dtype=float)
        lengths = {a.size for a in cols.values()}
        if len(lengths) != 1:
            raise RerunSinkError(
                f"PivotForceChunk at sample {first}: arrays of different lengths {sorted(lengths)}"
            )
        n = lengths.pop()
        start_ns = _stamp_ns(msg)
        if self._next_index is not None and first != self._next_index:
            if first < self._next_index:
                self._flush(final=True)
                self._recent.clear()
                self._last_state_index = None
                self._next_frame_ns = 0
                self._event(start_ns, f"simulation restarted at sample {first} (reset)", "WARN")
            else:
                lost = first - self._next_index
                self._event(start_ns, f"{lost} pivot-force samples lost before {first}", "WARN")
        if self._rate_hz is not None and rate != self._rate_hz:
            self._flush(final=True)
        self._rate_hz = rate
        self._next_index = first + n
        if n == 0:
            return
        index = first + np.arange(n, dtype=np.int64)
        self._pending_index.append(index)
        for (side, series), values in cols.items():
            self._pending.setdefault(f"{side}/{series}", []).append(values)
        self._recent.append(
            (first, {s: tuple(cols[(s, k)] for k in ("fx", "fy", "magnitude")) for s in E.SIDES})
        )
        self.samples_logged += n
        end_ns = start_ns + round((n - 1) * _NS_PER_S / rate)
        self._seen(start_ns)
        self._seen(end_ns)
        self._due(end_ns)

    def _flush_pivot(self, *, final: bool) -> None:
        if not self._pending_index or self._rate_hz is None:
            return
        rate = self._rate_hz
        index = np.concatenate(self._pending_index)
        cols = {k: np.concatenate(v) for k, v in self._pending.items()}
        env = self.settings.force_envelope_hz
        bucket = 1 if env is None else max(1, round(rate / env))
        usable = index.size if final or bucket == 1 else (index.size // bucket) * bucket
        self._pending_index = [index[usable:]] if usable < index.size else []
        self._pending = {k: [v[usable:]] for k, v in cols.items()} if usable < index.size else {}
        if usable == 0:
            return
        ns_all = np.rint(index[:usable] * (_NS_PER_S / rate)).astype(np.int64)
        for key, values in cols.items():
            side, series = key.split("/")
            keep = envelope_positions(values[:usable], bucket)
            self.rec.send_columns(
                E.pivot_path(side, series),
                indexes=[rr.TimeColumn(E.TIMELINE, duration=_durations(ns_all[keep]))],
                columns=rr.Scalars.columns(scalars=values[:usable][keep]),
            )

    def _pivot_at(self, index: int) -> dict[str, tuple[float, float]] | None:
        """Pivot force (fx, fy) per side at sample ``index``, if still held."""
        for first, sides in reversed(self._recent):
            k = index - first
            if 0 <= k < sides["left"][0].size:
                return {s: (float(v[0][k]), float(v[1][k])) for s, v in sides.items()}
        return None

    def _peak_since(self, side: str, after: int | None, upto: int) -> tuple[int, float] | None:
        """(index, value) of the largest |F_pivot| of ``side`` in samples (after, upto]."""
        best: tuple[int, float] | None = None
        for first, sides in self._recent:
            mag = sides[side][2]
            idx = first + np.arange(mag.size)
            mask = idx <= upto if after is None else (idx > after) & (idx <= upto)
            if mask.any():
                k = int(np.argmax(np.where(mask, mag, -np.inf)))
                if best is None or mag[k] > best[1]:
                    best = (int(idx[k]), float(mag[k]))
        return best

    # -- states -----------------------------------------------------------------------------
    def _on_state(self, msg: Any) -> None:
        ns = _stamp_ns(msg)
        index = int(msg.sample_index)
        t = np.array([ns], dtype=np.int64)
        one = np.array
        add = self._series_add
        add(f"{E.SPEED}/flywheel", t, one([msg.flywheel_speed_rad_s], float))
        add(f"{E.SPEED}/drum", t, one([msg.drum_speed_rad_s], float))
        add(f"{E.CONTACT}/regime", t, one([int(msg.regime)], float))
        for side in E.SIDES:
            angle = float(getattr(msg, f"{side}_shoe_angle_rad"))
            add(f"{E.SHOE_ANGLE}/{side}", t, one([math.degrees(angle)]))
            add(f"{E.INDENTATION}/{side}", t, one([1e6 * getattr(msg, f"{side}_indentation_m")]))
            normal = float(getattr(msg, f"{side}_normal_force_n"))
            add(f"{E.CONTACT_FORCE}/{side}/normal", t, one([normal]))
            add(
                f"{E.CONTACT_FORCE}/{side}/friction",
                t,
                one([getattr(msg, f"{side}_friction_force_n")], float),
            )
            add(f"{E.ACTUATION}/{side}", t, one([getattr(msg, f"{side}_actuation_force_n")], float))
            add(f"{E.CONTACT}/{side}", t, one([float(bool(getattr(msg, f"{side}_in_contact")))]))
        self._events_at(msg, ns, index)
        if ns >= self._next_frame_ns:
            self._draw(msg, ns, index)
            self._next_frame_ns = ns + round(_NS_PER_S / self.settings.drawing_rate_hz)
        self._last_state, self._last_state_index = msg, index
        # keep only the pivot samples after this state (the next impact's window)
        while len(self._recent) > 1 and _chunk_end(self._recent[0]) <= index:
            self._recent.popleft()
        self.states_logged += 1
        self._seen(ns)
        self._due(ns)

    def _sample_ns(self, index: int, msg: Any) -> int:
        """Time (ns) of sample ``index``, as the pivot-force series times it; without a
        chunk seen yet, scaled from the stamp of ``msg`` (a ContactEvent)."""
        if self._rate_hz is not None:
            return round(index * (_NS_PER_S / self._rate_hz))
        event_index = int(msg.sample_index)
        return _stamp_ns(msg) if event_index == 0 else _stamp_ns(msg) * index // event_index

    def _on_contact_event(self, msg: Any) -> None:
        self._contact_events_seen = True
        ns = _stamp_ns(msg)
        index = int(msg.sample_index)
        shoe = int(msg.shoe)
        side = E.SIDES[shoe] if 0 <= shoe < len(E.SIDES) else None
        if side is None:
            self._event(ns, f"contact event of an unknown shoe {shoe} ignored", "WARN")
            return
        if int(msg.kind) == _KIND_ONSET:
            self.impacts[side] += 1
            pivot = self._pivot_at(index)
            if pivot is not None:
                self._set_time(ns)
                self.rec.log(f"{E.IMPACTS}/{side}", rr.Scalars(float(np.hypot(*pivot[side]))))
            self._event(ns, f"impact: {side} shoe touches the drum (sample {index})")
        else:
            peak = float(msg.peak_pivot_force_n)
            peak_index = int(msg.peak_sample_index)
            peak_ns = self._sample_ns(peak_index, msg)
            self._set_time(peak_ns)
            self.rec.log(E.impact_peak_path(side), rr.Scalars(peak))
            self._event(
                ns,
                f"separation: {side} shoe leaves the drum after"
                f" {1e3 * float(msg.duration_s):.3f} ms; peak |F_pivot| {peak:.0f} N at"
                f" t = {peak_ns / _NS_PER_S:.6f} s",
            )
        self._seen(ns)

    def _events_at(self, msg: Any, ns: int, index: int) -> None:
        prev = self._last_state
        regime = int(msg.regime)
        if prev is None or int(prev.regime) != regime:
            before = "start" if prev is None else _regime_name(int(prev.regime))
            self._event(ns, f"regime: {before} -> {_regime_name(regime)}")
        if self._contact_events_seen:
            return  # impacts come from the ContactEvents, at their exact samples
        for side in E.SIDES:
            # the BrakeState flags are onsets.in_contact of the indentation; an onset is
            # detected between consecutive states by the same rule as in the samples
            now_in = np.array([bool(getattr(msg, f"{side}_in_contact"))])
            was_in = prev is not None and bool(getattr(prev, f"{side}_in_contact"))
            if contact_changes(now_in, before=was_in).onsets.size:
                self.impacts[side] += 1
                peak = self._peak_since(side, self._last_state_index, index)
                text = f"impact: {side} shoe touches the drum (contact onset seen at this state"
                if peak is not None:
                    peak_ns = round(peak[0] * _NS_PER_S / (self._rate_hz or 1.0))
                    text += f"; largest |F_pivot| since the previous state {peak[1]:.0f} N"
                    self._set_time(peak_ns)
                    self.rec.log(f"{E.IMPACTS}/{side}", rr.Scalars(peak[1]))
                self._event(ns, text + ")")

    def _draw(self, msg: Any, ns: int, index: int) -> None:
        actuation = (float(msg.left_actuation_force_n), float(msg.right_actuation_force_n))
        frame = self._drawing.frame(
            shoe_angles_rad=(float(msg.left_shoe_angle_rad), float(msg.right_shoe_angle_rad)),
            drum_angle_rad=float(msg.drum_angle_rad),
            actuation_n=actuation,
        )
        colors = [COLORS[s] for s in E.SIDES]
        self._set_time(ns)
        log = self.rec.log
        d = E.DRAWING
        log(f"{d}/drum", rr.LineStrips2D([frame.drum, frame.drum_marker], colors=[(70, 70, 70)]))
        log(f"{d}/linings", rr.LineStrips2D(list(frame.linings), colors=colors, radii=0.0015))
        log(f"{d}/shoes", rr.LineStrips2D(list(frame.tables), colors=colors, radii=0.0008))
        log(
            f"{d}/pivots",
            rr.Points2D(frame.pivots, radii=0.005, colors=colors, labels=["pivot L", "pivot R"]),
        )
        log(
            f"{d}/actuation",
            rr.Arrows2D(
                origins=frame.actuation_origins,
                vectors=frame.actuation_vectors,
                colors=[(120, 120, 120)],
                labels=[f"{f:.0f} N" for f in actuation],
            ),
        )
        pivot = self._pivot_at(index)
        if pivot is not None:
            vectors = np.array([pivot[s] for s in E.SIDES]) * FORCE_SCALE_M_PER_N
            log(
                f"{d}/pivot_forces",
                rr.Arrows2D(
                    origins=frame.pivots,
                    vectors=vectors,
                    colors=colors,
                    labels=[f"{np.hypot(*pivot[s]):.0f} N" for s in E.SIDES],
                ),
            )
        points, origins, vectors, cols = [], [], [], []
        for side in E.SIDES:
            if bool(getattr(msg, f"{side}_in_contact")):
                p = (
                    float(getattr(msg, f"{side}_contact_x_m")),
                    float(getattr(msg, f"{side}_contact_y_m")),
                )
                normal, friction = contact_force_vectors(
                    p,
                    float(getattr(msg, f"{side}_normal_force_n")),
                    float(getattr(msg, f"{side}_friction_force_n")),
                )
                points.append(p)
                origins += [p, p]
                vectors += [normal, friction]
                cols += [COLORS[side], (200, 40, 40)]
        log(
            f"{d}/contact_points",
            rr.Points2D(np.array(points).reshape(-1, 2), radii=0.004, colors=[(200, 40, 40)]),
        )
        log(
            f"{d}/contact_forces",
            rr.Arrows2D(
                origins=np.array(origins).reshape(-1, 2),
                vectors=np.array(vectors).reshape(-1, 2),
                colors=cols or None,
            ),
        )

    # -- ground truth, commands, diagnostics ------------------------------------------------------
    def _on_defects(self, msg: Any) -> None:
        ns = _stamp_ns(msg)
        sides = {}
        for side in E.SIDES:
            sides[side] = ShoeDefect(
                pivot_radius_change_pct=float(getattr(msg, f"{side}_pivot_radius_change_pct")),
                initial_angle_deg=math.degrees(float(getattr(msg, f"{side}_initial_angle_rad"))),
                actuation_share=float(getattr(msg, f"{side}_actuation_share")),
            )
        try:
            self._drawing = BrakeDrawing(self._params, Defects(**sides))
        except ParameterError as exc:  # keep the previous drawing, say why
            self._event(ns, f"defects not drawn: {exc}", "WARN")
        labels = list(msg.active_defects)
        lines = [
            f"### Defect ground truth — scenario `{msg.scenario}`",
            "",
            "**healthy**" if msg.healthy else "**active:** " + "; ".join(labels),
            "",
            "| | left | right |",
            "|---|---|---|",
            f"| pivot radius (mm) | {1e3 * msg.left_pivot_radius_m:.2f}"
            f" | {1e3 * msg.right_pivot_radius_m:.2f} |",
            f"| pivot radius change (%) | {msg.left_pivot_radius_change_pct:+.2f}"
            f" | {msg.right_pivot_radius_change_pct:+.2f} |",
            f"| initial angle (deg) | {math.degrees(msg.left_initial_angle_rad):+.3f}"
            f" | {math.degrees(msg.right_initial_angle_rad):+.3f} |",
            f"| actuation share | {msg.left_actuation_share:.3f}"
            f" | {msg.right_actuation_share:.3f} |",
            "",
            f"applies from t = {ns / _NS_PER_S:.6f} s",
        ]
        self._set_time(ns)
        self.rec.log(
            f"{E.DEFECTS}/ground_truth",
            rr.TextDocument("\n".join(lines), media_type=rr.MediaType.MARKDOWN),
        )
        for side in E.SIDES:
            d = sides[side]
            for name, value in (
                ("pivot_radius_change_pct", d.pivot_radius_change_pct),
                ("initial_angle_deg", d.initial_angle_deg),
                ("actuation_share", d.actuation_share),
            ):
                self.rec.log(f"{E.DEFECTS}/{side}/{name}", rr.Scalars(value))
        text = "healthy" if msg.healthy else ", ".join(labels)
        self._event(ns, f"defect ground truth ({msg.scenario}): {text}")
        self._seen(ns)

    def _on_actuation(self, msg: Any, ns: int) -> None:
        self._set_time(ns)
        for side in E.SIDES:
            self.rec.log(
                f"{E.ACTUATION}/command/{side}", rr.Scalars(float(getattr(msg, f"{side}_force_n")))
            )

    def _on_diagnostics(self, msg: Any, ns: int) -> None:
        self._set_time(ns)
        for status in msg.status:
            level = _DIAG_LEVELS.get(
                int.from_bytes(status.level, "little")
                if isinstance(status.level, bytes)
                else int(status.level),
                "INFO",
            )
            text = f"{status.name}: {status.message}"
            self.rec.log(f"{E.EVENTS}/diagnostics", rr.TextLog(text, level=level))


def _chunk_end(entry: tuple[int, dict[str, tuple[np.ndarray, ...]]]) -> int:
    first, sides = entry
    return first + sides["left"][2].size


def _regime_name(regime: int) -> str:
    return REGIME_NAMES[regime] if 0 <= regime < len(REGIME_NAMES) else f"unknown ({regime})"
