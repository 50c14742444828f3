"""``brake-sim live``, the README's main job: node in real time, MCAP and Rerun files."""

from __future__ import annotations

import sys
from pathlib import Path

from rosbags.highlevel import AnyReader

from brake_sim_ros.ros.harness import domain_id_for, ros_environment
from tests import cli_process
from tests.rerun_helpers import verify

DURATION_S = 0.5


def test_live_streams_records_and_says_where(tmp_path: Path):
    env = ros_environment(domain_id_for(11))
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    proc = cli_process.run(
        [
            sys.executable,
            "-m",
            "brake_sim_ros.cli",
            "live",
            "symmetric",
            "--duration",
            str(DURATION_S),
            "--out-dir",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    mcaps, rrds = list(tmp_path.glob("symmetric-*.mcap")), list(tmp_path.glob("symmetric-*.rrd"))
    assert len(mcaps) == 1 and len(rrds) == 1
    # it says where both files are and how to open them
    assert f"wrote {mcaps[0]}" in proc.stdout and f"wrote {rrds[0]}" in proc.stdout
    assert f"brake-sim replay {mcaps[0]}" in proc.stdout
    assert f"rerun {rrds[0]}" in proc.stdout
    assert "no display here" in proc.stdout
    verify(rrds[0])
    with AnyReader([mcaps[0]]) as reader:
        chunks = [c for c in reader.connections if c.topic == "/brake_sim/pivot_forces"]
        samples = sum(
            len(reader.deserialize(raw, conn.msgtype).left_fx_n)
            for conn, _t, raw in reader.messages(connections=chunks)
        )
    assert samples == round(DURATION_S * 25_600)  # every sample of the run, 25.6 kHz
