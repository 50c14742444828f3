"""A detector over a real sweep (real worker processes, real Parquet): fitted on train,
scored on test, the score's figures checked against what a detector that always alarms
must get, and the threshold baseline scored twice to the same JSON."""

from __future__ import annotations

import json
from collections.abc import Mapping

import numpy as np
import pytest

from brake_sim_ros.campaigns import load_campaign
from brake_sim_ros.datasets import open as open_dataset
from brake_sim_ros.datasets.sweep import sweep
from brake_sim_ros.detection import evaluate
from brake_sim_ros.detection.detector import Assessment, Detector
from brake_sim_ros.detection.registry import make_detector

CAMPAIGN = """
name = "scored"
base = "symmetric"
seed = 5
units = 3
[outputs]
duration_s = 0.5
sample_rate_hz = 2560.0
[[axes]]
defects = ["initial_angle"]
severities = [1.0]
healthy = true
"""


class AlwaysAlarm(Detector):
    """Alarms on every window: every defective run is detected one hold after its onset
    (all onsets are at 0 here), every healthy run has exactly one false alarm."""

    name = "always"
    channels = ("backing_plate_accel_y",)
    window_s = 0.05

    def assess(
        self, window: Mapping[str, np.ndarray], last_sample_index: int, sample_rate_hz: float
    ) -> Assessment:
        return Assessment(last_sample_index, last_sample_index / sample_rate_hz, 2.0, True)


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    return _swept(tmp_path_factory.mktemp("scored"), "scored.toml", {"scored.toml": CAMPAIGN})


def _swept(folder, campaign: str, files: dict[str, str]):
    """The dataset of ``campaign`` swept into ``folder``, its ``files`` (name -> text:
    the campaign and any scenario it names) written there first."""
    for name, text in files.items():
        (folder / name).write_text(text)
    sweep(load_campaign(folder / campaign), folder / "out", workers=2, quiet=True)
    return open_dataset(folder / "out")


def test_scores_of_a_detector_that_always_alarms(dataset):
    detector = make_detector("tests.detection.test_evaluate:AlwaysAlarm")
    score = evaluate.score(detector, dataset, "test", hold_s=0.1)
    runs = dataset.runs("test")
    per_run = {r["run_id"]: r for r in score["per_run"]}
    assert score["runs"] == len(runs) == len(per_run) > 0
    healthy = [r for r in per_run.values() if not r["defects"]]
    defective = [r for r in per_run.values() if r["defects"]]
    assert healthy and defective
    # windows of 128 samples (0.05 s at 2560 Hz) end at 0.0496 s, 0.0996 s, ...: the run
    # of alarms is held 0.1 s at the end of the third window, 0.1496 s after the start
    first_held = 3 * 128 / 2560.0 - 1 / 2560.0
    for r in defective:
        assert r["onset_s"] == 0.0
        assert r["delay_s"] == pytest.approx(first_held)
    per_class = score["detection"].pop("per_class")
    classes = {c for r in defective for c in r["defects"][:1]}
    assert set(per_class) == classes == {"initial_angle:left", "initial_angle:right"}
    for c, figures in per_class.items():
        runs_of_class = sum(r["defects"][:1] == [c] for r in defective)
        assert figures == {
            "defective_runs": runs_of_class,
            "detected": runs_of_class,
            "median_delay_s": pytest.approx(first_held),
        }
    assert score["detection"] == {
        "defective_runs": len(defective),
        "detected": len(defective),
        "missed": 0,
        "delays_s": [pytest.approx(first_held)] * len(defective),
        "median_delay_s": pytest.approx(first_held),
    }
    assert score["false_alarms"]["count"] == len(healthy)  # one held run of alarms each
    hours = len(healthy) * 0.5 / 3600.0  # every sample of a healthy run, 0.5 s each
    assert score["false_alarms"]["healthy_hours"] == pytest.approx(hours, rel=0.02)
    assert score["health_index"]["auroc"] == 0.5  # one value for all: no ranking
    assert score["health_index"]["roc"] == {"fpr": [0.0, 1.0], "tpr": [0.0, 1.0]}
    for figures in score["health_index"]["per_class"].values():
        assert figures["auroc"] == 0.5 and figures["windows"] > 0
    assert score["isolation"] is None and score["severity"] is None


def test_the_threshold_baseline_scores_deterministically(dataset):
    scores = []
    for _ in range(2):
        detector = make_detector("rms")
        assert evaluate.fit(detector, dataset, "train") > 0
        scores.append(json.dumps(evaluate.score(detector, dataset, "test"), sort_keys=True))
    assert scores[0] == scores[1]
    score = json.loads(scores[0])
    assert score["schema_version"] == evaluate.SCHEMA_VERSION and score["detector"] == "rms"
    assert 0.0 <= score["health_index"]["auroc"] <= 1.0


def test_offline_chunking_does_not_change_the_assessments(dataset):
    run = evaluate.read_run(dataset, dataset.runs("test")[0])
    detector = make_detector("rms")
    evaluate.fit(detector, dataset, "train")
    a = evaluate.assess_run(detector, run, chunk_s=0.1)
    b = evaluate.assess_run(detector, run, chunk_s=0.0137)
    assert a == b and len(a) == 5  # 0.5 s in windows of 0.1 s


def test_the_score_command_writes_the_json_and_refuses_in_one_line(dataset, tmp_path, capsys):
    from brake_sim_ros import cli

    out = tmp_path / "score.json"
    assert cli.main(["score", str(dataset.root), "--detector", "kurtosis", "--out", str(out)]) == 0
    score = json.loads(out.read_text())
    assert score["detector"] == "kurtosis" and score["split"] == "test"
    assert "scored on test" in capsys.readouterr().out
    assert cli.main(["score", str(dataset.root), "--detector", "no_module_xyz:X"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no module 'no_module_xyz'" in err
    assert cli.main(["score", str(dataset.root), "--hold", "-1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--hold" in err
    link = tmp_path / "link.json"
    link.symlink_to(out)
    assert cli.main(["score", str(dataset.root), "--out", str(link)]) == 2
    assert json.loads(out.read_text())["detector"] == "kurtosis"  # not written through


@pytest.mark.parametrize(
    ("option", "where", "words"),
    [
        ("--out", "manifest.parquet", "an output never replaces an input"),
        ("--out", "campaign.lock", "an output never replaces an input"),
        ("--windows", "manifest.parquet", "an output never replaces an input"),
        ("--out", "samples/x.json", "inside the dataset's samples"),
        ("--windows", "samples/w.parquet", "inside the dataset's samples"),
        ("--report", "samples/rep", "inside the dataset's samples"),
        ("--out", None, "allowed a file path"),
        ("--windows", None, "allowed a FILE.parquet path"),
        ("--report", None, "allowed a directory path"),
        ("--detector", None, "allowed a detector's name"),
        ("--model", None, "allowed a saved detector's file"),
    ],
)
def test_score_never_writes_over_its_dataset_nor_takes_an_empty_option(
    dataset, option, where, words, capsys
):
    """The dataset is score's input: its manifest and lock are never replaced and nothing is
    written among its samples (it would be read as one); an empty path or name is refused,
    never taken as the option left out. One line each, before the work, nothing changed."""
    from brake_sim_ros import cli

    before = {p: p.read_bytes() for p in dataset.root.rglob("*") if p.is_file()}
    value = "" if where is None else str(dataset.root / where)
    assert cli.main(["score", str(dataset.root), option, value]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err, err
    after = {p: p.read_bytes() for p in dataset.root.rglob("*") if p.is_file()}
    assert after == before


@pytest.mark.slow
def test_the_baselines_report_is_written_whole_and_the_same_twice(dataset, tmp_path, capsys):
    from brake_sim_ros import cli

    reports = [tmp_path / "a", tmp_path / "b"]
    for out in reports:
        argv = ["score", str(dataset.root), "--detector", "learned", "--detector", "rms"]
        assert cli.main([*argv, "--report", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "detector learned" in printed and "detector rms" in printed
    for name in ("score-learned.json", "score-rms.json"):
        a, b = ((r / name).read_text() for r in reports)
        assert a == b  # fixed seeds, one job: the same forest, the same figures
        score = json.loads(a)
        assert score["schema_version"] == evaluate.SCHEMA_VERSION
        assert score["runs"] == len(dataset.runs("test"))
    for name in ("roc.png", "delays.png"):
        assert (reports[0] / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    learned = json.loads((reports[0] / "score-learned.json").read_text())
    if learned["isolation"] is not None:  # it diagnosed: its matrix is drawn
        assert (reports[0] / "confusion-learned.png").is_file()
    link = tmp_path / "link"
    link.symlink_to(reports[0], target_is_directory=True)
    assert cli.main(["score", str(dataset.root), "--report", str(link)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "a link" in err
    argv = ["score", str(dataset.root), "--detector", "rms", "--detector", "orders"]
    assert cli.main([*argv, "--out", str(tmp_path / "x.json")]) == 2
    assert "allowed one detector" in capsys.readouterr().err
    # 0.5 s runs: the order detector's second of history never sees the quiet sliding
    assert cli.main(["score", str(dataset.root), "--detector", "orders"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "healthy training histories" in err


# A pivot radius growing linearly from 0 at t = 0 at 1.5 %/s toward 4 %: it reaches the 3 %
# service limit at 2 s, after the runs' 0.5 s, so each run's ``rul [s]`` label is 2 - t
# (its growth law's time, datasets/life.py).
GROWING = """
name = "growing"
duration_s = 0.5
sample_rate_hz = 2560.0
[defects.left]
pivot_radius_change_pct = {value = 4.0, growth = "linear", rate_per_s = 1.5}
"""
FORECAST_CAMPAIGN = """
name = "forecast"
base = "growing.toml"
seed = 9
units = 3
[[axes]]
name = "peak_force_n"
key = "actuation.peak_force_n"
values = [1000.0, 1300.0]
"""
LATE_S = 0.25


class LateForecast(Detector):
    """Forecasts the remaining life LATE_S too late at every other window (and gives no
    forecast at the others): every scored forecast is off by +LATE_S."""

    name = "late"
    channels = ("backing_plate_accel_y",)
    window_s = 0.05

    def assess(
        self, window: Mapping[str, np.ndarray], last_sample_index: int, sample_rate_hz: float
    ) -> Assessment:
        t = last_sample_index / sample_rate_hz
        n = round(self.window_s * sample_rate_hz)
        rul = 2.0 - t + LATE_S if (last_sample_index // n) % 2 else float("nan")
        return Assessment(last_sample_index, t, 0.0, False, rul_s=rul)


def test_forecasts_are_scored_against_the_rul_label(tmp_path_factory):
    files = {"growing.toml": GROWING, "forecast.toml": FORECAST_CAMPAIGN}
    data = _swept(tmp_path_factory.mktemp("forecast"), "forecast.toml", files)
    run = evaluate.read_run(data, data.runs("test")[0])
    assert run.rul_s is not None
    np.testing.assert_allclose(run.rul_s, 2.0 - run.time_s, atol=1e-9)
    score = evaluate.score(LateForecast(), data, "test")
    runs = score["runs"]
    assert runs == 2  # one test unit, two forces
    windows = runs * 10 // 2  # 10 windows of 0.05 s per run, every other one forecast
    f = score["forecast"]
    assert f["windows"] == windows
    assert f["rmse_s"] == pytest.approx(LATE_S, abs=1e-9)
    assert f["mean_error_s"] == pytest.approx(LATE_S, abs=1e-9)
    assert f["rul_score"] == pytest.approx(windows * np.expm1(LATE_S / 10.0), rel=1e-9)
    # a detector that never forecasts has no forecast figures
    assert evaluate.score(AlwaysAlarm(), data, "test")["forecast"] is None


class TwoPasses(AlwaysAlarm):
    """Iterates its training windows twice; in each pass it checks that the windows of a run
    it has left are no longer held by anyone (the fit streams the split run by run)."""

    def fit(self, windows) -> None:
        import gc
        import weakref

        self.passes: list[list[tuple[str, int]]] = []
        self.freed = 0
        for _ in range(2):
            seen: list[tuple[str, int]] = []
            previous = None  # a weak reference to the last run's channel array
            for w in windows:
                if seen and w.run_id != seen[-1][0]:
                    gc.collect()
                    assert previous() is None, "an earlier run's samples are still held"
                    self.freed += 1
                seen.append((w.run_id, w.last_sample_index))
                previous = weakref.ref(w.channels[self.channels[0]].base)
                del w
            self.passes.append(seen)


def test_fit_streams_the_split_run_by_run_and_may_iterate_it_again(dataset):
    detector = TwoPasses()
    count = evaluate.fit(detector, dataset, "train")
    first, second = detector.passes
    assert first == second and count == len(first) > 0
    runs = dataset.runs("train")
    assert [r for r, _ in first[:: len(first) // len(runs)]] == runs  # run by run, in order
    assert detector.freed == 2 * (len(runs) - 1)
    assert detector.fitted_rate_hz == 2560.0


def test_a_split_at_two_sample_rates_is_one_line_not_the_detectors_error(dataset, tmp_path):
    other = _swept(tmp_path, "other.toml", {"other.toml": CAMPAIGN.replace("2560.0", "5120.0")})
    mixed = [(dataset, r) for r in dataset.runs("train")[:1]]
    mixed += [(other, r) for r in other.runs("train")[:1]]

    class Mixed:  # a split whose runs come from both datasets, in that order
        def runs(self, split):
            return [f"{i}" for i in range(len(mixed))]

    original = evaluate.read_run
    try:
        evaluate.read_run = lambda _, run_id: original(*mixed[int(run_id)])
        with pytest.raises(evaluate.SplitRateError, match=r"^split train: runs at 2560, 5120 Hz"):
            evaluate.fit(TwoPasses(), Mixed(), "train")
    finally:
        evaluate.read_run = original


def test_a_run_without_the_detectors_channel_is_one_line_not_the_detectors_error(
    dataset, tmp_path, capsys
):
    """A train run whose file lacks a measured channel (rehashed into its manifest, so that
    it reads as intact) is named in one line before the detector's fit sees its windows."""
    import hashlib
    import shutil

    import pyarrow as pa
    import pyarrow.parquet as pq

    from brake_sim_ros import cli

    root = tmp_path / "ds"
    shutil.copytree(dataset.root, root)
    manifest = pq.read_table(root / "manifest.parquet")
    rows = manifest.to_pylist()
    row = next(r for r in rows if r["run_id"] == dataset.runs("train")[1])
    path = root / row["file"]
    table = pq.read_table(path)
    measured = [c for c in table.column_names if c.startswith("measured:")]
    pq.write_table(table.drop(measured).replace_schema_metadata(table.schema.metadata), path)
    row["sha256"] = hashlib.sha256(path.read_bytes()).hexdigest()
    pq.write_table(pa.Table.from_pylist(rows, schema=manifest.schema), root / "manifest.parquet")
    for argv in (
        ["fit", str(root), "--detector", "rms", "--out", str(tmp_path / "m.json")],
        ["score", str(root), "--detector", "rms"],
    ):
        assert cli.main(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"run {row['run_id']}" in err and "no channel" in err
    assert not (tmp_path / "m.json").exists()
