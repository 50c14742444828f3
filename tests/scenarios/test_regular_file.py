"""The one bounded read of a checked file (regular_file.py), and each caller's wording of
its refusals: scenario files, a sweep's files, saved detectors."""

from __future__ import annotations

import os

import pytest

from brake_sim_ros import regular_file
from brake_sim_ros.datasets.checked import DatasetError, read_bytes
from brake_sim_ros.detection.saved import MAX_MODEL_BYTES, ModelFileError, read_document
from brake_sim_ros.errors import ScenarioError
from brake_sim_ros.regular_file import FileRefusedError, read_regular_file
from brake_sim_ros.scenarios.files import read_scenario_text


def _reason(path: os.PathLike[str] | str, limit: int = 100, **kw: bool) -> FileRefusedError:
    with pytest.raises(FileRefusedError) as info:
        read_regular_file(path, limit, **kw)
    return info.value


@pytest.fixture
def files(tmp_path):
    """A file of 10 bytes, a link to it, a FIFO and a directory."""
    (tmp_path / "ten").write_bytes(b"0123456789")
    (tmp_path / "link").symlink_to(tmp_path / "ten")
    os.mkfifo(tmp_path / "fifo")
    (tmp_path / "dir").mkdir()
    return tmp_path


def test_a_regular_file_up_to_the_limit_is_read_whole(files):
    assert read_regular_file(files / "ten", 10) == b"0123456789"
    assert read_regular_file(files / "link", 10) == b"0123456789"  # a link is followed


def test_each_refusal_has_its_reason(files):
    assert _reason(files / "ten", 9).reason == regular_file.TOO_LARGE
    assert _reason(files / "ten", 9).size == 10
    missing = _reason(files / "nothing")
    assert (missing.reason, missing.detail) == (regular_file.MISSING, os.strerror(2))
    assert _reason(files / "link", follow_symlinks=False).reason == regular_file.NOT_OPENED
    assert _reason("a\x00b").reason == regular_file.NOT_A_PATH
    for name, kind in (("fifo", "a FIFO (named pipe)"), ("dir", "a directory")):
        refused = _reason(files / name)  # the FIFO is refused, not waited on
        assert (refused.reason, refused.detail) == (regular_file.NOT_REGULAR, kind)
    assert _reason("/dev/zero").detail == "a character device"


def test_each_caller_words_the_refusals_its_own_way(files):
    cases = [
        (lambda p: read_scenario_text(p), ScenarioError, "cannot read the scenario file: it is"),
        (lambda p: read_bytes(p, 100, "lock"), DatasetError, "lock: not a regular file"),
        (
            lambda p: read_document(p, where="--model"),
            ModelFileError,
            "--model: not a regular file; allowed a saved detector",
        ),
    ]
    for read, error, message in cases:
        with pytest.raises(error, match=message):
            read(files / "fifo")
    with pytest.raises(DatasetError, match=r"^lock: cannot open it \(.*; a link\?\)$"):
        read_bytes(files / "link", 100, "lock")
    with pytest.raises(DatasetError, match=r"^lock: 10 bytes; allowed at most 9$"):
        read_bytes(files / "ten", 9, "lock")
    with pytest.raises(DatasetError, match=r"^lock: missing$"):
        read_bytes(files / "nothing", 9, "lock")
    big = files / "big.json"
    big.write_bytes(b" " * (MAX_MODEL_BYTES + 1))
    with pytest.raises(ModelFileError, match=f"bytes; allowed at most {MAX_MODEL_BYTES}$"):
        read_document(big)
    with pytest.raises(ModelFileError, match=r"^saved detector: cannot open it \(No such file"):
        read_document(files / "nothing")
