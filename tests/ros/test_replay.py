"""``brake-sim replay``: a subscriber receives what was recorded, in order and in time.

A recording is made offline, replayed by ``brake-sim replay`` in its own process over
real DDS, and received by raw (CDR bytes) subscriptions in this process.
"""

from __future__ import annotations

import contextlib
import re
import subprocess
import sys
import time
from collections import defaultdict
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
import rclpy
from mcap.reader import make_reader
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.serialization import deserialize_message

from brake_sim_ros import stream
from brake_sim_ros.ros import qos
from brake_sim_ros.ros.harness import LOSSLESS, domain_id_for, ros_environment
from brake_sim_ros.ros.messages import message_class
from tests import cli_process

pytestmark = pytest.mark.realtime  # arrival times against the recording's log times

DURATION_S = 1.5
# Timing tolerance of a replayed message against its recorded log time (wall s at rate 1).
# The replay sleeps to each message's due time (sub-ms on Linux) and loopback DDS adds
# about a millisecond; on a loaded 2-core CI machine a wake-up can be late by a few tens
# of ms, so single messages get a generous bound and the typical one a tight bound.
TYPICAL_LATE_S = 0.010  # median |arrival - due|
WORST_LATE_S = 0.150  # any message


def _record(path: Path, duration_s: float) -> None:
    cli_process.run(
        [
            sys.executable,
            "-m",
            "brake_sim_ros.cli",
            "simulate",
            "symmetric",
            "--duration",
            str(duration_s),
            "--mcap",
            str(path),
            "--quiet",
        ],
        capture_output=True,
        check=True,
    )


def _recorded(path: Path) -> list[tuple[str, bytes, int]]:
    with path.open("rb") as f:
        return [
            (channel.topic, bytes(message.data), message.log_time)
            for _s, channel, message in make_reader(f).iter_messages(log_time_order=True)
        ]


@pytest.fixture(scope="module")
def recording(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("replay") / "symmetric.mcap"
    _record(path, DURATION_S)
    return path


class RawListener:
    """Raw subscriptions on every recorded topic; keeps (topic, bytes, wall time)."""

    def __init__(self, domain_id: int, topics: dict[str, str]) -> None:
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node("replay_listener", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.received: list[tuple[str, bytes, float]] = []
        for name, type_name in topics.items():
            if name == stream.DEFECTS.name:
                profile = qos.for_topic(stream.DEFECTS)
            elif name == stream.CLOCK.name:
                profile = qos.for_topic(stream.CLOCK)
            else:
                profile = LOSSLESS
            self.node.create_subscription(
                message_class(type_name),
                name,
                lambda data, name=name: self.received.append((name, data, time.monotonic())),
                profile,
                raw=True,
            )

    def spin_until(self, done, timeout_s: float) -> None:
        end = time.monotonic() + timeout_s
        while not done() and time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.01)

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


def _replay(path: Path, domain: int, *args: str) -> subprocess.Popen:
    return subprocess.Popen(
        [
            sys.executable,
            "-m",
            "brake_sim_ros.cli",
            "replay",
            str(path),
            "--wait-for-subscribers",
            "1",
            *args,
        ],
        env=ros_environment(domain),
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )


@contextlib.contextmanager
def _replaying(
    path: Path, domain: int, topics: dict[str, str], *args: str
) -> Iterator[tuple[subprocess.Popen, RawListener]]:
    """A replay of ``path`` on ``domain`` and a listener to ``topics`` there; the replay
    is killed if still running, and the listener closed, on the way out."""
    listener = RawListener(domain, topics)
    proc = _replay(path, domain, *args)
    try:
        yield proc, listener
    finally:
        if proc.poll() is None:
            proc.kill()
        listener.close()


def _listen(path: Path, offset: int, *args: str) -> tuple[list, list]:
    recorded = _recorded(path)
    topics = {}
    with path.open("rb") as f:
        summary = make_reader(f).get_summary()
        for channel in summary.channels.values():
            topics[channel.topic] = summary.schemas[channel.schema_id].name
    with _replaying(path, domain_id_for(offset), topics, *args) as (proc, listener):
        listener.spin_until(lambda: proc.poll() is not None, 60.0)
        listener.spin_until(lambda: False, 0.3)  # what is still in flight
        out = proc.communicate(timeout=10)[0] if proc.poll() is not None else ""
    assert proc.returncode == 0, out
    return recorded, listener.received


def _decoded_by_topic(messages) -> dict[str, list]:
    """Messages per topic, deserialized.

    Compared as messages, not bytes: DDS may append CDR alignment padding to a payload
    (flagged in the encapsulation header), so equal messages can differ by trailing bytes.
    """
    types = {t.name: t.type_name for t in stream.TOPICS}
    out: dict[str, list] = defaultdict(list)
    for topic, data, _t in messages:
        out[topic].append(deserialize_message(data, message_class(types[topic])))
    return out


def test_replay_delivers_the_recording_in_order_and_in_time(recording: Path):
    recorded, received = _listen(recording, 1)

    by_topic_rec = _decoded_by_topic(recorded)
    by_topic_rx = _decoded_by_topic(received)
    # reliable topics: every message, every field equal, in order
    for topic in (stream.PIVOT_FORCES.name, stream.STATE.name, stream.JOINT_STATES.name):
        assert by_topic_rx[topic] == by_topic_rec[topic], topic
    assert by_topic_rx[stream.DEFECTS.name] == by_topic_rec[stream.DEFECTS.name]
    # /clock is best effort (as live): what arrives is recorded clock, in order
    clocks = by_topic_rx[stream.CLOCK.name]
    rec_clocks = by_topic_rec[stream.CLOCK.name]
    assert clocks, "no /clock received"
    positions = [rec_clocks.index(c) for c in clocks]
    assert positions == sorted(positions)

    # timing: arrival - first arrival against (log time - first log time), per chunk
    log_times = [t for topic, _d, t in recorded if topic == stream.PIVOT_FORCES.name]
    arrivals = [t for topic, _d, t in received if topic == stream.PIVOT_FORCES.name]
    pairs = list(zip(log_times, arrivals, strict=True))  # same chunks, in order (above)
    log0, wall0 = pairs[0]
    late = np.array([(t - wall0) - (lt - log0) * 1e-9 for lt, t in pairs])
    late -= np.median(late)  # the first message's own delay is not a timing error
    assert np.median(np.abs(late)) <= TYPICAL_LATE_S, late
    assert np.max(np.abs(late)) <= WORST_LATE_S, late
    span = pairs[-1][1] - wall0
    assert span == pytest.approx(DURATION_S - 0.01, abs=0.1)


def test_rate_and_start_offset(recording: Path):
    """At 2x from 0.5 s: half the wall time, messages from 0.5 s on, ground truth first.

    The pace is judged by the median of the messages' lateness against their due times
    (as the in-time test, which also bounds the worst at 1x) and by the arrivals' slope
    against log time (least squares over some 100 chunks), not by the span from the first
    arrival: a late first message shortens that (under the suite's load one came 0.12 s
    late, its followers on time)."""
    recorded, received = _listen(recording, 2, "--rate", "2", "--start-offset", "0.5")
    start_ns = recorded[0][2] + 500_000_000
    rec = _decoded_by_topic(recorded)
    rx = _decoded_by_topic(received)
    first = next(
        i
        for i, (topic, _d, t) in enumerate(m for m in recorded if m[0] == stream.PIVOT_FORCES.name)
        if t >= start_ns
    )
    assert rx[stream.PIVOT_FORCES.name] == rec[stream.PIVOT_FORCES.name][first:]
    assert first > 0
    log_times = [t for topic, _d, t in recorded if topic == stream.PIVOT_FORCES.name][first:]
    times = [t for topic, _d, t in received if topic == stream.PIVOT_FORCES.name]
    log_s = (np.array(log_times) - log_times[0]) * 1e-9
    wall_s = np.array(times) - times[0]
    late = wall_s - log_s / 2.0
    late -= np.median(late)
    assert np.median(np.abs(late)) <= TYPICAL_LATE_S, late
    assert np.polyfit(log_s, wall_s, 1)[0] == pytest.approx(0.5, rel=0.1)
    # the defect ground truth recorded at t = 0 is published at the start
    assert rx[stream.DEFECTS.name] == rec[stream.DEFECTS.name]


def test_refuses_a_broken_recording_with_the_fix(tmp_path: Path, recording: Path):
    broken = tmp_path / "cut.mcap"
    broken.write_bytes(recording.read_bytes()[: recording.stat().st_size // 2])
    proc = cli_process.run(
        [sys.executable, "-m", "brake_sim_ros.cli", "replay", str(broken)],
        capture_output=True,
        text=True,
        env=ros_environment(domain_id_for(3)),
        timeout=60,
    )
    assert proc.returncode == 1
    assert "brake-sim recover" in proc.stderr, proc.stderr


def _damaged_middle_chunk(recording: Path, out: Path) -> None:
    """One byte of a middle chunk changed: mcap's own reader would replay it unchecked."""
    with recording.open("rb") as f:
        indexes = sorted(
            make_reader(f).get_summary().chunk_indexes, key=lambda i: i.chunk_start_offset
        )
    middle = indexes[len(indexes) // 2]
    data = bytearray(recording.read_bytes())
    data[middle.chunk_start_offset + middle.chunk_length - 100] ^= 0x01
    out.write_bytes(data)


def test_a_damaged_recording_is_refused_and_nothing_is_published(tmp_path: Path, recording: Path):
    """A CRC-damaged chunk in the middle of an otherwise whole file: refused before the node
    starts, one line naming the chunk and the fix, not one message on any topic."""
    broken = tmp_path / "damaged.mcap"
    _damaged_middle_chunk(recording, broken)
    topics = {t.name: t.type_name for t in stream.TOPICS if t.name in dict(_topics(recording))}
    with _replaying(broken, domain_id_for(4), topics) as (proc, listener):
        listener.spin_until(lambda: proc.poll() is not None, 60.0)
        listener.spin_until(lambda: False, 1.0)  # anything published would arrive by now
        out = proc.communicate(timeout=10)[0]
    assert proc.returncode == 1, out
    lines = out.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in out, out
    assert re.search(r"damaged\.mcap: chunk \d+ at offset \d+: ", lines[0]), lines[0]
    assert "brake-sim recover" in lines[0]
    assert listener.received == []


def _topics(path: Path) -> list[tuple[str, str]]:
    with path.open("rb") as f:
        summary = make_reader(f).get_summary()
    return [(c.topic, summary.schemas[c.schema_id].name) for c in summary.channels.values()]


@pytest.mark.parametrize("signum", [2, 15], ids=["SIGINT", "SIGTERM"])
def test_a_signal_ends_a_looping_replay_cleanly(recording: Path, signum: int):
    """SIGINT or SIGTERM while a looping replay is publishing: it stops between two
    messages and exits 0 with its summary, never a traceback (rclpy's own handlers would
    shut the context down under a publish)."""
    topics = {t.name: t.type_name for t in stream.TOPICS if t.name in dict(_topics(recording))}
    replay = _replaying(recording, domain_id_for(5 + signum), topics, "--loop", "--rate", "4")
    with replay as (proc, listener):
        listener.spin_until(lambda: len(listener.received) > 200, 30.0)
        assert len(listener.received) > 200, "the replay did not start publishing"
        proc.send_signal(signum)
        out = proc.communicate(timeout=10)[0]
    assert proc.returncode == 0, out
    assert "Traceback" not in out and "RCLError" not in out, out
    assert re.search(r"published \d+ messages", out), out
