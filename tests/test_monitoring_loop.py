"""The monitoring developer's loop over real sweeps: what a detector was fitted on is
recorded and enforced, and the scores can be taken further.

Two small sweeps of one campaign, at 5120 Hz and at the node's 25.6 kHz, written by the
real sweep and read back from their Parquet files.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from brake_sim_ros import cli
from brake_sim_ros.campaigns import load_campaign
from brake_sim_ros.datasets.sweep import sweep

CAMPAIGN = """
name = "loop"
base = "symmetric"
seed = 29
units = 4
[outputs]
duration_s = 0.4
sample_rate_hz = {rate}
[[axes]]
defects = ["pivot_radius_change"]
severities = [0.5, 1.0]
healthy = true
[split]
train = 0.5
validation = 0.0
test = 0.5
[[split.held_out]]
column = "defect_severity_fraction"
values = [0.5]
"""


def _sweep(folder: Path, rate: float) -> Path:
    path = folder / f"loop-{rate:g}.toml"
    path.write_text(CAMPAIGN.format(rate=rate))
    out = folder / f"data-{rate:g}"
    summary, _ = sweep(load_campaign(path), out, workers=1, quiet=True)
    assert summary.failed == 0
    return out


@pytest.fixture(scope="module")
def slow(tmp_path_factory) -> Path:
    """The campaign at 5120 Hz."""
    return _sweep(tmp_path_factory.mktemp("slow"), 5120.0)


@pytest.fixture(scope="module")
def fast(tmp_path_factory) -> Path:
    """The same campaign at 25 600 Hz, the node's default rate."""
    return _sweep(tmp_path_factory.mktemp("fast"), 25600.0)


def test_a_detector_fitted_at_5120_hz_is_refused_at_25600_hz_by_score(slow, fast, tmp_path, capsys):
    model = tmp_path / "rms.json"
    assert cli.main(["fit", str(slow), "--detector", "rms", "--out", str(model)]) == 0
    doc = json.loads(model.read_text())
    assert doc["fitted_at"] == {
        "sample_rate_hz": 5120.0,
        "channels": {"backing_plate_accel_y": "m/s^2"},
    }
    capsys.readouterr()
    assert cli.main(["score", str(fast), "--model", str(model)]) == cli.EXIT_ERROR
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert "fitted at 5120 Hz" in err and "at 25600 Hz" in err
    # fitted and scored at one rate, it scores
    assert cli.main(["score", str(fast), "--detector", "rms"]) == 0
    assert cli.main(["score", str(slow), "--model", str(model)]) == 0
