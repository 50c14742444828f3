"""A detector records the brake whose samples it was fitted on, and refuses the other's.

Three small sweeps of one campaign, written by the real sweep and read back from their
Parquet files: on the study brake, on the service brake, and one whose axis runs each unit
on both. A built-in and a user's detector fitted on one brake's runs and scored on the
other's are refused in one line naming both brakes and the run's file; on their own brake
they score; a split of both brakes is not fitted on; and a run file written before the
brake was recorded gives it from its scenario's text.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from brake_sim_ros import cli
from brake_sim_ros.campaigns import load_campaign
from brake_sim_ros.datasets.checked import DatasetError
from brake_sim_ros.datasets.reader import open_dataset
from brake_sim_ros.datasets.run_brake import recorded_brake
from brake_sim_ros.datasets.sweep import sweep
from brake_sim_ros.datasets.sweep_output import run_file
from brake_sim_ros.detection import evaluate
from brake_sim_ros.detection.evaluate import SplitBrakeError
from brake_sim_ros.detection.registry import make_detector

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "peak_detector.py"
EXAMPLE_SPEC = f"{EXAMPLE}:PeakAcceleration"

CAMPAIGN = """
name = "brakes"
base = "symmetric"
{brake}
seed = 31
units = 2
[outputs]
duration_s = 0.4
sample_rate_hz = 5120.0
[[axes]]
{axis}
[split]
train = 0.5
validation = 0.0
test = 0.5
"""
DEFECTS = 'defects = ["friction_change"]\nseverities = [1.0]\nhealthy = true'
BOTH = 'name = "brake"\nkey = "brake"\nvalues = ["study", "service"]'


def _sweep(folder: Path, brake: str, axis: str = DEFECTS) -> Path:
    """A sweep of the campaign; ``brake``: its brake key's line ("": none, the base's)."""
    text = CAMPAIGN.format(brake=brake, axis=axis)
    path = folder / "brakes.toml"
    path.write_text(text)
    out = folder / "data"
    summary, _ = sweep(load_campaign(path), out, workers=1, quiet=True)
    assert summary.failed == 0
    return out


@pytest.fixture(scope="module")
def study(tmp_path_factory) -> Path:
    """The base scenario's brake: symmetric has no brake key, so the study brake."""
    return _sweep(tmp_path_factory.mktemp("study"), "")


@pytest.fixture(scope="module")
def service(tmp_path_factory) -> Path:
    return _sweep(tmp_path_factory.mktemp("service"), 'brake = "service"')


@pytest.fixture(scope="module")
def both(tmp_path_factory) -> Path:
    return _sweep(tmp_path_factory.mktemp("both"), "", BOTH)


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


@pytest.mark.parametrize("spec", ["rms", EXAMPLE_SPEC])
@pytest.mark.parametrize(("fitted", "other"), [("study", "service"), ("service", "study")])
def test_a_detector_fitted_on_one_brake_is_refused_on_the_other_by_score(
    spec, fitted, other, study, service, tmp_path, capsys
):
    data = {"study": study, "service": service}
    model = tmp_path / "model.json"
    argv = ["fit", str(data[fitted]), "--detector", spec, "--out", str(model)]
    assert cli.main(argv) == 0
    assert f"on the {fitted} brake): {model}" in capsys.readouterr().out
    assert json.loads(model.read_text())["fitted_at"]["brake"] == fitted
    user = [] if spec == "rms" else ["--detector", spec]  # a user's class is named
    assert cli.main(["score", str(data[other]), "--model", str(model), *user]) == cli.EXIT_ERROR
    err = _one_line_error(capsys)
    assert f"was fitted on the {fitted} brake's samples" in err, err
    assert f"comes from the {other} brake" in err and "part-0.parquet" in err, err
    # on its own brake it scores, and says what it was fitted on
    assert cli.main(["score", str(data[fitted]), "--model", str(model), *user]) == 0
    assert f"(fitted at 5120 Hz on the {fitted} brake)" in capsys.readouterr().out


def test_score_fits_and_scores_one_brakes_runs(service, capsys):
    assert cli.main(["score", str(service), "--detector", "rms"]) == 0
    assert "at 5120 Hz on the service brake), scored on test" in capsys.readouterr().out
    dataset = open_dataset(service)
    detector = make_detector("rms")
    evaluate.fit(detector, dataset, "train")
    assert detector.fitted_brake == "service"
    assert evaluate.score(detector, dataset, "test")["runs"] == len(dataset.runs("test"))


def test_a_split_of_both_brakes_is_not_fitted_on(both, tmp_path, capsys):
    dataset = open_dataset(both)
    brakes = {evaluate.read_run(dataset, r).brake for r in dataset.runs("train")}
    assert brakes == {"study", "service"}
    with pytest.raises(SplitBrakeError, match="runs from the service and the study brake"):
        evaluate.fit(make_detector("rms"), dataset, "train")
    model = tmp_path / "model.json"
    argv = ["fit", str(both), "--detector", "rms", "--out", str(model)]
    assert cli.main(argv) == cli.EXIT_ERROR
    assert "allowed one brake's runs to fit a detector on" in _one_line_error(capsys)
    assert not model.exists()


def _table(root: Path, run_id: str) -> pa.Table:
    return pq.read_table(root / run_file(run_id))


def _with_meta(table: pa.Table, change) -> pa.Table:
    meta = json.loads(table.schema.metadata[b"brake_sim"])
    change(meta)
    return table.replace_schema_metadata({b"brake_sim": json.dumps(meta).encode()})


def test_a_run_file_records_its_brake_and_an_older_one_gives_it_by_its_scenario(study, service):
    """A new file's metadata names its brake; a file written before that field (the same
    file without it) gives it from its scenario's text: the study brake where the text has
    no brake key, the service brake where the campaign set it."""
    for root, brake in ((study, "study"), (service, "service")):
        table = _table(root, open_dataset(root).runs()[0])
        assert json.loads(table.schema.metadata[b"brake_sim"])["brake"] == brake
        assert recorded_brake(table, "here") == brake
        older = _with_meta(table, lambda m: m.pop("brake"))
        assert recorded_brake(older, "here") == brake
    table = _table(study, open_dataset(study).runs()[0])
    text = json.loads(table.schema.metadata[b"brake_sim"])["scenario_toml"]
    assert "brake" not in tomllib.loads(text)  # the older file's brake is the default's

    def neither(meta: dict) -> None:
        meta.pop("brake")
        meta.pop("scenario_toml")

    cases = {
        "neither": (_with_meta(table, neither), "records neither the brake nor"),
        "unknown": (
            _with_meta(table, lambda m: m.update(brake="tram")),
            "brake 'tram' in its metadata; allowed ['study', 'service']",
        ),
        "no metadata": (table.replace_schema_metadata({}), "no brake_sim metadata"),
    }
    for changed, words in cases.values():
        with pytest.raises(DatasetError) as caught:
            recorded_brake(changed, "run 7")
        assert str(caught.value).startswith("run 7: ") and words in str(caught.value)
        assert "\n" not in str(caught.value)


def test_evaluation_refuses_the_other_brake_and_a_brake_not_recorded_is_not_checked(study, service):
    """From Python: ``evaluate.score`` raises the same one line; a detector whose brake is
    not recorded (built by hand, never fitted on a dataset, as a saved file's null brake)
    judges either brake's runs."""
    fitted = make_detector("rms")
    evaluate.fit(fitted, open_dataset(study), "train")
    assert fitted.fitted_brake == "study"
    with pytest.raises(ValueError, match="comes from the service brake") as caught:
        evaluate.score(fitted, open_dataset(service), "test")
    assert "\n" not in str(caught.value)
    by_hand = make_detector("rms")
    by_hand.threshold = fitted.threshold
    assert by_hand.fitted_brake is None
    for root in (study, service):
        dataset = open_dataset(root)
        assert evaluate.score(by_hand, dataset, "test")["runs"] == len(dataset.runs("test"))
