"""Recording from real node processes over real DDS: live = offline, signals, crashes, failures.

* A node run as fast as possible with ``--record`` writes the same messages (CDR bytes and
  log times) as ``record_offline`` for the same scenario, /diagnostics aside.
* SIGINT and SIGTERM during a real-time recording leave a complete file holding exactly
  what the node says it published.
* SIGKILL leaves a file from which ``recover`` restores a prefix of what a client received
  over DDS, value for value; the test measures the loss and holds it under the flush
  interval (1 s of simulated time).
* A full disk (/dev/full) or an impossible path is reported and the node streams on.
"""

from __future__ import annotations

import os
import re
import signal
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import rclpy
import yaml
from mcap.reader import make_reader
from rclpy.qos import QoSProfile, ReliabilityPolicy

from brake_sim_ros import stream
from brake_sim_ros.recording.record import record_offline
from brake_sim_ros.recording.recover import recover
from brake_sim_ros.ros.harness import NodeProcess, domain_id_for
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.solvers.methods import FIXED_STEP_METHODS
from brake_sim_ros.stream import conversion
from brake_sim_ros.stream.offline import StreamSettings
from tests.bag_helpers import rosbags_decoded

SCENARIO = "symmetric"
SCENARIOS = Path(__file__).parents[2] / "brake_sim_ros" / "scenarios" / "builtin"
SUMMARY = re.compile(r"published (\d+) samples in (\d+) chunks and (\d+) states")
FLUSH_NS = 1_000_000_000


def _messages(path: Path) -> list[tuple[str, int, bytes]]:
    with path.open("rb") as f:
        return [
            (c.topic, m.log_time, m.data)
            for _s, c, m in make_reader(f).iter_messages(log_time_order=False)
        ]


def _run_id(path: Path) -> str:
    """The run id a recording's ``brake_sim_run`` record gives (its DefectState's too)."""
    with path.open("rb") as f:
        records = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
    run_id = records["brake_sim_run"]["run_id"]
    (defects,) = rosbags_decoded(path)[stream.DEFECTS.name]
    assert defects.run_id == run_id and len(run_id) == 32
    return run_id


def _wait_for_line(node: NodeProcess, text: str, timeout_s: float) -> None:
    end = time.monotonic() + timeout_s
    while text not in node.output():
        if node.proc.poll() is not None or time.monotonic() > end:
            pytest.fail(f"node never logged {text!r}:\n{node.output()}")
        time.sleep(0.05)


@pytest.mark.slow
def test_live_recording_equals_offline_recording(tmp_path, nodes):
    live = tmp_path / "live.mcap"
    code, out = nodes.run(
        ["--scenario", SCENARIO, "--duration", "1.5", "--exit-at-end", "--record", str(live),
         "--ros-args", "-p", "real_time_factor:=0.0", "-p", "publish_measured:=true"],
        domain_id_for(40), timeout_s=120,
    )  # fmt: skip
    assert code == 0, out
    offline = tmp_path / "offline.mcap"
    # the live run's id, given to the offline run: then every byte must be equal
    record_offline(
        load_scenario(SCENARIO),
        offline,
        duration_s=1.5,
        run_id=_run_id(live),
        settings=StreamSettings(publish_measured=True),
    )
    live_msgs = [m for m in _messages(live) if m[0] != stream.DIAGNOSTICS.name]
    offline_msgs = _messages(offline)
    assert len(live_msgs) == len(offline_msgs) > 0
    assert live_msgs == offline_msgs  # topic, log time and CDR bytes, one by one
    # the sensors too: the node's bank and the offline one measure the same bits
    assert sum(m[0] == stream.MEASURED.name for m in live_msgs) == 15  # a chunk per 100 ms
    with live.open("rb") as f:
        records = {m.name: m.metadata for m in make_reader(f).iter_metadata()}
    assert records["brake_sim_run"]["mode"] == "live"
    assert "real_time_factor" in records["brake_sim_ros_parameters"]


@pytest.mark.slow
@pytest.mark.parametrize("method", FIXED_STEP_METHODS)
def test_live_equals_offline_for_every_scheme(tmp_path, nodes, method):
    """Same scenario, same scheme: the node's recording and the offline one hold the same
    bytes, through the first impacts (0.8 s), whichever fixed-step scheme is chosen."""
    text = (SCENARIOS / "symmetric.toml").read_text()
    scenario_file = tmp_path / f"{method}.toml"
    scenario_file.write_text(f'{text}\n[solver]\nmethod = "{method}"\n')
    live = tmp_path / "live.mcap"
    code, out = nodes.run(
        ["--scenario", str(scenario_file), "--duration", "0.8", "--exit-at-end",
         "--record", str(live), "--ros-args", "-p", "real_time_factor:=0.0"],
        domain_id_for(50 + FIXED_STEP_METHODS.index(method)), timeout_s=120,
    )  # fmt: skip
    assert code == 0, out
    offline = tmp_path / "offline.mcap"
    scenario = load_scenario(str(scenario_file))
    assert scenario.solver.method == method
    record_offline(scenario, offline, duration_s=0.8, run_id=_run_id(live))
    live_msgs = [m for m in _messages(live) if m[0] != stream.DIAGNOSTICS.name]
    offline_msgs = _messages(offline)
    assert len(live_msgs) == len(offline_msgs) > 0
    assert live_msgs == offline_msgs


@pytest.mark.slow
def test_the_recording_holds_the_qos_the_node_offers(tmp_path, nodes):
    """Each recorded channel's offered_qos_profiles equals what the running node's
    publisher offers, as DDS discovery reports it to another participant (every topic:
    ~/measured switched on), the operator's QoS overrides included."""
    path = tmp_path / "rec.mcap"
    domain = domain_id_for(47)
    overrides = {"/brake_sim/pivot_forces": ("depth", 500), "/brake_sim/state": ("reliability",
                 "best_effort")}  # fmt: skip
    args = ["--scenario", SCENARIO, "--duration", "3", "--exit-at-end", "--record", str(path),
            "--ros-args", "-p", "publish_measured:=true"]  # fmt: skip
    for name, (policy, value) in overrides.items():
        args += ["-p", f"qos_overrides.{name}.publisher.{policy}:={value}"]
    offered: dict[str, tuple[str, str, int]] = {}
    with nodes.process(args, domain) as node:
        context = rclpy.context.Context()
        rclpy.init(context=context, domain_id=domain)
        try:
            probe = rclpy.create_node("qos_probe", context=context)
            published = [t for t in stream.TOPICS if t.published]
            end = time.monotonic() + 30.0
            while len(offered) < len(published) and time.monotonic() < end:
                for topic in published:
                    for info in probe.get_publishers_info_by_topic(topic.name):
                        if info.node_name == "brake_sim":
                            q = info.qos_profile
                            offered[topic.name] = (
                                q.reliability.name.lower(),
                                q.durability.name.lower(),
                                q.depth,
                            )
                time.sleep(0.1)
            probe.destroy_node()
            assert node.wait(60) == 0, node.output()
        finally:
            rclpy.try_shutdown(context=context)
    assert set(offered) == {t.name for t in stream.TOPICS if t.published}
    with path.open("rb") as f:
        reader = make_reader(f)
        channels = reader.get_summary().channels.values()
        recorded = {}
        for channel in channels:
            (profile,) = yaml.safe_load(channel.metadata["offered_qos_profiles"])
            recorded[channel.topic] = (profile["reliability"], profile["durability"])
            recorded_depth = profile["depth"]
            # DDS discovery carries no history depth (it reports 0); the node creates its
            # publishers from the same table, so the recorded depth is checked against it
            topic = stream.topics.TOPIC_BY_NAME[channel.topic]
            policy, value = overrides.get(channel.topic, ("depth", topic.qos.depth))
            assert recorded_depth == (value if policy == "depth" else topic.qos.depth)
    for name, (reliability, durability, _depth) in offered.items():
        assert recorded[name] == (reliability, durability), name
    assert offered["/brake_sim/state"][0] == "best_effort"  # the override reached DDS


@pytest.mark.realtime  # signalled after 2.5 s of wall time: more than 1 s of signal
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signal_closes_the_file_with_every_message(tmp_path, nodes, sig):
    path = tmp_path / "rec.mcap"
    args = ["--scenario", SCENARIO, "--duration", "600", "--record", str(path)]
    with nodes.process(args, domain_id_for(41 + int(sig))) as node:
        _wait_for_line(node, "samples per chunk", 60.0)
        time.sleep(2.5)  # about 2.5 s of signal at real-time factor 1
        node.proc.send_signal(sig)
        assert node.wait(20) == 0, node.output()
    out = node.output()
    match = SUMMARY.search(out)
    assert match, out
    samples, chunks, states = map(int, match.groups())
    assert samples > 25_600  # more than 1 s of signal was running
    with path.open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None, "no summary: the file was not finished"
        assert "rosbag2" in {m.name for m in reader.iter_metadata()}
    decoded = rosbags_decoded(path)
    assert len(decoded[stream.PIVOT_FORCES.name]) == chunks
    assert sum(len(c.left_fx_n) for c in decoded[stream.PIVOT_FORCES.name]) == samples
    assert len(decoded[stream.STATE.name]) == states
    assert len(decoded[stream.JOINT_STATES.name]) == states
    assert summary.statistics.message_count == sum(len(v) for v in decoded.values())
    assert f"brake_sim: recorded {path}" in out


@pytest.mark.realtime  # killed after 3 s of wall time, with a command flushed to the file
def test_sigkill_then_recover_loses_less_than_the_flush_interval(tmp_path, node_and_client):
    path = tmp_path / "killed.mcap"
    args = ["--scenario", SCENARIO, "--duration", "600", "--record", str(path),
            "--ros-args", "-p", "paused:=true"]  # fmt: skip
    reliable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    with node_and_client(args, domain_id_for(50), stream_qos=reliable, exit_code=None) as (
        node,
        client,
    ):
        assert client.set_parameter("paused", False).successful
        client.spin_for(1.0)
        client.command(300.0, 300.0)  # an accepted command goes into the file
        client.spin_for(2.0)
        node.proc.send_signal(signal.SIGKILL)
        node.wait(10)
        client.spin_for(0.3)  # what was on its way
    received = client.rx.chunks
    assert client.gaps == 0 and received[0].first_sample_index == 0
    fixed = tmp_path / "fixed.mcap"
    result = recover(path, fixed)
    assert not result.complete  # killed: no summary, open chunk cut off
    decoded = rosbags_decoded(fixed)
    chunks = decoded[stream.PIVOT_FORCES.name]
    n = len(chunks)
    assert 0 < n <= len(received)
    for name in conversion.PIVOT_CHUNK_ARRAYS:  # the recovered prefix is exactly what was sent
        np.testing.assert_array_equal(
            np.concatenate([getattr(c, name) for c in chunks]),
            np.concatenate([np.asarray(getattr(c, name)) for c in received[:n]]),
        )
    commands = decoded[stream.ACTUATION.name]
    assert [(c.left_force_n, c.right_force_n) for c in commands] == [(300.0, 300.0)]
    dt = 1.0 / chunks[0].sample_rate_hz
    lost = received[n:]
    lost_samples = sum(len(c.left_fx_n) for c in lost)
    lost_span_ns = (
        conversion.stamp_ns(lost[-1].first_sample_index, dt)
        - conversion.stamp_ns(lost[0].first_sample_index, dt)
        if lost
        else 0
    )
    print(
        f"SIGKILL after {sum(len(c.left_fx_n) for c in received)} samples received;"
        f" recovered {n} chunks, lost {len(lost)} chunks = {lost_samples} samples"
        f" ({lost_samples * dt:.3f} s of signal)"
    )
    assert lost_span_ns < FLUSH_NS  # the lost chunks' stamps span less than the interval
    assert lost_samples * dt < FLUSH_NS / 1e9 + 0.0101  # + the last chunk's own 10 ms


@pytest.mark.slow
def test_recording_failure_is_reported_and_the_node_streams_on(tmp_path, nodes):
    """The file system refuses a write in the middle of the run (a file-size limit of
    64 KiB on the node process; Python ignores SIGXFSZ, so the write fails with EFBIG):
    the node reports it, drops the recorder and streams on to the end."""
    wrapper = tmp_path / "limited-python"
    wrapper.write_text(f'#!/bin/sh\nulimit -f 128\nexec "{sys.executable}" "$@"\n')
    wrapper.chmod(0o755)
    target = tmp_path / "limited.mcap"
    code, out = nodes.run(
        ["--scenario", SCENARIO, "--duration", "2", "--exit-at-end", "--record", str(target),
         "--record-flush-s", "0.25", "--ros-args", "-p", "real_time_factor:=0.0"],
        domain_id_for(60), timeout_s=120, python=str(wrapper),
    )  # fmt: skip
    assert code == 0, out
    assert "File too large" in out, out
    assert "the chunks written before are in the file" in out
    assert "the simulation goes on" in out
    assert "published 51200 samples in 200 chunks" in out
    assert "1 recorder/viewer failure(s)" in out


@pytest.mark.parametrize(
    ("target", "cause"),
    [("fifo.mcap", "not a regular file"), ("/dev/null/sub/x.mcap", "")],
    ids=["fifo", "bad-path"],
)
def test_an_unusable_record_path_is_refused_before_the_node_starts(tmp_path, nodes, target, cause):
    if target == "fifo.mcap":
        target = str(tmp_path / target)
        os.mkfifo(target)
    code, out = nodes.run(
        ["--scenario", SCENARIO, "--duration", "0.5", "--exit-at-end", "--record", target],
        domain_id_for(61),
    )
    assert code == 2, out
    last = out.strip().splitlines()[-1]
    assert last.startswith("python -m brake_sim_ros.app.node: error: --record"), last
    assert cause in last
