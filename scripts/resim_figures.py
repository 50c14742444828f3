"""Figures of the live drive's settings and of ``brake-sim resim``, on the built-in rig.

``PYTHONPATH=. .venv/bin/python scripts/resim_figures.py [--seconds S]`` prints:

1. offline, the built-in rig (25.6 kHz) from rest toward a live target of 5 m/s: the time
   to 4 m/s and to 4.9 m/s for several ``max_drive_torque_n_m`` and
   ``speed_time_constant_s`` (the ``[vehicle]`` keys, as the node's parameters set them);
2. live, a real node on the rig over DDS (its own domain, localhost) with
   ``max_drive_torque_n_m:=200``, recorded, driven by a client (a target speed, a brake
   stop, a torque; stepped while paused, then a free run in real time); then
   ``brake-sim resim`` of the recording: its CPU time and whether the samples equal the
   recording's, bit for bit.
"""

from __future__ import annotations

import argparse
import dataclasses
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from brake_sim_ros.model.cycle import LiveDrive
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.stream import parameters as ros_params
from brake_sim_ros.stream.build import stepper_for


def _times(torque_n_m: float, tau_s: float, seconds: float) -> tuple[float, float]:
    rig = load_scenario("rig")
    setup = ros_params.with_drive_limits(
        rig.setup, {"max_drive_torque_n_m": torque_n_m, "speed_time_constant_s": tau_s}
    )
    stepper = stepper_for(dataclasses.replace(rig, setup=setup), setup=setup)
    stepper.drive(LiveDrive("target_speed", target_speed_m_s=5.0))
    block = stepper.advance(round(seconds * rig.sample_rate_hz), record_every=256)
    speed = block["flywheel_speed_rad_s"] * setup.vehicle.wheel_radius_m
    dt = 256 / rig.sample_rate_hz

    def first(level: float) -> float:
        reached = np.flatnonzero(speed >= level)
        return reached[0] * dt if len(reached) else float("inf")

    return first(4.0), first(4.9)


def live_session(folder: Path, seconds: int) -> Path:
    from brake_sim_msgs.msg import DriveCommand

    from brake_sim_ros.ros.harness import NodeProcess, SimClient, domain_id_for

    recording = folder / "live.mcap"
    domain = domain_id_for(83)
    node = NodeProcess.start(
        ["--scenario", "rig", "--record", str(recording), "--ros-args", "-p", "paused:=true",
         "-p", "max_drive_torque_n_m:=200.0", "-p", "on_command_timeout:=hold",
         "-p", "diagnostics_period_s:=0.2"],
        domain_id=domain,
        log_path=folder / "node.log",
    )  # fmt: skip
    client = SimClient(domain, keep_chunks=False)
    rate = 25_600

    def step(s: float) -> None:
        for _ in range(round(s / 0.2)):
            assert client.step(steps=rate // 5).success

    try:
        client.wait_for_node(60.0)
        client.drive(DriveCommand.MODE_TARGET_SPEED, speed_m_s=8.0)
        client.spin_for(0.3)
        step(seconds / 2)
        client.drive(DriveCommand.MODE_COAST)
        client.command(1500.0, 1500.0)
        client.spin_for(0.3)
        step(seconds / 2)
        client.command(0.0, 0.0)
        client.drive(DriveCommand.MODE_TORQUE, torque_n_m=180.0)
        assert client.set_parameter("paused", False).successful
        client.spin_for(2.0)  # a free run: the wall clock cuts the chunks
        client.drive(DriveCommand.MODE_TARGET_SPEED, speed_m_s=3.0)
        client.spin_for(2.0)
    finally:
        client.close()
        node.stop()
    return recording


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=int, default=10, help="stepped seconds of the session")
    args = parser.parse_args()
    print("rig, live target 5 m/s from rest (offline, 25.6 kHz):")
    for torque, tau in ((60.0, 1.0), (120.0, 1.0), (200.0, 1.0), (300.0, 1.0), (120.0, 0.25)):
        to4, to49 = _times(torque, tau, 15.0)
        print(
            f"  max_drive_torque_n_m {torque:5.0f}, speed_time_constant_s {tau:4.2f}:"
            f" 4 m/s at {to4:6.3f} s, 4.9 m/s at {to49:6.3f} s"
        )
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        recording = live_session(folder, args.seconds)
        out = folder / "again.mcap"
        wall0 = time.perf_counter()
        done = subprocess.run(
            [sys.executable, "-m", "brake_sim_ros.cli", "resim", str(recording), "--out", str(out)],
            capture_output=True,
            text=True,
            check=False,
        )
        wall = time.perf_counter() - wall0
        print(f"live session recorded: {recording.stat().st_size / 1e6:.1f} MB")
        print(f"resim (exit {done.returncode}, {wall:.1f} s wall): {done.stdout.strip()}")
        if done.returncode:
            print(done.stderr.strip())


if __name__ == "__main__":
    main()
