"""Live drive commands through the ROS node, over real DDS on a private domain.

A client drives a test rig's vehicle (a scenario with a [vehicle] and no [cycle]) in
lock-step: a target speed, then the brake with the drive coasting, then a constant torque.
The drum speed follows (reaches the target within the speed controller's tolerance, then
stops under the brake), and every published sample equals the offline stepper's given
the same commands at the same samples, bit for bit. Hostile drive commands, and drive
commands to runs that take none (a drive cycle, no vehicle), are rejected, counted and
named in /diagnostics, and the node runs on. A recording holds the accepted commands at
the samples they took effect.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from brake_sim_msgs.msg import DriveCommand

from brake_sim_ros import stream
from brake_sim_ros.model.cycle import DRIVE_MODES, SPEED_TOLERANCE, LiveDrive
from brake_sim_ros.model.layout import COL
from brake_sim_ros.ros.harness import LOSSLESS, SimClient, domain_id_for
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.stream import conversion
from brake_sim_ros.stream.build import stepper_for
from tests.bag_helpers import rosbags_timed
from tests.stream.test_drive_command import RATE, RIG  # the rig and its sample rate

# a ~/step call is bounded by the node's measured wall cost per sample
pytestmark = pytest.mark.realtime

DOMAIN = domain_id_for(41)
BRAKE_N = 1500.0


@pytest.fixture(scope="module")
def rig(tmp_path_factory, node_and_client):
    """(client, scenario path) of a node on the rig, paused, commands held."""
    folder = tmp_path_factory.mktemp("drive")
    path = folder / "rig.toml"
    path.write_text(RIG)
    args = ["--scenario", str(path), "--ros-args", "-p", "paused:=true",
            "-p", "diagnostics_period_s:=0.1", "-p", "on_command_timeout:=hold",
            "-p", "state_rate_hz:=256.0", "-p", f"scenario_dirs:={folder}"]  # fmt: skip
    with node_and_client(args, DOMAIN, stream_qos=LOSSLESS) as (_, client):
        yield client, path


def _counted(client: SimClient, key: str, n: int) -> dict[str, str]:
    """Wait until /diagnostics counts ``n`` for ``key`` (the command is in the node)."""
    client.wait_for(lambda: client.diagnostics().get(key) == str(n), 10.0, f"{key} = {n}")
    return client.diagnostics()


def _step(client: SimClient, seconds: int) -> None:
    # 0.2 s per call: within one call's bound of wall time on a loaded machine
    for _ in range(5 * seconds):
        response = client.step(steps=RATE // 5)
        assert response.success, response.message


def test_a_client_drives_a_stop_live_as_the_offline_stepper_does(rig):
    client, path = rig
    assert client.reset(scenario=str(path)).success
    client.wait_for(lambda: client.diagnostics().get("sample_index") == "0", 10.0, "the reset")
    client.forget()
    before = client.next_diagnostics()
    accepted = int(before["drive_commands_accepted"])
    commands = int(before["commands_accepted"])
    assert before["drive"] == "coast"  # the node starts coasting

    client.drive(DriveCommand.MODE_TARGET_SPEED, speed_m_s=5.0)
    assert _counted(client, "drive_commands_accepted", accepted + 1)["drive"] == (
        "target_speed 5 m/s"
    )
    _step(client, 7)
    client.drive(DriveCommand.MODE_COAST)
    client.command(BRAKE_N, BRAKE_N)
    _counted(client, "drive_commands_accepted", accepted + 2)
    _counted(client, "commands_accepted", commands + 1)
    _step(client, 3)
    client.command(0.0, 0.0)
    client.drive(DriveCommand.MODE_TORQUE, torque_n_m=60.0)
    assert _counted(client, "drive_commands_accepted", accepted + 3)["drive"] == "torque 60 N m"
    _counted(client, "commands_accepted", commands + 2)
    _step(client, 2)
    n = 12 * RATE
    stride = RATE // 256  # state_rate_hz 256
    client.wait_for(lambda: client.sample_count >= n, 10.0, "every sample")
    client.wait_for(
        lambda: client.rx.states and client.rx.states[-1].sample_index >= n - stride,
        10.0,
        "the last state",
    )

    # offline: the same commands at the same samples
    scenario = load_scenario(str(path))
    stepper = stepper_for(scenario)
    stepper.drive(LiveDrive("target_speed", target_speed_m_s=5.0))
    blocks = [stepper.advance(7 * RATE)]
    stepper.drive(LiveDrive("coast"))
    blocks.append(stepper.advance(3 * RATE, actuation_n=(BRAKE_N, BRAKE_N)))
    stepper.drive(LiveDrive("torque", drive_torque_n_m=60.0))
    blocks.append(stepper.advance(2 * RATE, actuation_n=(0.0, 0.0)))
    offline = np.concatenate([b.data for b in blocks])

    got = client.chunk_arrays()
    np.testing.assert_array_equal(got["index"], np.arange(n))
    for side in ("left", "right"):
        for axis in ("fx", "fy"):
            np.testing.assert_array_equal(
                got[f"{side}_{axis}_n"], offline[:, COL[f"{side}_pivot_{axis}_n"]]
            )
    # every state (the node's histories are deep for this reliable client)
    states = [s for s in client.rx.states if s.sample_index < n]
    index = np.array([s.sample_index for s in states])
    np.testing.assert_array_equal(index, np.arange(0, n, stride))
    for name in ("flywheel_speed_rad_s", "drum_speed_rad_s"):
        np.testing.assert_array_equal([getattr(s, name) for s in states], offline[index, COL[name]])

    # so the node's drum followed as the offline one did: the target within the speed
    # controller's tolerance after 7 s of drive, no overshoot, a stop under the brake
    # (held at standstill), rolling again on the torque
    drum_m_s = offline[:, COL["drum_speed_rad_s"]] * scenario.setup.vehicle.wheel_radius_m
    assert abs(drum_m_s[7 * RATE - 1] - 5.0) <= SPEED_TOLERANCE * 5.0
    assert drum_m_s[: 7 * RATE].max() < 5.0 * (1.0 + SPEED_TOLERANCE)
    assert drum_m_s[10 * RATE - 1] == 0.0 and offline[10 * RATE - 1, COL["drum_sticking"]] == 1.0
    assert drum_m_s[-1] > 1.0


@pytest.mark.parametrize(
    ("mode", "torque", "speed", "says"),
    [
        (DriveCommand.MODE_TORQUE, math.nan, 0.0, "drive_torque_n_m=nan"),
        (DriveCommand.MODE_TORQUE, math.inf, 0.0, "drive_torque_n_m=inf"),
        (DriveCommand.MODE_TORQUE, -50.0, 0.0, "never brakes"),
        (DriveCommand.MODE_TORQUE, 500.0, 0.0, "max_drive_torque_n_m = 120 N m"),
        (DriveCommand.MODE_TARGET_SPEED, 0.0, 100.0, "from 0 to 69.44 m/s"),
        (DriveCommand.MODE_TARGET_SPEED, 0.0, -math.inf, "target_speed_m_s=-inf"),
        (7, 10.0, 1.0, "mode=7 is unknown: allowed 0 (COAST), 1 (TORQUE), 2 (TARGET_SPEED)"),
    ],
)
def test_hostile_drive_commands_are_rejected_counted_and_change_nothing(
    rig, mode, torque, speed, says
):
    client, path = rig
    assert client.reset(scenario=str(path)).success
    before = client.next_diagnostics()
    rejected = int(before["drive_commands_rejected"])
    client.drive(mode, torque_n_m=torque, speed_m_s=speed)
    diag = _counted(client, "drive_commands_rejected", rejected + 1)
    assert says in diag["last_drive_rejection"] and "\n" not in diag["last_drive_rejection"]
    assert diag["drive"] == "coast"
    assert diag["drive_commands_accepted"] == before["drive_commands_accepted"]
    assert client.step(steps=64).success  # and the node runs on


@pytest.mark.parametrize(
    ("scenario", "says"), [("urban", "drive cycle drives"), ("symmetric", "has no vehicle")]
)
def test_runs_that_take_no_drive_reject_it(rig, scenario, says):
    client, path = rig
    try:
        assert client.reset(scenario=scenario).success
        rejected = int(client.next_diagnostics()["drive_commands_rejected"])
        client.drive(DriveCommand.MODE_TARGET_SPEED, speed_m_s=5.0)
        diag = _counted(client, "drive_commands_rejected", rejected + 1)
        assert says in diag["last_drive_rejection"] and diag["drive"] == "none"
        assert client.step(steps=64).success
    finally:
        assert client.reset(scenario=str(path)).success


def test_accepted_drive_commands_are_recorded_at_their_sample(tmp_path, node_and_client):
    """A node recording (--record) holds each accepted drive command, stamped with the
    sample it took effect at, as rosbags reads it back; a rejected one is not there."""
    scenario_path = tmp_path / "rig.toml"
    scenario_path.write_text(RIG)
    bag = tmp_path / "run.mcap"
    args = ["--scenario", str(scenario_path), "--record", str(bag), "--ros-args",
            "-p", "paused:=true", "-p", "diagnostics_period_s:=0.1"]  # fmt: skip
    with node_and_client(args, domain_id_for(42)) as (_, client):
        client.drive(DriveCommand.MODE_TARGET_SPEED, speed_m_s=5.0)
        _counted(client, "drive_commands_accepted", 1)
        assert client.step(steps=256).success
        client.drive(DriveCommand.MODE_TORQUE, torque_n_m=math.nan)
        _counted(client, "drive_commands_rejected", 1)
        client.drive(DriveCommand.MODE_TORQUE, torque_n_m=30.0)
        _counted(client, "drive_commands_accepted", 2)
    recorded = rosbags_timed(bag)[stream.DRIVE.name]
    period = 1.0 / RATE
    assert [(ns, m.mode, m.drive_torque_n_m, m.target_speed_m_s) for ns, m in recorded] == [
        (0, DriveCommand.MODE_TARGET_SPEED, 0.0, 5.0),
        (conversion.stamp_ns(256, period), DriveCommand.MODE_TORQUE, 30.0, 0.0),
    ]


def test_the_message_modes_are_the_cores_in_order():
    """DriveCommand's MODE_* numbers index the core's modes (stream.commands.drive_command)."""
    numbers = [getattr(DriveCommand, f"MODE_{mode.upper()}") for mode in DRIVE_MODES]
    assert numbers == list(range(len(DRIVE_MODES)))
