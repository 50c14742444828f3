"""The forked command runner (tests/cli_process.py) against fresh interpreters: the same
exit status and output, its own working directory, environment and process, its time-out,
its signals, and a fresh interpreter wherever it cannot stand in."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import pytest

from tests import cli_process

CLI = [sys.executable, "-m", "brake_sim_ros.cli"]
# seconds of CPU, 120 MB of samples
LONG = ["simulate", "urban", "--duration", "60", "--sample-rate", "5120", "--quiet"]


@pytest.fixture(autouse=True)
def _forking(monkeypatch):
    """These tests are of the forked runs: not sent to fresh interpreters by the switch."""
    monkeypatch.delenv(cli_process.FRESH_ENV, raising=False)


@pytest.mark.parametrize(
    "argv",
    [
        ["--version"],
        ["simulate", "no_such_scenario"],
        ["defects"],
        ["unit", "VIN-0042", "--fleet-seed", "11"],
        ["bench", "--nope"],
    ],
    ids=" ".join,
)
def test_a_forked_command_exits_and_prints_as_a_fresh_interpreter(argv, tmp_path):
    forked = cli_process.run([*CLI, *argv], capture_output=True, text=True, timeout=120)
    fresh = subprocess.run([*CLI, *argv], capture_output=True, text=True, timeout=120)
    assert (forked.returncode, forked.stdout, forked.stderr) == (
        fresh.returncode,
        fresh.stdout,
        fresh.stderr,
    )
    assert cli_process._server is not None and cli_process._server.served > 0


def test_the_child_has_its_own_directory_environment_and_process(tmp_path):
    code = "import os, sys; print(os.getcwd(), os.environ.get('MARK'), os.getpid())"
    # brake-sim's own modules only: anything else is a fresh interpreter
    assert cli_process._module([sys.executable, "-c", code]) is None
    env = {**os.environ, "ROS_DOMAIN_ID": "77"}  # read by rclpy when it starts, not before
    served = cli_process._server.served if cli_process._server else 0
    r = cli_process.run(
        [*CLI, "simulate", "symmetric", "--duration", "0.002", "--quiet", "--out", "run.npz"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        timeout=120,
    )
    assert r.returncode == 0, r.stderr
    assert cli_process._server.served == served + 1
    assert (tmp_path / "run.npz").is_file()  # relative to the child's directory
    assert os.getcwd() != str(tmp_path)


def test_a_command_past_its_time_out_is_killed_and_said(tmp_path):
    with pytest.raises(subprocess.TimeoutExpired):
        cli_process.run(
            [*CLI, *LONG],
            capture_output=True,
            timeout=0.5,
        )
    # the server serves on after it
    assert cli_process.run([*CLI, "--version"], capture_output=True).returncode == 0


def test_an_interrupted_command_ends_as_interrupted(tmp_path):
    log = tmp_path / "log"
    with log.open("w") as out:
        proc = cli_process.popen(
            [*CLI, *LONG],
            stdout=out,
            stderr=subprocess.STDOUT,
        )
    assert isinstance(proc, cli_process.ForkedProcess)
    with pytest.raises(subprocess.TimeoutExpired):
        proc.wait(0.3)
    assert proc.poll() is None
    proc.send_signal(signal.SIGINT)
    code = proc.wait(60)
    assert code != 0 and "interrupted" in log.read_text()
    proc.kill()  # after the end: nothing, as Popen.kill


def test_what_it_cannot_stand_in_for_gets_a_fresh_interpreter(tmp_path):
    # an environment variable read at start-up, standard input, a pipe
    env = {**os.environ, "NUMBA_OPT": "1"}
    cases = [
        cli_process.run([*CLI, "--version"], capture_output=True, env=env),
        cli_process.run([*CLI, "--version"], capture_output=True, input=b""),
    ]
    assert all(isinstance(c, subprocess.CompletedProcess) for c in cases)
    served = cli_process._server.served
    cli_process.run([*CLI, "--version"], capture_output=True, env=env)
    assert cli_process._server.served == served
    proc = cli_process.popen([*CLI, "--version"], stdout=subprocess.PIPE)
    assert isinstance(proc, subprocess.Popen)
    proc.communicate(timeout=60)
