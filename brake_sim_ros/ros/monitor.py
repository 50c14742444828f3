"""A brake-health monitor as a ROS 2 node: :class:`MonitorNode` (a leaf adapter).

It runs one detector (the streaming contract of :mod:`brake_sim_ros.detection.detector`,
handed in by the composition root with the function that turns a ``MeasuredChunk`` into
the detector's input) over the measured channels of a brake, and publishes what the
detector says. It knows nothing of the detector's method; it translates and guards.

Run it with ``brake-sim monitor --detector NAME`` (:mod:`brake_sim_ros.app.monitor`).

Topics (node name ``brake_monitor``; ``~`` = ``/brake_monitor``):
    <simulator>/measured brake_sim_msgs/MeasuredChunk   (subscribed) the measured channels;
                                                       any publisher of that name and type
                                                       (the simulator, a replay, a real
                                                       brake's driver)
    <simulator>/defects  brake_sim_msgs/DefectState     (subscribed, optional) only its
                                                       run_id and unit_id are read, to label
                                                       the outputs; no ground truth is used
    ~/health             brake_sim_msgs/HealthAssessment one per detector window
    ~/diagnoses          brake_sim_msgs/Diagnosis       when the detector diagnoses a defect
    /diagnostics         diagnostic_msgs/DiagnosticArray every diagnostics_period_s (wall)

Windows are aligned to the sample index (detector contract), so a window's assessment is
the same live, replayed or offline. Each message is checked: a malformed one (fields that
do not fit together), one that repeats or goes back in the sample index (out of order),
a gap (lost samples: the detector restarts at the next aligned window), a detector that
raises, or a diagnosis outside the defect catalogue each give one warning line and a
counter in /diagnostics; the node keeps running. A message starting again at sample 0, or
at another sample rate, is a new run (the simulator was reset): the detector restarts.

Samples the detector cannot judge at all stop the node (:attr:`MonitorNode.refusal`, one
line; ``brake-sim monitor`` exits 2): samples at another rate than it was fitted at, or,
for a detector that recorded the brake it was fitted on, a stream from the other brake.
No message says which brake it is: the monitor asks the stream's publisher (the simulator's
or a replay's read-only parameter ``brake``, :mod:`.monitor_brake`) before it judges the
first window and at each new run (a ``~/reset`` may switch brakes), holding the samples
meanwhile. The parameter ``brake`` declares it for a stream whose publisher cannot say it
(a driver); a declared brake the node contradicts is refused, naming both.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from brake_sim_msgs.msg import DefectState, Diagnosis, HealthAssessment, MeasuredChunk
from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.srv import GetParameters
from rclpy.clock import Clock, ClockType
from rclpy.exceptions import (
    InvalidServiceNameException,
    InvalidTopicNameException,
    ParameterException,
)
from rclpy.node import Node
from rclpy.parameter import Parameter
from std_msgs.msg import Header

from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.model.catalogue import KIND_BY_NAME
from brake_sim_ros.model.parameters import BRAKES
from brake_sim_ros.ros import qos
from brake_sim_ros.ros.descriptors import descriptor
from brake_sim_ros.ros.monitor_brake import BrakeQuery, StreamBrake
from brake_sim_ros.stream.conversion import stamp_ns, time_msg
from brake_sim_ros.stream.parameters import ParamSpec
from brake_sim_ros.stream.topics import (
    DIAGNOSTICS,
    EVENTS_QOS,
    LATCHED_QOS,
    QosSpec,
    Topic,
)

NODE_NAME = "brake_monitor"
_NS_PER_S = 1_000_000_000
MAX_STAMP_NS = 2**31 * _NS_PER_S  # builtin_interfaces/Time holds int32 seconds
MAX_ID_CHARS = 128  # run and unit ids longer than this (from the wire) are cut
# a stamp this much earlier than sample 0's time is float rounding in the publisher's
# stamp (its time since sample 0 computed in float64), not a malformed message
STAMP_ROUNDING_NS = 1_000
FAULT_SUMMARY_S = 10.0  # after a fault's first line, its count at most once per this (wall)
MAX_WINDOW_SAMPLES = 1 << 22  # detection.detector's: the node imports nothing of it
MAX_WINDOW_S = 60.0
# messages held while the stream's brake is asked (a bounded wait: 200 s of 10 Hz chunks);
# those past it are dropped, and counted as a gap when the next is judged
MAX_HELD = 2000

# The monitor wants every sample: a reliable subscription with room for 10 s of the
# simulator's 10 Hz chunks, so a briefly busy monitor loses nothing (a loss would show as
# a gap and cost the windows around it). It matches the simulator's reliable publisher.
MEASURED_QOS = QosSpec("reliable", "volatile", 100)
# The monitor's own topics (a second node's, so not in the simulator's table of
# stream.topics, in the same form). Verdicts are offered reliable with a deep history: a
# scorer or a logger wants every window, and 100 is 10 s of the baselines' windows.
HEALTH = Topic(
    f"/{NODE_NAME}/health",
    "brake_sim_msgs/msg/HealthAssessment",
    QosSpec("reliable", "volatile", 100),
    "one per detector window (window_s of simulated time, 0.1 s for the baselines)",
    "~/health",
)
DIAGNOSES = Topic(
    f"/{NODE_NAME}/diagnoses",
    "brake_sim_msgs/msg/Diagnosis",
    EVENTS_QOS,
    "one per window the detector diagnoses",
    "~/diagnoses",
)
MONITOR_TOPICS = (HEALTH, DIAGNOSES, DIAGNOSTICS)


def parameter_specs() -> list[ParamSpec]:
    fixed = "Fixed at start-up."
    return [
        ParamSpec(
            "simulator",
            "/brake_sim",
            "Fully qualified name of the node whose <name>/measured (and <name>/defects, for"
            " the run and unit id) the monitor reads. " + fixed,
        ),
        ParamSpec(
            "measured_topic",
            "",
            "MeasuredChunk topic to monitor; empty: <simulator>/measured. " + fixed,
        ),
        ParamSpec(
            "defects_topic",
            "",
            "DefectState topic whose run_id/unit_id label the outputs; empty:"
            " <simulator>/defects. " + fixed,
        ),
        ParamSpec(
            "unit_id",
            "",
            "Brake unit id written into every output; empty: the one DefectState gives. " + fixed,
        ),
        ParamSpec(
            "brake",
            "",
            "The brake the measured samples come from: study or service (a scenario's"
            " brake); empty: asked of the node that publishes them (the simulator's or a"
            " replay's parameter brake), which must say the same when it is given. A"
            " detector fitted on one brake's samples refuses the other's, and a stream whose"
            " brake is neither declared nor said by its publisher (a driver). " + fixed,
            constraints=f"one of {', '.join(BRAKES)}, or empty",
        ),
        ParamSpec(
            "warn_level",
            0.8,
            "Health index (dimensionless, 1 = alarm) from which /diagnostics says WARN. " + fixed,
            (0.0, 1.0),
        ),
        ParamSpec(
            "diagnostics_period_s",
            1.0,
            "Wall seconds between /diagnostics messages. " + fixed,
            (0.05, 60.0),
        ),
    ]


class StreamingDetector(Protocol):
    """What the node needs of a detector (:class:`brake_sim_ros.detection.detector.
    Detector` has it)."""

    name: str

    def window_samples(self, sample_rate_hz: float) -> int: ...

    def feed(self, chunk: Any) -> list[Any]: ...

    def reset(self) -> None: ...

    def rate_refusal(self, sample_rate_hz: float) -> str | None: ...

    def brake_refusal(self, brake: str, where: str) -> str | None: ...


@dataclass
class MonitorStats:
    """Counters since the node started (reported in /diagnostics)."""

    chunks: int = 0  # MeasuredChunks fed to the detector
    windows: int = 0  # assessments published
    alarms: int = 0  # of which alarms
    diagnoses: int = 0  # diagnoses published
    malformed: int = 0  # messages dropped: fields that do not fit together
    out_of_order: int = 0  # messages dropped: repeated or earlier sample index
    gaps: int = 0  # jumps forward in the sample index
    samples_lost: int = 0  # samples those jumps skipped
    runs: int = 0  # runs seen (a restart at sample 0, or a new rate, begins one)
    detector_failures: int = 0  # chunks whose feed() raised
    diagnoses_refused: int = 0  # diagnoses outside the defect catalogue
    windows_too_long: int = 0  # messages dropped: a rate whose window exceeds the buffer
    warning_lines: int = 0  # warning lines logged (one per kind of fault, then counts)
    last_warning: str = ""


@dataclass
class PeriodView:
    """What happened since the last /diagnostics message."""

    windows: int = 0
    alarms: int = 0
    max_health: float = -math.inf
    warnings: int = 0


def health_level(period: PeriodView, stats: MonitorStats, warn_level: float) -> tuple[bytes, str]:
    """The /diagnostics level and message of one period: ERROR on an alarm, WARN from
    ``warn_level`` or on dropped input, STALE without windows, OK otherwise."""
    if period.alarms:
        return DiagnosticStatus.ERROR, (
            f"ALARM in {period.alarms} of {period.windows} windows (health index up to"
            f" {period.max_health:.3g})"
        )
    if period.windows == 0:
        if stats.windows == 0:
            return DiagnosticStatus.STALE, "no window assessed yet: waiting for samples"
        return DiagnosticStatus.STALE, "no window assessed in the last period"
    text = f"{period.windows} windows, health index up to {period.max_health:.3g}"
    if not period.max_health < warn_level:  # NaN too: a detector giving no number
        return DiagnosticStatus.WARN, f"{text} (warn level {warn_level:g})"
    if period.warnings:
        return (
            DiagnosticStatus.WARN,
            f"{text}; {period.warnings} input warnings: {stats.last_warning}",
        )
    return DiagnosticStatus.OK, text


def _id_text(value: str) -> str:
    return "".join(c for c in value[:MAX_ID_CHARS] if c.isprintable())


def _stamp_ns(stamp: Time) -> int:
    return int(stamp.sec) * _NS_PER_S + int(stamp.nanosec)


class MonitorNode(StreamBrake, Node):
    """Feeds ``~/measured`` to ``detector`` and publishes its verdicts (module docstring).

    Args:
        detector: fitted, ready to :meth:`feed`.
        to_chunk: MeasuredChunk -> the detector's input chunk; raises ValueError on a
            malformed message (:func:`brake_sim_ros.detection.detector.chunk_from_measured`).
        parameter_overrides: values that replace the parameters' defaults.
        context: the rclpy context (default: the global one).

    Raises:
        BrakeSimError: a parameter out of range or a topic name ROS does not accept.
    """

    def __init__(
        self,
        detector: StreamingDetector,
        to_chunk: Callable[[Any], Any],
        *,
        parameter_overrides: list[Parameter] | None = None,
        context: Any = None,
    ) -> None:
        super().__init__(NODE_NAME, parameter_overrides=parameter_overrides or [], context=context)
        self.detector = detector
        self._to_chunk = to_chunk
        self.stats = MonitorStats()
        self._period = PeriodView()
        for spec in parameter_specs():
            try:
                self.declare_parameter(spec.name, spec.default, descriptor(spec))
            except ParameterException as exc:  # a bad --ros-args override
                raise BrakeSimError(f"--ros-args override refused: {exc}") from None
        p = {spec.name: self.get_parameter(spec.name).value for spec in parameter_specs()}
        simulator = str(p["simulator"]).rstrip("/")
        self.measured_topic = str(p["measured_topic"]) or f"{simulator}/measured"
        self.defects_topic = str(p["defects_topic"]) or f"{simulator}/defects"
        self.unit_id_fixed = _id_text(str(p["unit_id"]))
        self.brake = str(p["brake"])
        if self.brake not in ("", *BRAKES):
            raise BrakeSimError(
                f"brake {self.brake[:40]!r}: allowed {', '.join(BRAKES)} or empty (not declared)"
            )
        self.warn_level = float(p["warn_level"])
        period_s = float(p["diagnostics_period_s"])
        if not 0.0 <= self.warn_level <= 1.0:
            raise BrakeSimError(f"warn_level {self.warn_level!r}: allowed 0 to 1")
        if not (math.isfinite(period_s) and 0.05 <= period_s <= 60.0):
            raise BrakeSimError(f"diagnostics_period_s {period_s!r}: allowed 0.05 to 60 s")
        self.run_id = ""
        self.unit_id = self.unit_id_fixed
        # why the node stops: samples at another rate than the detector was fitted at, or
        # from another brake than it was fitted on (a declared one is known at start)
        self.refusal: str | None = None
        if self.brake:
            where = f"the stream on {self.measured_topic}"
            self.refusal = detector.brake_refusal(self.brake, where)
        if self.refusal is not None:
            self.get_logger().error(self.refusal)
        # the brake the stream comes from, as the simulator said it ("": not said)
        self.stream_brake = ""
        # asked when declared (the simulator must agree) or when the detector records one
        self._asks_brake = bool(self.brake) or detector.brake_refusal("", "") is not None
        self._brake_query: BrakeQuery | None = None
        self._held: list[MeasuredChunk] = []
        self._next_index: int | None = None
        self._rate: float | None = None
        self._last_stamp_ns = 0
        self._last_assessment: HealthAssessment | None = None
        self._faults: dict[str, _FaultLog] = {}
        # what the monitor buffers: a window, and a history detector's last history_s
        for attribute in ("window_s", "history_s"):
            seconds = getattr(detector, attribute, None)
            if attribute == "history_s" and seconds is None:
                continue
            if isinstance(seconds, int | float) and not 0.0 < seconds <= MAX_WINDOW_S:
                raise BrakeSimError(
                    f"detector {detector.name}: {attribute} {seconds!r}; allowed more than 0"
                    f" up to {MAX_WINDOW_S:g} s (the monitor buffers it)"
                )
        try:
            self.create_subscription(
                MeasuredChunk, self.measured_topic, self._on_measured, qos.profile(MEASURED_QOS)
            )
            self.create_subscription(
                DefectState, self.defects_topic, self._on_defects, qos.profile(LATCHED_QOS)
            )
            self._health = self.create_publisher(
                HealthAssessment, HEALTH.relative, qos.for_topic(HEALTH)
            )
            self._diagnoses = self.create_publisher(
                Diagnosis, DIAGNOSES.relative, qos.for_topic(DIAGNOSES)
            )
            self._parameters = self.create_client(GetParameters, f"{simulator}/get_parameters")
        except (InvalidTopicNameException, InvalidServiceNameException):
            shown = f"{self.measured_topic[:80]!r}, {self.defects_topic[:80]!r}, {simulator[:80]!r}"
            raise BrakeSimError(
                f"topics {shown}: not names ROS accepts (allowed e.g. /brake_sim/measured)"
            ) from None
        self.simulator = simulator
        if self._asks_brake and self.refusal is None:
            self._ask_brake()
        self.create_timer(0.1, self._poll_brake, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self._diagnostics = self.create_publisher(
            DiagnosticArray, DIAGNOSTICS.name, qos.for_topic(DIAGNOSTICS)
        )
        # on the steady wall clock, whatever use_sim_time says: a replay's /clock may stop
        self.create_timer(
            period_s, self._publish_diagnostics, clock=Clock(clock_type=ClockType.STEADY_TIME)
        )

    def published_topics(self) -> list[str]:
        """The resolved names the node publishes on."""
        return [p.topic_name for p in (self._health, self._diagnoses, self._diagnostics)]

    # -- input ---------------------------------------------------------------------------
    def _warn(self, kind: str, text: str) -> None:
        """One fault of ``kind``: its first is logged at once, the next ones are counted
        and logged as a count at most every :data:`FAULT_SUMMARY_S` (a flood of bad
        messages gives a few lines, not one per message)."""
        self.stats.last_warning = text
        self._period.warnings += 1
        log = self._faults.setdefault(kind, _FaultLog())
        if log.logged_at is None:
            log.logged_at = time.monotonic()
            self._log(f"{text} (more {kind} are counted, one line every {FAULT_SUMMARY_S:g} s)")
            return
        log.unreported += 1
        log.latest = text
        self._summarise(kind, log)

    def _summarise(self, kind: str, log: _FaultLog, *, now: float | None = None) -> None:
        now = time.monotonic() if now is None else now
        if log.unreported and log.logged_at is not None and now - log.logged_at >= FAULT_SUMMARY_S:
            self._log(
                f"{log.unreported} more {kind} in the last {now - log.logged_at:.0f} s; the"
                f" latest: {log.latest}"
            )
            log.unreported, log.logged_at = 0, now

    def _log(self, text: str) -> None:
        self.stats.warning_lines += 1
        self.get_logger().warning(text)

    def _on_defects(self, msg: DefectState) -> None:
        self.run_id = _id_text(msg.run_id)
        if not self.unit_id_fixed:
            self.unit_id = _id_text(msg.unit_id)

    def _on_measured(self, msg: MeasuredChunk) -> None:
        if self.refusal is not None:
            return
        new_run = self._next_index is not None and (
            (msg.first_sample_index == 0 and self._next_index > 0)
            or msg.sample_rate_hz != self._rate
        )
        if new_run and self._asks_brake and self._brake_query is None and not self._held:
            self._ask_brake()  # a ~/reset may have loaded a scenario of the other brake
        if self._brake_query is not None:
            self._brake_query.heard()
            if len(self._held) < MAX_HELD:
                self._held.append(msg)
            return
        self._judge(msg)

    def _judge(self, msg: MeasuredChunk) -> None:
        try:
            chunk = self._to_chunk(msg)
            first, rate = chunk.first_sample_index, chunk.sample_rate_hz
            # The chunk's stamp is the time of its first sample: the stream's clock is that
            # stamp less the first sample's time since sample 0 (0 for the simulator), and
            # a window's time is its last sample's on that clock, by the simulator's rule.
            epoch_ns = _stamp_ns(msg.header.stamp) - stamp_ns(first, 1.0 / rate)
            if -STAMP_ROUNDING_NS <= epoch_ns < 0:
                epoch_ns = 0  # stamped a rounding early: the stream's clock starts at 0
            if not (
                epoch_ns >= 0 and epoch_ns + stamp_ns(first + len(chunk), 1.0 / rate) < MAX_STAMP_NS
            ):
                raise ValueError("its stamp and sample index give times outside 0 to 2^31 s")
        except (ValueError, ArithmeticError) as exc:
            self.stats.malformed += 1
            self._warn(
                "malformed messages",
                f"dropped a malformed MeasuredChunk on {self.measured_topic}: {exc}",
            )
            return
        refusal = self.detector.rate_refusal(rate)
        if refusal is not None:  # every verdict would be wrong: stop, do not warn and run on
            self.refusal = refusal
            self.get_logger().error(refusal)
            return
        if self._next_index is None or (first == 0 and self._next_index > 0) or rate != self._rate:
            self.stats.runs += 1
            self.detector.reset()
            if self._next_index is not None:
                self.get_logger().info(f"a new run at sample {first} ({rate:g} Hz)")
            if first > 0:  # the run's first samples were sent before this monitor heard them
                self.stats.gaps += 1
                self.stats.samples_lost += first
                self._warn(
                    "late joins",
                    f"samples 0 to {first - 1} of the run never arrived (the monitor joined"
                    " late: start it before the node, or the node with"
                    " measured_subscribers:=1)",
                )
        elif first < self._next_index:
            self.stats.out_of_order += 1
            self._warn(
                "out-of-order messages",
                f"dropped a MeasuredChunk out of order: it starts at sample {first}, the next"
                f" expected is {self._next_index}",
            )
            return
        elif first > self._next_index:
            self.stats.gaps += 1
            self.stats.samples_lost += first - self._next_index
            self._warn(
                "gaps",
                f"samples {self._next_index} to {first - 1} never arrived; the detector"
                " restarts at its next aligned window",
            )
        self._next_index, self._rate = first + len(chunk), rate
        if not self._window_fits(rate):
            return
        try:
            assessments = self.detector.feed(chunk)
        except Exception as exc:  # a user's detector may raise anything: one line, run on
            self.stats.detector_failures += 1
            text = " ".join(str(exc).split())[:300]
            # a detector that fails once fails on every chunk (a channel it needs is
            # missing, say): one line every 10 s, the counter counts each
            self._warn(
                "detector failures",
                f"detector {self.detector.name} failed on samples from {first}: {text}",
            )
            return
        self.stats.chunks += 1
        n = self.detector.window_samples(rate)
        for a in assessments:
            ns = epoch_ns + stamp_ns(int(a.sample_index), 1.0 / rate)
            self._publish(a, Header(stamp=time_msg(ns), frame_id=msg.header.frame_id), n, rate)
            self._last_stamp_ns = ns

    def _window_fits(self, rate: float) -> bool:
        """Whether the detector's window at ``rate`` fits the buffer; else the message is
        dropped and counted (a publisher at 1e12 Hz would have it buffer without end)."""
        try:
            n = int(self.detector.window_samples(rate))
        except (ValueError, ArithmeticError, TypeError, OverflowError):
            n = MAX_WINDOW_SAMPLES + 1
        if n <= MAX_WINDOW_SAMPLES:
            return True
        self.stats.windows_too_long += 1
        self._warn(
            "messages at a rate too high for the window",
            f"dropped a MeasuredChunk at {rate:g} Hz: detector {self.detector.name}'s window"
            f" would be {n} samples, more than the {MAX_WINDOW_SAMPLES} the monitor buffers",
        )
        return False

    # -- output --------------------------------------------------------------------------
    def _diagnosis(self, a: Any, header: Header) -> Diagnosis | None:
        d = a.diagnosis
        if d is None:
            return None
        kind = KIND_BY_NAME.get(d.kind)
        if kind is None or d.location not in kind.locations:
            self.stats.diagnoses_refused += 1
            self._warn(
                "diagnoses outside the catalogue",
                f"detector {self.detector.name} diagnosed kind {str(d.kind)[:60]!r} at"
                f" {str(d.location)[:60]!r}: not in the defect catalogue (brake-sim defects);"
                " not published",
            )
            return None
        return Diagnosis(
            header=header,
            run_id=self.run_id,
            unit_id=self.unit_id,
            detector=self.detector.name,
            sample_index=int(a.sample_index),
            kind=kind.name,
            location=d.location,
            severity=float(d.severity),
            unit=kind.unit,
            confidence=float(d.confidence),
        )

    def _publish(self, a: Any, header: Header, window: int, rate: float) -> None:
        diagnosis = self._diagnosis(a, header)
        health = HealthAssessment(
            header=header,
            run_id=self.run_id,
            unit_id=self.unit_id,
            detector=self.detector.name,
            first_sample_index=max(0, int(a.sample_index) - window + 1),
            last_sample_index=int(a.sample_index),
            sample_rate_hz=rate,
            health_index=float(a.health_index),
            alarm=bool(a.alarm),
            has_diagnosis=diagnosis is not None,
            rul_s=float(a.rul_s),
        )
        self._health.publish(health)
        if diagnosis is not None:
            self._diagnoses.publish(diagnosis)
            self.stats.diagnoses += 1
        self._last_assessment = health
        self.stats.windows += 1
        self.stats.alarms += health.alarm
        self._period.windows += 1
        self._period.alarms += health.alarm
        h = health.health_index
        self._period.max_health = h if math.isnan(h) else max(self._period.max_health, h)

    def diagnostic_array(self) -> DiagnosticArray:
        """One DiagnosticStatus ``<node>: health`` for the period since the last one;
        stamp = the last window's (0 before any)."""
        level, message = health_level(self._period, self.stats, self.warn_level)
        last = self._last_assessment
        values = {
            "detector": self.detector.name,
            "measured_topic": self.measured_topic,
            "run_id": self.run_id,
            "unit_id": self.unit_id,
            "last_first_sample_index": "" if last is None else str(last.first_sample_index),
            "last_sample_index": "" if last is None else str(last.last_sample_index),
            "last_health_index": "" if last is None else f"{last.health_index:.6g}",
            "last_alarm": "" if last is None else str(last.alarm).lower(),
            "last_rul_s": "" if last is None else f"{last.rul_s:.6g}",
            "warn_level": f"{self.warn_level:g}",
            "brake": self.stream_brake or self.brake,
            "held_for_brake": str(len(self._held)),
            **{k: str(v) for k, v in vars(self.stats).items()},
        }
        status = DiagnosticStatus(
            level=level,
            name=f"{self.get_fully_qualified_name()}: health",
            message=message,
            hardware_id=self.unit_id or "brake",
            values=[KeyValue(key=k, value=v) for k, v in values.items()],
        )
        return DiagnosticArray(header=Header(stamp=time_msg(self._last_stamp_ns)), status=[status])

    def _publish_diagnostics(self) -> None:
        self._diagnostics.publish(self.diagnostic_array())
        self._period = PeriodView()
        for kind, log in self._faults.items():  # counts of a flood that has stopped, too
            self._summarise(kind, log)


@dataclass
class _FaultLog:
    """One kind of fault's logging: when its last line was written, how many since."""

    logged_at: float | None = None
    unreported: int = 0
    latest: str = ""
