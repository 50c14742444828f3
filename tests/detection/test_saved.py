"""Saved fitted detectors on a real small sweep (real worker processes, real Parquet): every
baseline that fits, saved and loaded, gives bit for bit the assessments of the fitted one
on every test run; ``brake-sim fit`` then ``score --model`` scores as fitting does; the
learned baseline's severity estimates reach the score's per-class figures; and a saved
file is written whole, never over an input or through a link."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from brake_sim_ros.campaigns import load_campaign
from brake_sim_ros.cli import main
from brake_sim_ros.datasets import open as open_dataset
from brake_sim_ros.datasets.sweep import sweep
from brake_sim_ros.detection import evaluate, saved
from brake_sim_ros.detection.detector import Assessment, Detector, Diagnosis
from brake_sim_ros.detection.forest import ForestArrays
from brake_sim_ros.detection.order_analysis import OrderAnalysis
from brake_sim_ros.detection.registry import make_detector
from brake_sim_ros.model.catalogue import KIND_BY_NAME

CAMPAIGN = """
name = "saved"
base = "symmetric"
seed = 7
units = 3
[outputs]
duration_s = 1.0
sample_rate_hz = 2560.0
[[axes]]
defects = ["drum_out_of_round", "friction_change"]
severities = [0.5, 1.0]
healthy = true
"""


@pytest.fixture(scope="module")
def dataset_dir(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("campaign") / "saved.toml"
    path.write_text(CAMPAIGN)
    out = tmp_path_factory.mktemp("sweep") / "out"
    sweep(load_campaign(path), out, workers=2, quiet=True)
    return out


@pytest.fixture(scope="module")
def dataset(dataset_dir):
    return open_dataset(dataset_dir)


_FITTED: dict[tuple[int, str], Detector] = {}


def _fitted(name: str, dataset) -> Detector:
    """``name`` fitted on the train split, once per dataset (callers only read it)."""
    key = (id(dataset), name)
    if key not in _FITTED:
        # the default order analysis needs longer runs (1 s histories, a quiet backing
        # plate): a 0.3 s history without the gate fits on these 1 s runs
        if name == "orders":
            detector: Detector = OrderAnalysis(history_s=0.3, gate_channel=None)
        else:
            detector = make_detector(name)
        evaluate.fit(detector, dataset, "train")
        _FITTED[key] = detector
    return _FITTED[key]


def _key(a: Assessment) -> tuple:
    """An assessment as exact bits (NaN severities compare equal to each other)."""
    d = a.diagnosis
    diagnosis = None if d is None else (d.kind, d.location, repr(d.severity), repr(d.confidence))
    return a.sample_index, repr(a.time_s), repr(a.health_index), a.alarm, diagnosis


@pytest.mark.slow
@pytest.mark.parametrize("name", ["rms", "kurtosis", "crest", "orders", "learned"])
def test_a_loaded_detector_assesses_bit_for_bit_as_the_fitted_one(name, dataset, tmp_path):
    fitted = _fitted(name, dataset)
    path = tmp_path / f"{name}.json"
    fitted_on = {"dataset": "sweep", "split": "train", "windows": 0}
    path.write_text(saved.dumps(fitted, fitted_on=fitted_on))
    loaded = saved.load(path, name)
    assert type(loaded) is type(fitted) and loaded is not fitted
    windows = alarms = diagnoses = 0
    for run_id in dataset.runs("test"):
        run = evaluate.read_run(dataset, run_id)
        expected = [_key(a) for a in evaluate.assess_run(fitted, run, 0.1)]
        assert [_key(a) for a in evaluate.assess_run(loaded, run, 0.1)] == expected
        windows += len(expected)
        alarms += sum(k[3] for k in expected)
        diagnoses += sum(k[4] is not None for k in expected)
    assert windows == 7 * 10  # 7 test runs of 1 s, a window every 0.1 s
    if name in ("orders", "learned"):  # the comparison covers alarms and diagnoses
        assert alarms > 0 and diagnoses > 0
    # the loaded one saves to the same file, byte for byte
    again = tmp_path / "again.json"
    again.write_text(saved.dumps(loaded, fitted_on=fitted_on))
    assert again.read_bytes() == path.read_bytes()


def test_forest_arrays_predict_as_scikit_learn(dataset):
    """The arrays' prediction is scikit-learn's, bit for bit, on every training feature row
    (the classifier and each severity regressor), not only at the alarms."""
    detector = _fitted("learned", dataset)
    rng = np.random.default_rng(3)
    X = rng.normal(0.0, 1.0, (200, detector.model.named_steps["forest"].n_features_in_))
    X[::7, 5] = np.nan  # the imputer's part
    X *= np.abs(rng.normal(0.0, 1e3, X.shape[1]))  # every feature's scale, roughly
    forest = ForestArrays.from_sklearn(detector.model)
    assert forest.check() is None
    assert np.array_equal(forest.predict_proba(X), detector.model.predict_proba(X))
    assert detector.severity_models
    for model in detector.severity_models.values():
        arrays = ForestArrays.from_sklearn(model)
        assert np.array_equal(arrays.predict(X), model.predict(X))


@pytest.mark.slow
def test_fit_then_score_with_the_model_scores_as_fitting(dataset_dir, dataset, tmp_path, capsys):
    model = tmp_path / "learned.json"
    assert main(["fit", str(dataset_dir), "--detector", "learned", "--out", str(model)]) == 0
    doc = json.loads(model.read_text())
    assert doc["format"] == saved.FORMAT and doc["schema_version"] == saved.SCHEMA_VERSION
    assert doc["detector"] == "learned" and doc["fitted_on"]["windows"] == 70
    out = tmp_path / "score.json"
    args = ["score", str(dataset_dir), "--detector", "learned", "--model", str(model)]
    assert main([*args, "--out", str(out)]) == 0
    expected = evaluate.score(_fitted("learned", dataset), dataset, "test")
    assert json.loads(out.read_text()) == json.loads(json.dumps(expected))
    # without --detector: the detector the file holds
    out.unlink()
    assert main(["score", str(dataset_dir), "--model", str(model), "--out", str(out)]) == 0
    assert json.loads(out.read_text())["detector"] == "learned"
    # a file of another detector is refused in one line, before any scoring
    capsys.readouterr()
    assert main([*args[:3], "orders", *args[4:]]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert "detector: the file holds a fitted learned" in captured.err
    assert main([*args, "--fit-split", "train"]) == 2  # a saved detector is fitted already
    assert "--fit-split with --model" in capsys.readouterr().err


@pytest.mark.slow
def test_learned_severity_per_class_on_the_test_split(dataset):
    """The learned baseline's diagnoses carry severities in the kind's unit, between the
    smallest and largest trained (a forest averages training targets), and the score
    gives the severity error per diagnosed class."""
    detector = _fitted("learned", dataset)
    trained = {
        c: (KIND_BY_NAME[c.split(":")[0]].service_limit * np.array([0.5, 1.0]))
        for c in detector.severity_models
    }
    assert set(trained) == {
        "drum_out_of_round:drum",
        "friction_change:left",
        "friction_change:right",
    }
    score = evaluate.score(detector, dataset, "test")
    severity = score["severity"]
    assert severity is not None and severity["windows"] > 0
    assert sum(f["windows"] for f in severity["per_class"].values()) == severity["windows"]
    for run_id in dataset.runs("test"):
        run = evaluate.read_run(dataset, run_id)
        for a in evaluate.assess_run(detector, run, 0.1):
            d = a.diagnosis
            if d is not None:
                low, high = sorted(trained[f"{d.kind}:{d.location}"])
                assert low - 1e-9 <= d.severity <= high + 1e-9
    for label, figures in severity["per_class"].items():
        kind = KIND_BY_NAME[label.split(":")[0]]
        assert figures["unit"] == kind.unit
        assert figures["rmse_of_service_limit"] == pytest.approx(
            figures["rmse"] / abs(kind.service_limit)
        )


class SaysDrumAt(Detector):
    """Alarms on every window and says the drum is 100 um out of round."""

    name = "drum-100"
    channels = ("backing_plate_accel_y",)
    window_s = 0.1

    def assess(self, window, last_sample_index: int, sample_rate_hz: float) -> Assessment:
        return Assessment(
            last_sample_index,
            last_sample_index / sample_rate_hz,
            2.0,
            True,
            Diagnosis("drum_out_of_round", "drum", 100.0, 1.0),
        )


def test_severity_error_of_a_known_estimate(dataset):
    """Known answer: the test unit's drums are 75 and 150 um out of round (half and all of
    the 150 um service limit), 10 windows each; an estimate of 100 um is 25 um high on the
    first and 50 um low on the second: rmse sqrt((25^2 + 50^2) / 2), mean error
    (25 - 50) / 2 = -12.5 um. The
    windows of the friction runs, misdiagnosed as the drum, are isolation errors and not
    in the severity figures."""
    score = evaluate.score(SaysDrumAt(), dataset, "test")
    figures = score["severity"]["per_class"]
    assert set(figures) == {"drum_out_of_round:drum"}
    drum = figures["drum_out_of_round:drum"]
    assert drum["windows"] == 20 and drum["unit"] == "um"
    assert drum["rmse"] == pytest.approx(math.sqrt((25.0**2 + 50.0**2) / 2.0), rel=1e-12)
    assert drum["mean_error"] == pytest.approx(-12.5, rel=1e-12)
    assert drum["rmse_of_service_limit"] == pytest.approx(drum["rmse"] / 150.0, rel=1e-12)
    assert score["severity"]["rmse"] == drum["rmse"]


def test_fit_writes_whole_files_never_over_an_input_or_through_a_link(dataset_dir, tmp_path):
    base = ["fit", str(dataset_dir), "--detector", "rms", "--out"]
    manifest = dataset_dir / "manifest.parquet"
    before = manifest.read_bytes()
    assert main([*base, str(manifest), "--overwrite"]) == 2  # the input
    assert manifest.read_bytes() == before
    target = tmp_path / "target.json"
    target.write_text("keep")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    assert main([*base, str(link), "--overwrite"]) == 2  # a link
    assert target.read_text() == "keep" and link.is_symlink()
    assert main([*base, str(target)]) == 2  # exists, no --overwrite
    assert target.read_text() == "keep"
    inside = dataset_dir / "samples" / "model.json"  # would be read as a sample file
    assert main([*base, str(inside)]) == 2 and not inside.exists()

    # a write that fails midway leaves no file, and no partial one
    def fail_midway(self, text, encoding=None):
        with open(self, "w") as f:
            f.write(text[:10])
        raise OSError("disk full")

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(Path, "write_text", fail_midway)
        with pytest.raises(OSError, match="disk full"):
            main([*base, str(tmp_path / "rms.json")])
    # a user's detector has no saved form: refused before fitting, nothing written
    user = ["fit", str(dataset_dir), "--detector", "tests.detection.test_saved:SaysDrumAt"]
    assert main([*user, "--out", str(tmp_path / "user.json")]) == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.json", "target.json"]
