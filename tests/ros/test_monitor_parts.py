"""The monitor's parts without DDS: the MeasuredChunk conversion, the /diagnostics level,
and ``brake-sim monitor``'s refusals of bad options (one line, exit 2)."""

from __future__ import annotations

import math
import os
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticStatus

from brake_sim_ros.cli import main
from brake_sim_ros.detection.detector import (
    MAX_CHUNK_SAMPLES,
    MAX_CHUNK_VALUES,
    chunk_from_measured,
)
from brake_sim_ros.ros.harness import domain_id_for, ros_environment
from brake_sim_ros.ros.monitor import MonitorStats, PeriodView, health_level
from tests import cli_process

MONITOR = [sys.executable, "-m", "brake_sim_ros.cli", "monitor"]


def _chunk(**changes) -> SimpleNamespace:
    """Samples 5..10 of two channels: ``a`` every sample, ``b`` every 3rd (6 and 9)."""
    fields = dict(
        first_sample_index=5,
        sample_count=6,
        sample_rate_hz=100.0,
        channel_names=["a", "b"],
        units=["m/s^2", "bar"],
        decimation=[1, 3],
        channel_sample_counts=[6, 2],
        values=[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 60.0, 90.0],
    )
    return SimpleNamespace(**{**fields, **changes})


def test_a_measured_chunk_becomes_channels_on_every_sample():
    chunk = chunk_from_measured(_chunk())
    assert (chunk.first_sample_index, chunk.sample_rate_hz, len(chunk)) == (5, 100.0, 6)
    np.testing.assert_array_equal(chunk.channels["a"], [1, 2, 3, 4, 5, 6])
    # b samples the multiples of 3: 6 and 9 of 5..10; NaN on the others
    np.testing.assert_array_equal(chunk.channels["b"], [np.nan, 60.0, np.nan, np.nan, 90.0, np.nan])


@pytest.mark.parametrize(
    ("changes", "says"),
    [
        ({"values": [1.0] * 7}, "7 values, its channel_sample_counts say 8"),
        ({"units": ["m/s^2"]}, "allowed one of each per channel"),
        ({"channel_names": ["a", "a"]}, "appears twice"),
        ({"decimation": [1, 0]}, "decimation 0; allowed >= 1"),
        ({"channel_sample_counts": [5, 3]}, "channel 'a' has 5 values; 6 samples"),
        ({"sample_rate_hz": math.nan}, "sample_rate_hz is not a finite rate > 0"),
        ({"sample_rate_hz": 0.0}, "sample_rate_hz is not a finite rate > 0"),
        ({"sample_count": MAX_CHUNK_SAMPLES + 1}, f"allowed at most {MAX_CHUNK_SAMPLES}"),
        (
            {
                "sample_count": MAX_CHUNK_SAMPLES,
                "channel_names": [f"c{k}" for k in range(9)],
                "units": ["1"] * 9,
                "decimation": [MAX_CHUNK_SAMPLES] * 9,
                "channel_sample_counts": [0] * 9,
                "values": [],
            },
            f"9 channels of {MAX_CHUNK_SAMPLES} samples; allowed at most {MAX_CHUNK_VALUES}",
        ),
        ({"channel_names": ["x" * 10_000, "b"], "channel_sample_counts": [5, 3]}, "'xxx"),
    ],
)
def test_a_malformed_measured_chunk_is_one_line(changes, says):
    with pytest.raises(ValueError) as info:
        chunk_from_measured(_chunk(**changes))
    text = str(info.value)
    assert says in text and "\n" not in text and len(text) < 300
    assert text.startswith("measured chunk at sample 5: ")


def test_health_level_of_a_period():
    stats = MonitorStats(windows=5, last_warning="samples 3 to 9 never arrived")
    level = health_level
    assert level(PeriodView(), MonitorStats(), 0.8)[0] == DiagnosticStatus.STALE
    assert level(PeriodView(), stats, 0.8)[0] == DiagnosticStatus.STALE
    assert level(PeriodView(windows=4, max_health=0.5), stats, 0.8)[0] == DiagnosticStatus.OK
    assert level(PeriodView(windows=4, max_health=0.8), stats, 0.8)[0] == DiagnosticStatus.WARN
    assert level(PeriodView(windows=4, max_health=math.nan), stats, 0.8)[0] == (
        DiagnosticStatus.WARN
    )
    warned = level(PeriodView(windows=4, max_health=0.1, warnings=2), stats, 0.8)
    assert warned[0] == DiagnosticStatus.WARN and "never arrived" in warned[1]
    alarm = level(PeriodView(windows=4, alarms=1, max_health=1.5, warnings=2), stats, 0.8)
    assert alarm[0] == DiagnosticStatus.ERROR and "ALARM in 1 of 4 windows" in alarm[1]


@pytest.mark.parametrize(
    ("args", "says"),
    [
        ([], "the following arguments are required: --detector"),
        (["--detector", "nope"], "detector 'nope': allowed rms, kurtosis, crest"),
        (["--detector", "os:path"], "not a brake_sim_ros.detection Detector subclass"),
        (["--detector", "no_such_module_x:Cls"], "no module 'no_such_module_x' on the Python"),
        (["--detector", "rms"], "learns from data: give --fit DIR"),
        (["--detector", "rms", "--fit", "/nonexistent/dir"], "--fit /nonexistent/dir:"),
        (["--detector", "rms", "--simulator", "brake sim"], "--simulator 'brake sim'"),
        (["--detector", "rms", "--measured-topic", "/a//b"], "--measured-topic '/a//b'"),
        (["--detector", "rms", "--bogus"], "unrecognized arguments: --bogus"),
        (["--detector", "rms", "--brake", "foo"], "--brake: invalid choice: 'foo'"),
    ],
)
def test_bad_options_are_one_line_and_exit_2(args, says, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["monitor", *args])
    assert exit_info.value.code == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("brake-sim monitor: error: "), lines
    assert says in lines[0]


def test_fit_on_a_file_that_is_not_a_dataset_is_one_line(tmp_path, capsys):
    bogus = tmp_path / "data"
    bogus.mkdir()
    (bogus / "campaign.lock").write_text("\x00not json")
    with pytest.raises(SystemExit) as exit_info:
        main(["monitor", "--detector", "rms", "--fit", str(bogus)])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "not json" not in err


@pytest.mark.slow
@pytest.mark.parametrize(
    ("parameter", "says"),
    [
        ("warn_level:=2.0", "warn_level out of range"),
        ("unit_id:=5", "expecting type 'STRING'"),
        ("brake:=foo", "brake 'foo': allowed study, service or empty"),
    ],
)
def test_a_bad_ros_parameter_is_refused_in_one_line(parameter, says):
    """--ros-args -p values are arguments too: one line, exit 2, before any topic."""
    env = ros_environment(domain_id_for(21))
    env["PYTHONPATH"] = os.pathsep.join([str(Path(__file__).parent), env.get("PYTHONPATH", "")])
    env["BRAKE_SIM_TEST_RMS_THRESHOLD"] = "1.0"
    proc = cli_process.run(
        [*MONITOR, "--detector", "test_monitor:OffsetRms", "--ros-args", "-p", parameter],
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 2 and proc.stdout == "", proc.stdout + proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("brake-sim monitor: refused to start: ")
    assert says in lines[0]
