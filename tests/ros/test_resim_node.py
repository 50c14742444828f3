"""A live session with commands, recorded by a real node over DDS (private domain), and
re-simulated offline from the recording alone (``brake-sim resim``): the samples are the
recorded ones, bit for bit, read back from both files by the independent ``mcap`` reader.

The node runs the rig (a vehicle, no cycle) with drive settings of its own, given as node
parameters (a larger torque limit, a quicker speed controller), and the command timeout
ramping to zero; a client drives it: target speeds, a torque above the limit (refused,
naming the limit), a torque within it, brake commands that time out and ramp, some of it
stepped while paused, some in a free run whose chunk boundaries the wall clock sets.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from brake_sim_msgs.msg import DriveCommand
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from brake_sim_ros import stream
from brake_sim_ros.model.cycle import LiveDrive
from brake_sim_ros.ros.harness import LOSSLESS, SimClient, domain_id_for
from brake_sim_ros.scenarios import parse_scenario
from brake_sim_ros.stream.build import stepper_for
from tests.recording.test_resim_cli import pivot_arrays, resim, run_record
from tests.stream.test_drive_command import RATE, RIG

LIMIT_N_M = 200.0  # the node's max_drive_torque_n_m (the rig's own: the default 120)
TAU_S = 0.5  # the node's speed_time_constant_s (default 1)


def _decoded(path: Path, topic: str) -> list[tuple[int, object]]:
    with path.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return [
            (m.log_time, msg) for _s, _c, m, msg in reader.iter_decoded_messages(topics=[topic])
        ]


def _counted(client: SimClient, key: str, n: int) -> dict[str, str]:
    client.wait_for(lambda: client.diagnostics().get(key) == str(n), 10.0, f"{key} = {n}")
    return client.diagnostics()


def _step(client: SimClient, samples: int) -> None:
    for _ in range(samples // (RATE // 5)):  # 0.2 s per call
        response = client.step(steps=RATE // 5)
        assert response.success, response.message


@pytest.fixture(scope="module")
def session(tmp_path_factory, node_and_client):
    """(recording, re-simulation, client's diagnostics) of one live session."""
    folder = tmp_path_factory.mktemp("resim_live")
    scenario = folder / "rig.toml"
    scenario.write_text(RIG)
    recording = folder / "live.mcap"
    args = ["--scenario", str(scenario), "--record", str(recording), "--ros-args",
            "-p", "paused:=true", "-p", "diagnostics_period_s:=0.1",
            "-p", f"max_drive_torque_n_m:={LIMIT_N_M}", "-p", f"speed_time_constant_s:={TAU_S}",
            "-p", "on_command_timeout:=ramp_to_zero", "-p", "command_timeout_s:=0.5",
            "-p", "state_rate_hz:=256.0"]  # fmt: skip
    with node_and_client(args, domain_id_for(61), stream_qos=LOSSLESS) as (_, client):
        refused = client.set_parameter("max_drive_torque_n_m", 300.0)
        client.drive(DriveCommand.MODE_TARGET_SPEED, speed_m_s=5.0)
        _counted(client, "drive_commands_accepted", 1)
        _step(client, 2 * RATE)
        client.drive(DriveCommand.MODE_TORQUE, torque_n_m=LIMIT_N_M + 50.0)  # refused
        rejected = _counted(client, "drive_commands_rejected", 1)
        client.drive(DriveCommand.MODE_TORQUE, torque_n_m=LIMIT_N_M - 20.0)
        _counted(client, "drive_commands_accepted", 2)
        _step(client, RATE)
        # set while the node runs: recorded (brake_sim_parameter_change), re-simulated
        assert client.set_parameter("command_timeout_s", 0.3).successful
        client.drive(DriveCommand.MODE_COAST)
        client.command(800.0, 800.0)  # times out after 0.3 s, then ramps to zero
        _counted(client, "commands_accepted", 1)
        _step(client, RATE)
        assert client.set_parameter("friction.coefficient", 0.3).successful
        # a free run in real time: commands land wherever the wall clock cuts the chunks
        assert client.set_parameter("paused", False).successful
        client.spin_for(0.4)
        client.command(1500.0, 1500.0)
        client.spin_for(0.3)
        client.drive(DriveCommand.MODE_TARGET_SPEED, speed_m_s=2.0)
        client.spin_for(0.4)
        assert client.set_parameter("paused", True).successful
        client.spin_for(0.3)
    out = folder / "resim.mcap"
    done = resim(recording, "--out", out)
    assert done.returncode == 0, done.stderr
    twice = folder / "twice.mcap"  # a re-simulation holds what re-simulates it again
    again = resim(out, "--out", twice)
    assert again.returncode == 0 and "bit for bit" in again.stdout, again.stderr
    return recording, out, done.stdout, rejected, refused


@pytest.mark.slow
def test_the_resimulation_gives_the_recorded_samples_bit_for_bit(session):
    recording, out, said, _rejected, _refused = session
    live, again = pivot_arrays(recording), pivot_arrays(out)
    n = len(live["index"])
    assert n > 4 * RATE  # the stepped 4 s and the free run
    np.testing.assert_array_equal(live["index"], np.arange(n))
    for name, values in live.items():
        assert values.tobytes() == again[name].tobytes(), name
    assert f"{n} samples equal to the recording's, bit for bit" in said
    # the states too (speeds, actuation), message for message
    live_states = [m for _ns, m in _decoded(recording, stream.STATE.name)]
    states = [m for _ns, m in _decoded(out, stream.STATE.name)]
    assert len(live_states) == len(states) > 4 * 256
    for a, b in zip(live_states, states, strict=True):
        for field in ("sample_index", "flywheel_speed_rad_s", "drum_speed_rad_s",
                      "left_actuation_force_n", "right_actuation_force_n"):  # fmt: skip
            assert getattr(a, field) == getattr(b, field), field
    # every command that took effect, at its sample, in both files (the refused one in none)
    for topic, fields in (
        (stream.ACTUATION.name, ("left_force_n", "right_force_n")),
        (stream.DRIVE.name, ("mode", "drive_torque_n_m", "target_speed_m_s")),
    ):
        a, b = _decoded(recording, topic), _decoded(out, topic)
        assert a and [(ns, *(getattr(m, f) for f in fields)) for ns, m in a] == [
            (ns, *(getattr(m, f) for f in fields)) for ns, m in b
        ]
    drives = [m.drive_torque_n_m for _ns, m in _decoded(recording, stream.DRIVE.name)]
    assert len(drives) == 4 and LIMIT_N_M + 50.0 not in drives
    assert len(_decoded(recording, stream.ACTUATION.name)) == 2


def test_the_command_timeout_ramp_and_the_brake_acted(session):
    """The actuation recorded: 800 N for the timeout, then down at 5000 N/s to 0, then the
    free run's 1500 N: the planner's rules were replayed, not bypassed. The parameters set
    while the node ran are recorded at the samples they took effect at, in order."""
    recording = session[0]
    with recording.open("rb") as f:
        changes = [m.metadata for m in make_reader(f).iter_metadata()]
    changes = [c for c in changes if "sample_index" in c]
    assert [sorted(set(c) - {"sample_index"}) for c in changes] == [
        ["command_timeout_s"],
        ["friction.coefficient"],
        ["paused"],
        ["paused"],
    ]
    samples = [int(c["sample_index"]) for c in changes]
    assert samples[:2] == [3 * RATE, 4 * RATE] and samples == sorted(samples)
    states = [m for _ns, m in _decoded(recording, stream.STATE.name)]
    force = np.array([s.left_actuation_force_n for s in states])
    assert force.max() == 1500.0 and 800.0 in force
    ramp = force[(force > 0.0) & (force < 800.0)]
    assert len(ramp) >= 10  # 0.16 s of ramp at 256 states/s


def test_the_nodes_drive_settings_took_effect_and_are_recorded(session):
    recording, out, _said, rejected, refused = session
    run = run_record(recording)
    assert (run["max_drive_torque_n_m"], run["speed_time_constant_s"]) == ("200.0", "0.5")
    assert run_record(out)["max_drive_torque_n_m"] == "200.0"
    says = rejected["last_drive_rejection"]
    assert "max_drive_torque_n_m = 200 N m" in says and "250" in says and "\n" not in says
    assert not refused.successful and "fixed at start-up" in refused.reason
    # the recorded approach to 5 m/s is the one of a 200 N m drive: sooner than the
    # scenario's own 120 N m would have reached 4 m/s (offline, the same command)
    states = [m for _ns, m in _decoded(recording, stream.STATE.name)]
    rig = parse_scenario(RIG)
    radius = rig.setup.vehicle.wheel_radius_m
    live = np.array([s.flywheel_speed_rad_s for s in states if s.sample_index < 2 * RATE])
    stepper = stepper_for(rig)
    stepper.drive(LiveDrive("target_speed", target_speed_m_s=5.0))
    default = stepper.advance(2 * RATE, record_every=RATE // 256)["flywheel_speed_rad_s"]
    assert len(live) == len(default)
    reached_live = int(np.argmax(live * radius >= 4.0))
    assert live[reached_live] * radius >= 4.0
    assert not np.any(default[: reached_live + 1] * radius >= 4.0)


@pytest.mark.parametrize(
    ("override", "says"),
    [
        ("max_drive_torque_n_m:=-5.0", "max_drive_torque_n_m"),
        ("max_drive_torque_n_m:=20000.0", "max_drive_torque_n_m"),
        ("speed_time_constant_s:=0.005", "vehicle speed_time_constant_s 0.005"),
    ],
)
def test_bad_drive_settings_refuse_the_node_in_one_line(nodes, override, says):
    code, out = nodes.run(["--scenario", "rig", "--ros-args", "-p", override], domain_id_for(62))
    assert code != 0
    refusal = [line for line in out.splitlines() if "refused" in line]
    assert len(refusal) == 1 and says in refusal[0], out
    assert "Traceback" not in out


@pytest.mark.slow
def test_a_node_started_on_a_growing_defect_grows_it_and_resimulates(tmp_path, node_and_client):
    """A node started on a scenario whose defect grows (not reset to it): its recording
    holds the growing truth, its samples are the offline run's (the scenario's own setup,
    growth and all), and its re-simulation gives them bit for bit."""
    text = (
        'name = "growing"\nsample_rate_hz = 2560.0\n[defects.left]\n'
        'pivot_radius_change_pct = {value = 4.0, onset_s = 0.05, growth = "linear",'
        " rate_per_s = 40.0}\n"
    )
    scenario = tmp_path / "growing.toml"
    scenario.write_text(text)
    recording = tmp_path / "live.mcap"
    args = ["--scenario", str(scenario), "--record", str(recording), "--ros-args",
            "-p", "paused:=true"]  # fmt: skip
    with node_and_client(args, domain_id_for(63)) as (_, client):
        _step(client, RATE)
    truths = _decoded(recording, stream.DEFECTS.name)
    assert len(truths) > 3  # the start, then the growth's updates
    stepper = stepper_for(parse_scenario(text))
    offline = stepper.advance(RATE)
    live = pivot_arrays(recording)
    assert live["left_fx_n"].tobytes() == offline["left_pivot_fx_n"].tobytes()
    out = tmp_path / "again.mcap"
    done = resim(recording, "--out", out)
    assert done.returncode == 0 and f"{RATE} samples equal" in done.stdout, done.stderr
