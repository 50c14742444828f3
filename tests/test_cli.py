"""The CLI as a user runs it: real processes, real files."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np

from brake_sim_ros.analysis.validation import checks


def _cli(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "brake_sim_ros.cli", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=600,
    )


def test_simulate_writes_a_history_numpy_opens(tmp_path):
    out = tmp_path / "run.npz"
    r = _cli("simulate", "symmetric", "--duration", "1.0", "--out", str(out), "--quiet")
    assert r.returncode == 0, r.stderr
    assert "impacts" in r.stdout and "real time" in r.stdout
    data = np.load(out)
    assert data["time_s"].size == 25_000
    assert data["left_pivot_fx_n"].shape == data["time_s"].shape
    assert json.loads(str(data["metadata"]))["scenario"] == "symmetric"


def test_simulate_csv(tmp_path):
    out = tmp_path / "run.csv"
    r = _cli("simulate", "case5_left_tilted", "--duration", "0.3", "--out", str(out), "--quiet")
    assert r.returncode == 0, r.stderr
    arr = np.genfromtxt(out, delimiter=",", names=True)
    assert arr["time_s"].size == 7500 and "right_pivot_fy_n" in arr.dtype.names


def test_errors_are_one_line_and_nonzero(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "b"\n[parameters.friction]\ncoefficient = -1.0\n')
    for args in (
        ("simulate", str(bad)),
        ("simulate", "nope"),
        ("simulate", "symmetric", "--dt", "1e-3"),
    ):
        r = _cli(*args)
        assert r.returncode == 2
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("brake-sim: error:"), r.stderr


def test_validate_writes_report_and_json(tmp_path):
    r = _cli("validate", "--out", str(tmp_path / "v"), "--json", str(tmp_path / "f.json"))
    assert r.returncode == 0, r.stderr
    fig = json.loads((tmp_path / "f.json").read_text())
    sym = fig["symmetric"]
    assert set(sym) >= {
        "stop_time_s",
        "first_impact_actuation_n",
        "first_impact_peak_fr_n",
        "period_s",
    }
    assert set(fig["cases"]) == {str(i) for i in range(1, 9)}
    for case in fig["cases"].values():
        assert set(case) >= {
            "shoe",
            "first_impact_actuation_n",
            "peak_fr_change_pct",
            "period_change_pct",
            "contact_fr_change_pct",
            "other_shoe_peak_fr_change_pct",
            "other_shoe_period_change_pct",
        }
    # the study's calibration targets, checked on the figures the command wrote
    failed = [c for c in checks(fig) if not c.passed]
    assert not failed, failed
    report = (tmp_path / "v" / "report.md").read_text()
    assert "| case 1: peak F_r change | -43.0 % |" in report
    for png in (
        "pivot_forces_event.png",
        "pivot_forces_impacting.png",
        "defects_vs_symmetric.png",
        "drum_speed.png",
    ):
        assert (tmp_path / "v" / png).stat().st_size > 10_000
