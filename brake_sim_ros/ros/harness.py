"""Start a brake_sim node in its own process and talk to it over real DDS.

Used by the ROS tests and the benchmark; also a worked example of every interface of the
node. :class:`NodeProcess` starts ``python -m brake_sim_ros.app.node`` as a user would,
isolated on its own ROS domain (localhost only). :class:`SimClient` is an rclpy node in
its own context that subscribes to everything the simulator publishes, publishes
commands, and calls its services and parameter services with bounded waits.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import rclpy
from brake_sim_msgs.msg import (
    ActuationCommand,
    BrakeState,
    ContactEvent,
    DefectState,
    DriveCommand,
    MeasuredChunk,
    PivotForceChunk,
)
from brake_sim_msgs.srv import ResetSimulation, StepSimulation
from diagnostic_msgs.msg import DiagnosticArray
from rcl_interfaces.msg import SetParametersResult
from rcl_interfaces.srv import GetParameters, SetParameters, SetParametersAtomically
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState

from brake_sim_ros import stream
from brake_sim_ros.ros import qos
from brake_sim_ros.stream import conversion
from brake_sim_ros.stream.topics import STREAM_QOS

NODE = "/brake_sim"
# a subscriber's profile for lossless checks: reliable, and a history that keeps whatever
# a busy client has not taken yet (a keep-last reader of depth 1000 lost states when a
# loaded client fell 1000 behind); pair it with the node's deep_history_args
LOSSLESS = QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE)


def domain_id_for(offset: int) -> int:
    """A ROS domain id in 1..100 derived from this process's pid and ``offset``.

    Different offsets (below 100) give different ids within one process; different
    processes (parallel test runs) most likely get different ones too. Under pytest-xdist
    (``PYTEST_XDIST_WORKER`` gwN of ``PYTEST_XDIST_WORKER_COUNT``) worker N draws from its
    own slice of 1..100 (two workers: 1..50 and 51..100), so two workers never share a
    domain; within a slice of width w, offsets differing by a multiple of w share one.
    """
    width, first = 100, 1
    worker = os.environ.get("PYTEST_XDIST_WORKER", "")
    if worker.startswith("gw"):
        count = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
        width = 100 // count
        if width < 10:
            raise RuntimeError(
                f"{count} pytest-xdist workers leave {width} ROS domains each: use -n 10 or fewer"
            )
        index = int(worker[2:])
        first = 1 + index * width
    return first + (os.getpid() + 37 * offset) % width


def deep_history_args(measured: bool = False, depth: int = 1000) -> list[str]:
    """Node arguments that deepen the stream publishers' keep-last histories to ``depth``
    (``qos_overrides``), so that a node run as fast as possible keeps every message for a
    reliable subscriber that is briefly slow (at the default depth of 10 a loaded client
    loses some). ``measured``: ~/measured too (only a node that publishes it declares it)."""
    topics = [stream.PIVOT_FORCES, stream.STATE, stream.JOINT_STATES]
    if measured:
        topics.append(stream.MEASURED)
    args = ["--ros-args"]
    for topic in topics:
        args += ["-p", f"qos_overrides.{topic.name}.publisher.depth:={depth}"]
    return args


def ros_environment(domain_id: int) -> dict[str, str]:
    env = dict(os.environ)
    env["ROS_DOMAIN_ID"] = str(domain_id)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env.pop("ROS_STATIC_PEERS", None)
    env.setdefault("PYTHONUNBUFFERED", "1")
    return env


@dataclass
class NodeProcess:
    """``python -m brake_sim_ros.app.node ARGS`` in a subprocess, output to ``log_path``."""

    proc: subprocess.Popen
    log_path: Path

    @classmethod
    def start(
        cls,
        args: list[str],
        *,
        domain_id: int,
        log_path: Path,
        python: str = sys.executable,
        launch: Callable[..., subprocess.Popen] = subprocess.Popen,
    ) -> NodeProcess:
        """The node started by ``launch`` (:class:`subprocess.Popen`'s signature and what it
        returns: wait, poll, send_signal, kill)."""
        log_path.parent.mkdir(parents=True, exist_ok=True)
        with log_path.open("w") as log:
            proc = launch(
                [python, "-m", "brake_sim_ros.app.node", *args],
                stdout=log,
                stderr=subprocess.STDOUT,
                env=ros_environment(domain_id),
            )
        return cls(proc, log_path)

    @property
    def pid(self) -> int:
        return self.proc.pid

    def output(self) -> str:
        return self.log_path.read_text(errors="replace")

    def wait(self, timeout_s: float) -> int:
        return self.proc.wait(timeout=timeout_s)

    def stop(self, timeout_s: float = 10.0) -> int:
        """SIGINT (a clean rclpy shutdown), then SIGKILL if it does not exit in time."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                return self.proc.wait(timeout=timeout_s)
            except subprocess.TimeoutExpired:
                self.proc.kill()
        return self.proc.wait(timeout=timeout_s)


@dataclass
class Received:
    """Everything a SimClient received, with wall receipt times (time.monotonic)."""

    chunks: list[PivotForceChunk] = field(default_factory=list)
    chunk_times: list[float] = field(default_factory=list)
    states: list[BrakeState] = field(default_factory=list)
    state_times: list[float] = field(default_factory=list)
    joints: list[JointState] = field(default_factory=list)
    contact_events: list[ContactEvent] = field(default_factory=list)
    measured: list[MeasuredChunk] = field(default_factory=list)
    defects: list[DefectState] = field(default_factory=list)
    clocks: list[Clock] = field(default_factory=list)
    diagnostics: list[DiagnosticArray] = field(default_factory=list)

    def clear(self) -> None:
        for value in self.__dict__.values():
            value.clear()


class SimClient:
    """A client of one brake_sim node, in its own rclpy context on ``domain_id``.

    Args:
        domain_id: ROS domain of the node.
        stream_qos: QoS of the stream subscriptions (REP 2003 consumer profile by default;
            a reliable profile for lossless checks).
        keep_chunks: store every chunk (False: only count them, for long runs).
    """

    def __init__(
        self,
        domain_id: int,
        *,
        stream_qos: QoSProfile = qos.STREAM_CONSUMER,
        keep_chunks: bool = True,
        node: str = NODE,
    ) -> None:
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node("brake_sim_client", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.rx = Received()
        self.keep_chunks = keep_chunks
        self.chunk_count = 0
        self.measured_count = 0
        self.sample_count = 0
        self.gaps = 0
        self._next_index: int | None = None
        n = self.node
        self._stream_topics = (
            f"{node}/pivot_forces",
            f"{node}/state",
            f"{node}/joint_states",
            f"{node}/contact_events",
        )  # ~/measured too, but only when the node's publish_measured is on: not waited for
        n.create_subscription(PivotForceChunk, f"{node}/pivot_forces", self._on_chunk, stream_qos)
        n.create_subscription(BrakeState, f"{node}/state", self._on_state, stream_qos)
        n.create_subscription(JointState, f"{node}/joint_states", self.rx.joints.append, stream_qos)
        n.create_subscription(MeasuredChunk, f"{node}/measured", self._on_measured, stream_qos)
        # reliable like the node's publisher: every label matters (see stream.topics.EVENTS_QOS)
        n.create_subscription(
            ContactEvent,
            f"{node}/contact_events",
            self.rx.contact_events.append,
            qos.for_topic(stream.CONTACT_EVENTS),
        )
        # latched as the node offers it, but deep: a run whose defects grow publishes several
        # states within one chunk, and a depth of 1 keeps only the newest a busy client
        # has not taken yet
        every_state = qos.for_topic(stream.DEFECTS)
        every_state.depth = 100
        n.create_subscription(DefectState, f"{node}/defects", self.rx.defects.append, every_state)
        n.create_subscription(Clock, "/clock", self.rx.clocks.append, qos.for_topic(stream.CLOCK))
        n.create_subscription(
            DiagnosticArray,
            "/diagnostics",
            self.rx.diagnostics.append,
            qos.for_topic(stream.DIAGNOSTICS),
        )
        self.actuation = n.create_publisher(
            ActuationCommand, f"{node}/actuation", qos.profile(STREAM_QOS)
        )
        self.drive_commands = n.create_publisher(
            DriveCommand, f"{node}/drive", qos.profile(STREAM_QOS)
        )
        self._step = n.create_client(StepSimulation, f"{node}/step")
        self._reset = n.create_client(ResetSimulation, f"{node}/reset")
        self._set = n.create_client(SetParameters, f"{node}/set_parameters")
        self._set_atomic = n.create_client(
            SetParametersAtomically, f"{node}/set_parameters_atomically"
        )
        self._get = n.create_client(GetParameters, f"{node}/get_parameters")

    # -- receiving ------------------------------------------------------------------------
    def _on_chunk(self, msg: PivotForceChunk) -> None:
        now = time.monotonic()
        first = msg.first_sample_index
        if self._next_index is not None and first != self._next_index:
            self.gaps += 1
        self._next_index = first + len(msg.left_fx_n)
        self.chunk_count += 1
        self.sample_count += len(msg.left_fx_n)
        if self.keep_chunks:
            self.rx.chunks.append(msg)
            self.rx.chunk_times.append(now)

    def _on_measured(self, msg: MeasuredChunk) -> None:
        self.measured_count += 1
        if self.keep_chunks:
            self.rx.measured.append(msg)

    def _on_state(self, msg: BrakeState) -> None:
        self.rx.states.append(msg)
        self.rx.state_times.append(time.monotonic())

    @property
    def next_sample_index(self) -> int | None:
        """Index the next chunk should start at (None before the first chunk)."""
        return self._next_index

    def forget(self) -> None:
        """Drop what was received so far (counters and gap tracking too)."""
        self.rx.clear()
        self.chunk_count = self.sample_count = self.gaps = 0
        self._next_index = None

    def spin_for(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=min(0.05, max(0.0, end - time.monotonic())))

    def wait_for(self, predicate: Callable[[], bool], timeout_s: float, what: str) -> None:
        """Spin until ``predicate()`` holds; TimeoutError naming ``what`` otherwise."""
        end = time.monotonic() + timeout_s
        while not predicate():
            if time.monotonic() > end:
                raise TimeoutError(f"no {what} within {timeout_s:g} s")
            self.executor.spin_once(timeout_sec=0.05)

    def wait_for_node(self, timeout_s: float = 30.0) -> None:
        """Wait until the node is up and discovered both ways.

        Its latched ground truth arrived, its services answer, its readers of our commands
        (actuation and drive) matched our writers and we see its stream publishers. A node that
        starts running at once publishes before any subscriber has matched (volatile
        topics do not replay), so start it paused and unpause it after this to receive its
        stream from sample 0.
        """
        self.wait_for(lambda: bool(self.rx.defects), timeout_s, "DefectState from the node")
        for client in (self._step, self._reset, self._set, self._set_atomic, self._get):
            self.wait_for(client.service_is_ready, timeout_s, f"service {client.srv_name}")
        # matched to our own publisher, not only seen in the graph: a command published
        # before the node's reader matched our writer is lost (volatile), and the graph
        # can show the reader first under load
        for commands in (self.actuation, self.drive_commands):
            self.wait_for(
                lambda commands=commands: commands.get_subscription_count() > 0,
                timeout_s,
                f"subscriber of {commands.topic_name} matched to our publisher",
            )
        for topic in self._stream_topics:
            self.wait_for(
                lambda topic=topic: self.node.count_publishers(topic) > 0,
                timeout_s,
                f"publisher of {topic}",
            )

    def diagnostics(self) -> dict[str, str]:
        """Key-values of the newest /diagnostics status of the node ({} if none yet)."""
        for array in reversed(self.rx.diagnostics):
            for status in array.status:
                if status.hardware_id == "brake_sim":
                    return {kv.key: kv.value for kv in status.values}
        return {}

    def next_diagnostics(self, timeout_s: float = 5.0) -> dict[str, str]:
        """Wait for a /diagnostics message newer than now and return its key-values."""
        count = len(self.rx.diagnostics)
        self.wait_for(lambda: len(self.rx.diagnostics) > count, timeout_s, "/diagnostics")
        return self.diagnostics()

    # -- acting ------------------------------------------------------------------------------
    def command(self, left_n: float, right_n: float) -> None:
        self.actuation.publish(
            ActuationCommand(left_force_n=float(left_n), right_force_n=float(right_n))
        )

    def drive(self, mode: int, *, torque_n_m: float = 0.0, speed_m_s: float = 0.0) -> None:
        """Publish a DriveCommand: ``mode`` one of DriveCommand.MODE_* (any number: the
        node checks it)."""
        self.drive_commands.publish(
            DriveCommand(
                mode=int(mode),
                drive_torque_n_m=float(torque_n_m),
                target_speed_m_s=float(speed_m_s),
            )
        )

    def _call(self, client, request, timeout_s: float):
        future = client.call_async(request)
        self.wait_for(future.done, timeout_s, f"response from {client.srv_name}")
        return future.result()

    def step(self, steps: int = 0, duration_s: float = 0.0, timeout_s: float = 30.0):
        return self._call(
            self._step, StepSimulation.Request(steps=steps, duration_s=duration_s), timeout_s
        )

    def reset(self, scenario: str = "", seed: int = -1, timeout_s: float = 30.0):
        return self._call(
            self._reset, ResetSimulation.Request(scenario=scenario, seed=seed), timeout_s
        )

    def set_parameters(self, values: dict, timeout_s: float = 10.0) -> list[SetParametersResult]:
        """One SetParameters request; one result per parameter, in order."""
        request = SetParameters.Request(
            parameters=[Parameter(k, value=v).to_parameter_msg() for k, v in values.items()]
        )
        return list(self._call(self._set, request, timeout_s).results)

    def set_parameter(self, name: str, value, timeout_s: float = 10.0) -> SetParametersResult:
        return self.set_parameters({name: value}, timeout_s)[0]

    def set_parameters_atomically(
        self, values: dict, timeout_s: float = 10.0
    ) -> SetParametersResult:
        request = SetParametersAtomically.Request(
            parameters=[Parameter(k, value=v).to_parameter_msg() for k, v in values.items()]
        )
        return self._call(self._set_atomic, request, timeout_s).result

    def get_parameters(self, names: list[str], timeout_s: float = 10.0) -> dict:
        response = self._call(self._get, GetParameters.Request(names=names), timeout_s)
        return {
            name: Parameter.from_parameter_msg(_named(name, value)).value
            for name, value in zip(names, response.values, strict=True)
        }

    # -- collected data ------------------------------------------------------------------------
    def chunk_arrays(self) -> dict[str, np.ndarray]:
        """Received chunks concatenated: first indices checked contiguous by the caller."""
        names = conversion.PIVOT_CHUNK_ARRAYS
        out = {
            name: np.concatenate([np.asarray(getattr(c, name)) for c in self.rx.chunks])
            for name in names
        }
        out["index"] = np.concatenate(
            [c.first_sample_index + np.arange(len(c.left_fx_n)) for c in self.rx.chunks]
        )
        return out

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


def _named(name: str, value):
    from rcl_interfaces.msg import Parameter as ParameterMsg

    return ParameterMsg(name=name, value=value)
