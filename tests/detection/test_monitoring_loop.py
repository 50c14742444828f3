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
from brake_sim_ros.datasets.reader import open_dataset
from brake_sim_ros.datasets.sweep import sweep
from brake_sim_ros.detection import evaluate, saved
from brake_sim_ros.detection.registry import make_detector

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "peak_detector.py"
EXAMPLE_SPEC = f"{EXAMPLE}:PeakAcceleration"

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
        "brake": "study",  # the campaign's base, symmetric, runs the study brake
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


def test_a_detector_named_by_its_file_loads_without_the_python_path(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # nowhere near the example, and not on sys.path
    detector = make_detector(EXAMPLE_SPEC)
    assert detector.name == "peak_acceleration"
    relative = tmp_path / "mine" / "peak.py"
    relative.parent.mkdir()
    relative.write_text(EXAMPLE.read_text())
    assert make_detector("mine/peak.py:PeakAcceleration").name == "peak_acceleration"
    with pytest.raises(ValueError, match=r"no file 'mine/none\.py'"):
        make_detector("mine/none.py:PeakAcceleration")
    with pytest.raises(ValueError, match="has no 'Nope'"):
        make_detector("mine/peak.py:Nope")


def test_an_import_error_inside_the_users_module_names_the_missing_module(tmp_path, monkeypatch):
    user = tmp_path / "user_detector_29.py"
    user.write_text("import numpy\nimport no_such_module_29\n")
    with pytest.raises(ValueError) as by_file:
        make_detector(f"{user}:Mine")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(ValueError) as by_module:
        make_detector("user_detector_29:Mine")
    for caught in (by_file, by_module):
        message = str(caught.value)
        assert "\n" not in message
        assert "ModuleNotFoundError" in message and "no_such_module_29" in message, message
        assert f"{user}, line 2" in message, message
    with pytest.raises(ValueError, match="no module 'absent_module_29' on the Python path"):
        make_detector("absent_module_29:Mine")
    (tmp_path / "broken_29.py").write_text("def f(:\n")
    with pytest.raises(ValueError, match=r"SyntaxError.*broken_29\.py, line 1"):
        make_detector(f"{tmp_path / 'broken_29.py'}:Mine")


def test_the_example_detector_is_fitted_saved_loaded_and_scored(slow, tmp_path, capsys):
    model = tmp_path / "peak.json"
    assert cli.main(["fit", str(slow), "--detector", EXAMPLE_SPEC, "--out", str(model)]) == 0
    doc = json.loads(model.read_text())
    assert doc["detector"] == "peak_acceleration" and doc["parameters"] == {}
    assert str(EXAMPLE) not in model.read_text()  # data, never a name of code to run
    out = tmp_path / "score.json"
    argv = ["score", str(slow), "--detector", EXAMPLE_SPEC, "--model", str(model)]
    assert cli.main([*argv, "--out", str(out)]) == 0
    scored = json.loads(out.read_text())
    assert scored["detector"] == "peak_acceleration" and scored["windows"] > 0
    # the loaded detector is the fitted one: the same verdicts, bit for bit
    dataset = open_dataset(slow)
    fitted = make_detector(EXAMPLE_SPEC)
    evaluate.fit(fitted, dataset, "train")
    loaded = saved.load(model, user=make_detector(EXAMPLE_SPEC))
    assert loaded.threshold == fitted.threshold and loaded.fitted_rate_hz == 5120.0
    assert evaluate.score(loaded, dataset) == evaluate.score(fitted, dataset) == scored
    # without its class named, the file is refused (it never names code to import)
    assert cli.main(["score", str(slow), "--model", str(model)]) == cli.EXIT_ERROR
    assert "allowed rms" in capsys.readouterr().err


def test_the_windows_file_gives_the_scores_auroc_and_the_held_out_figures(slow, tmp_path):
    import numpy as np
    import pyarrow.parquet as pq
    from sklearn.metrics import average_precision_score, roc_auc_score

    out, windows = tmp_path / "score.json", tmp_path / "windows.parquet"
    argv = ["score", str(slow), "--detector", "kurtosis", "--out", str(out)]
    assert cli.main([*argv, "--windows", str(windows)]) == 0
    score = json.loads(out.read_text())
    table = pq.read_table(windows).to_pydict()
    run_ids = np.array(table["run_id"])
    y, h = np.array(table["defective"]), np.array(table["health_index"])
    assert y.size == score["windows"] and len(set(run_ids)) == score["runs"]
    assert roc_auc_score(y, h) == score["health_index"]["auroc"]
    assert average_precision_score(y, h) == score["health_index"]["auprc"]
    classes = np.array(table["class"])
    assert set(classes) == {"healthy", "pivot_radius_change:left", "pivot_radius_change:right"}
    assert ((classes == "healthy") == ~y).all()
    # the held-out rule's runs (half the service limit) apart from the rest of the split
    manifest = pq.read_table(slow / "manifest.parquet").to_pydict()
    held_ids = {
        r
        for r, f in zip(manifest["run_id"], manifest["defect_severity_fraction"], strict=True)
        if f == 0.5
    }
    (rule,) = score["held_out"]
    assert rule["rule"]["column"] == "defect_severity_fraction"
    assert rule["held_out"]["runs"] == len(held_ids & set(run_ids)) > 0
    assert rule["held_out"]["runs"] + rule["rest"]["runs"] == score["runs"]
    inside = np.isin(run_ids, sorted(held_ids))
    for part, mask in (("held_out", inside), ("rest", ~inside)):
        assert rule[part]["windows"] == int(mask.sum())
        expected = roc_auc_score(y[mask], h[mask]) if len(set(y[mask])) == 2 else None
        assert rule[part]["health_index"]["auroc"] == expected
    assert cli.main([*argv, "--windows", str(slow / "samples" / "w.parquet")]) == cli.EXIT_ERROR


def _png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"  # a PNG, whole
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")


def test_plot_writes_a_png_for_a_run_of_each_kind_of_source(slow, tmp_path, capsys):
    import matplotlib.image
    import pyarrow as pa
    import pyarrow.parquet as pq

    run = tmp_path / "run.parquet"
    argv = ["simulate", "case5_left_tilted", "--duration", "0.4", "--quiet"]
    assert cli.main([*argv, "--sample-rate", "5120", "--out", str(run)]) == 0
    npz = tmp_path / "run.npz"
    assert cli.main([*argv, "--sample-rate", "5120", "--out", str(npz)]) == 0
    windows = tmp_path / "windows.parquet"
    assert cli.main(["score", str(slow), "--windows", str(windows)]) == 0
    test_run = open_dataset(slow).runs("test")[0]
    cases = {
        "file.png": [str(run)],
        "npz.png": [str(npz)],
        "dataset.png": [str(slow), "--run", test_run, "--windows", str(windows)],
    }
    sizes = {}
    for name, source in cases.items():
        out = tmp_path / name
        assert cli.main(["plot", *source, "--out", str(out)]) == 0, capsys.readouterr().err
        sizes[name] = _png_size(out)
        pixels = matplotlib.image.imread(out)
        assert pixels.std() > 0.05  # drawn, not blank
    assert sizes["dataset.png"][1] > sizes["file.png"][1]  # the health-index panel
    # bad sources: one line each, nothing written
    for bad in ([str(slow), "--out", str(tmp_path / "a.png")],
                [str(slow), "--run", "run-99999", "--out", str(tmp_path / "b.png")],
                [str(run), "--out", str(tmp_path / "c.txt")]):  # fmt: skip
        assert cli.main(["plot", *bad]) == cli.EXIT_ERROR
        assert capsys.readouterr().err.count("\n") == 1
    assert not list(tmp_path.glob("[abc].*"))
    # windows of another run of that id (another dataset's, at another rate: its windows end
    # at other times of the same indices) are refused, not drawn over this run
    table = pq.read_table(windows)
    other = tmp_path / "other.parquet"
    index = table.schema.get_field_index("time_s")
    doubled = pa.array([2.0 * t for t in table["time_s"].to_pylist()], pa.float64())
    pq.write_table(table.set_column(index, table.schema.field(index), doubled), other)
    argv = ["plot", str(slow), "--run", test_run, "--windows", str(other)]
    assert cli.main([*argv, "--out", str(tmp_path / "d.png")]) == cli.EXIT_ERROR
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not a sample of this run" in err
    assert not (tmp_path / "d.png").exists()
