"""A node with nothing to step idles: paused or at the end of its run it ticks slowly (it
ticked every millisecond as fast as possible, 60 % of a core for a finished run), and a
change that resumes the run (unpausing, a reset) restarts the tick at once."""

from __future__ import annotations

import time
from pathlib import Path

from brake_sim_ros.ros.harness import domain_id_for

DOMAIN = domain_id_for(29)
IDLE_CPU_S = 2.0  # measured over this much wall time
MAX_IDLE_SHARE = 0.15  # of one core; the 1 ms tick took 0.63 finished, the 10 ms one 0.10 paused


def cpu_s(pid: int) -> float:
    """User + system CPU seconds of process ``pid`` so far (/proc/PID/stat)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    ticks = int(fields[11]) + int(fields[12])  # utime, stime (fields 14 and 15)
    return ticks / 100.0  # USER_HZ


def idle_share(pid: int) -> float:
    before = cpu_s(pid)
    time.sleep(IDLE_CPU_S)
    return (cpu_s(pid) - before) / IDLE_CPU_S


def test_a_paused_or_finished_node_idles_and_wakes_at_once(node_and_client):
    args = ["--duration", "0.05", "--ros-args", "-p", "paused:=true",
            "-p", "real_time_factor:=0.0", "-p", "diagnostics_period_s:=0.1"]  # fmt: skip
    with node_and_client(args, DOMAIN) as (node, client):
        client.spin_for(0.3)
        paused = idle_share(node.pid)
        assert client.set_parameter("paused", False).successful
        client.wait_for(lambda: client.diagnostics().get("state") == "finished", 30.0, "the end")
        finished = idle_share(node.pid)
        # the reset restarts the tick: the run steps again within a few idle periods
        client.forget()
        assert client.reset().success
        client.wait_for(lambda: client.sample_count >= 1280, 5.0, "the run after the reset")
    assert paused < MAX_IDLE_SHARE and finished < MAX_IDLE_SHARE, (paused, finished)
