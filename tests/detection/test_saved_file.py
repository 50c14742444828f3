"""The saved-detector file against hostile input (pure logic: detectors fitted on hand-made
windows): every damaged, wrong or oversized file is refused with one line naming the key
and what is allowed, never a traceback, never echoing what the file holds; a save that
fails leaves no file."""

from __future__ import annotations

import base64
import copy
import json
import os
from pathlib import Path

import numpy as np
import pytest

from brake_sim_ros.cli import main
from brake_sim_ros.detection import saved
from brake_sim_ros.detection.baselines import VibrationThreshold
from brake_sim_ros.detection.detector import SampleChunk, TrainingWindow
from brake_sim_ros.detection.learned import LearnedClassifier

FS = 2560.0
N = 256
MARKER = "zq-planted-text"  # written into files; must never appear in a message
FITTED_ON = {"dataset": "hand-made", "split": "train", "windows": 60}


def _windows() -> list[TrainingWindow]:
    """Runs of 6 windows: healthy (y acceleration std 1) and a lowered friction on the left
    shoe (std 4, severity -30 %)."""
    rng = np.random.default_rng(5)
    out = []
    for r in range(10):
        bad = r % 2 == 1
        for w in range(6):
            channels = {
                "backing_plate_accel_x": rng.normal(0.0, 1.0, N),
                "backing_plate_accel_y": rng.normal(0.0, 4.0 if bad else 1.0, N),
                "wheel_speed": np.zeros(N),
                "line_pressure": np.full(N, 50.0),
            }
            defects = (("friction_change", "left"),) if bad else ()
            out.append(
                TrainingWindow(
                    channels, FS, defects, f"run-{r}", (w + 1) * N - 1, (-30.0,) if bad else ()
                )
            )
    return out


@pytest.fixture(scope="module")
def learned_doc() -> dict:
    d = LearnedClassifier()
    d.fit(_windows())
    return saved.document(d, fitted_on=FITTED_ON)


def _write(tmp_path: Path, doc: object) -> Path:
    path = tmp_path / "model.json"
    path.write_text(json.dumps(doc))
    return path


def _refused(path: Path, name: str | None = "learned") -> str:
    with pytest.raises(saved.ModelFileError) as info:
        saved.load(path, name)
    message = str(info.value)
    assert "\n" not in message and MARKER not in message
    return message


def test_a_valid_file_loads_and_assesses(learned_doc, tmp_path):
    d = saved.load(_write(tmp_path, learned_doc), "learned")
    rng = np.random.default_rng(9)
    y = np.concatenate([rng.normal(0.0, 1.0, 10 * N), rng.normal(0.0, 4.0, 10 * N)])
    n = y.size
    chunk = SampleChunk(
        0,
        FS,
        {
            "backing_plate_accel_x": rng.normal(0.0, 1.0, n),
            "backing_plate_accel_y": y,
            "wheel_speed": np.zeros(n),
            "line_pressure": np.full(n, 50.0),
        },
    )
    found = d.feed(chunk)
    assert not any(a.alarm for a in found[:8])  # healthy first second
    late = [a.diagnosis for a in found[15:] if a.diagnosis is not None]
    assert late and all(x.kind == "friction_change" and x.severity == -30.0 for x in late)


def _split_node(doc: dict, key: str = "left") -> tuple[np.ndarray, int]:
    a = doc["state"]["forest"][key]
    values = np.frombuffer(base64.b64decode(a["base64"]), dtype="<i8").copy()
    return values, int(np.flatnonzero(values != -1)[0])


def _set_array(doc: dict, key: str, values: np.ndarray) -> None:
    doc["state"]["forest"][key]["base64"] = base64.b64encode(values.tobytes()).decode()


def _child_to_itself(doc):
    values, i = _split_node(doc)
    values[i] = i
    _set_array(doc, "left", values)


def _child_outside(doc):
    values, i = _split_node(doc, "right")
    values[i] = 10**9
    _set_array(doc, "right", values)


def _feature_outside(doc):
    _, i = _split_node(doc)
    feature = np.frombuffer(
        base64.b64decode(doc["state"]["forest"]["feature"]["base64"]), dtype="<i8"
    ).copy()
    feature[i] = 10**6
    _set_array(doc, "feature", feature)


def _set(path: tuple, value):
    def mutate(doc):
        target = doc
        for k in path[:-1]:
            target = target[k]
        target[path[-1]] = value

    return mutate


def _drop(key):
    return lambda doc: doc.pop(key)


def _drop_brake(doc):
    doc["fitted_at"].pop("brake")


def _version_2(doc):
    """A file as version 2 wrote it: no brake in fitted_at."""
    _drop_brake(doc)
    doc["schema_version"] = 2


MUTATIONS = {
    "format": (_set(("format",), MARKER), "format"),
    "version": (_set(("schema_version",), 4), "schema_version"),
    "version as a list": (_set(("schema_version",), [2]), "schema_version"),
    "version 1": (_set(("schema_version",), 1), "did not record the rate: fit it again"),
    "version 2": (_version_2, "version 2 did not record the brake: fit it again"),
    "brake": (_set(("fitted_at", "brake"), "tram"), "fitted_at.brake"),
    "brake not recorded as a key": (_drop_brake, "fitted_at: no key 'brake'"),
    "rate": (_set(("fitted_at", "sample_rate_hz"), -5120.0), "fitted_at.sample_rate_hz"),
    "unit": (_set(("fitted_at", "channels"), {"backing_plate_accel_y": 5}), "fitted_at"),
    "version as true": (_set(("schema_version",), True), "schema_version"),
    "other detector": (_set(("detector",), "orders"), "holds a fitted orders"),
    "unknown detector": (_set(("detector",), MARKER), "detector"),
    "unknown key": (_set((MARKER,), 1), "an unknown key"),
    "missing state": (_drop("state"), "no key 'state'"),
    "threshold a string": (_set(("state", "threshold"), MARKER), "state.threshold"),
    "threshold out of range": (_set(("state", "threshold"), 0.2), "state.threshold"),
    "child to itself": (_child_to_itself, "state.forest: left"),
    "child outside": (_child_outside, "state.forest: right"),
    "feature outside": (_feature_outside, "state.forest: feature"),
    "not base64": (_set(("state", "forest", "left", "base64"), MARKER + "!!"), "base64"),
    "wrong length": (_set(("state", "forest", "left", "shape"), [3]), "base64"),
    "dtype": (_set(("state", "forest", "left", "dtype"), MARKER), "left.dtype"),
    "unknown class": (_set(("state", "classes"), ["healthy", MARKER]), "state.classes"),
    "channel": (_set(("parameters", "channels"), ["../" + MARKER]), "parameters.channels"),
    "severity key": (
        _set(("state", "severity"), {"drum_out_of_round:drum": {}}),
        "state.severity",
    ),
    "fitted_on": (_set(("fitted_on", "windows"), -1), "fitted_on.windows"),
}


@pytest.mark.parametrize("case", sorted(MUTATIONS))
def test_a_damaged_document_is_refused_naming_the_key(case, learned_doc, tmp_path):
    mutate, expected = MUTATIONS[case]
    doc = copy.deepcopy(learned_doc)
    mutate(doc)
    assert expected in _refused(_write(tmp_path, doc))


RAW = {
    "NaN": (lambda text: text.replace('"threshold": ', '"threshold": NaN, "x": ', 1), "NaN"),
    "duplicate key": (lambda text: text.replace("{", '{"format": 1, ', 1), "twice"),
    "not JSON": (lambda text: MARKER + text, "not JSON"),
    "truncated": (lambda text: text[: len(text) // 2], "not JSON"),
    "deep": (lambda text: "[" * 100_000 + "]" * 100_000, "nested too deep"),
}


@pytest.mark.parametrize("case", sorted(RAW))
def test_a_damaged_file_is_refused_in_one_line(case, learned_doc, tmp_path):
    change, expected = RAW[case]
    path = tmp_path / "model.json"
    path.write_text(change(json.dumps(learned_doc)))
    assert expected in _refused(path)


def test_files_that_are_not_saved_detectors(learned_doc, tmp_path, monkeypatch):
    binary = tmp_path / "binary.json"
    binary.write_bytes(b"\xff\xfe" + MARKER.encode())
    assert "not UTF-8" in _refused(binary)
    assert "not a regular file" in _refused(tmp_path)
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    assert "not a regular file" in _refused(fifo)  # refused, not waited on
    assert "cannot open" in _refused(tmp_path / "missing.json")
    assert "the file: a list" in _refused(_write(tmp_path, [MARKER]))
    path = _write(tmp_path, learned_doc)
    monkeypatch.setattr(saved, "MAX_MODEL_BYTES", path.stat().st_size - 1)
    assert "allowed at most" in _refused(path)


def test_a_threshold_detector_round_trips_and_checks_its_parameters(tmp_path):
    d = VibrationThreshold("kurtosis", k=3.0)
    d.threshold = 4.25
    doc = saved.document(d, fitted_on=FITTED_ON)
    loaded = saved.load(_write(tmp_path, doc), "kurtosis")
    assert (loaded.name, loaded.channels, loaded.k, loaded.threshold) == (
        "kurtosis",
        d.channels,
        3.0,
        4.25,
    )
    doc["parameters"]["window_s"] = -1.0
    assert "parameters.window_s" in _refused(_write(tmp_path, doc), "kurtosis")
    # a window under a sample at the fitted rate, never one sample standing in for it
    doc["fitted_at"]["sample_rate_hz"] = FS
    doc["parameters"]["window_s"] = 1e-300
    assert "under one sample at 2560 Hz" in _refused(_write(tmp_path, doc), "kurtosis")
    doc["parameters"]["window_s"] = 0.1
    # the units it records are of the channel it reads: a threshold learned on y is never
    # applied to x by a file whose channel was changed
    doc["fitted_at"]["channels"] = {d.channels[0]: "m/s^2"}
    saved.load(_write(tmp_path, doc), "kurtosis")
    doc["parameters"]["channel"] = "backing_plate_accel_x"
    assert "does not read" in _refused(_write(tmp_path, doc), "kurtosis")
    doc["parameters"]["channel"] = d.channels[0]
    for huge in ("1" + "0" * 400, "1e400"):  # Python reads 1e400 as infinity
        path = tmp_path / "huge.json"
        path.write_text(json.dumps(doc).replace('"threshold": 4.25', f'"threshold": {huge}'))
        assert "state.threshold" in _refused(path, "kurtosis")


def test_an_unfitted_detector_has_nothing_to_save():
    with pytest.raises(saved.ModelFileError, match="not fitted"):
        saved.dumps(VibrationThreshold("rms"), fitted_on=FITTED_ON)


def test_monitor_refuses_a_bad_model_in_one_line(tmp_path, capsys):
    bad = tmp_path / "model.json"
    bad.write_text(MARKER)
    with pytest.raises(SystemExit) as info:
        main(["monitor", "--detector", "learned", "--model", str(bad)])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not JSON" in err and MARKER not in err
    with pytest.raises(SystemExit):
        main(["monitor", "--detector", "rms", "--model", str(bad), "--fit", str(tmp_path)])
    assert "allowed one" in capsys.readouterr().err
