"""Output rules of ``recover FIXED`` and ``view --save FILE.rrd``.

No overwrite without ``--overwrite``; never through a symbolic link; never over an input,
whatever path names it; all refused before anything is written; the file appears whole or
not at all (a failure or Ctrl-C while writing leaves nothing).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

from brake_sim_ros.cli import main as cli_main
from brake_sim_ros.recording.output import (
    OutputError,
    atomic_output,
    check_output,
    check_output_directory,
    output_directory,
)
from brake_sim_ros.recording.reader import open_recording
from brake_sim_ros.recording.record import record_offline
from brake_sim_ros.recording.recover import RecoverError, recover
from brake_sim_ros.recording.writer import RecordingOptions
from brake_sim_ros.scenarios import load_scenario

pytestmark = [
    pytest.mark.ros,  # the recorder needs the ROS wheels' interface definitions
    pytest.mark.filterwarnings("ignore:module 'sre_(parse|constants)' is deprecated"),
]


@pytest.fixture(scope="module")
def bag(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("bag") / "run.mcap"
    options = RecordingOptions(flush_interval_s=0.1, durable=False)
    record_offline(load_scenario("symmetric"), path, duration_s=0.2, options=options)
    return path


def _one_line(capfd) -> str:
    err = capfd.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    return err.strip()


def _files(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.iterdir())


def test_existing_output_needs_overwrite(bag: Path, tmp_path: Path, capfd):
    fixed = tmp_path / "fixed.mcap"
    fixed.write_bytes(b"precious")
    assert cli_main(["recover", str(bag), str(fixed)]) == 2
    assert "exists: pass --overwrite to replace it" in _one_line(capfd)
    assert fixed.read_bytes() == b"precious"
    assert cli_main(["recover", str(bag), str(fixed), "--overwrite"]) == 0
    with open_recording(fixed) as recording:
        assert recording.message_count > 0
    rrd = tmp_path / "view.rrd"
    rrd.write_bytes(b"precious")
    assert cli_main(["view", str(bag), "--save", str(rrd)]) == 2
    assert "--save" in _one_line(capfd) and rrd.read_bytes() == b"precious"
    assert cli_main(["view", str(bag), "--save", str(rrd), "--overwrite"]) == 0
    assert rrd.stat().st_size > 1000
    assert _files(tmp_path) == ["fixed.mcap", "view.rrd"]


@pytest.mark.parametrize("dangling", [False, True])
def test_never_through_a_symbolic_link(bag: Path, tmp_path: Path, capfd, dangling: bool):
    target = tmp_path / "target.mcap"
    if not dangling:
        target.write_bytes(b"precious")
    link = tmp_path / "link.mcap"
    link.symlink_to(target)
    for argv in (
        ["recover", str(bag), str(link), "--overwrite"],
        ["view", str(bag), "--save", str(tmp_path / "v.rrd")],
    ):
        if argv[0] == "view":
            (tmp_path / "v.rrd").symlink_to(target)
        assert cli_main(argv) == 2
        assert "is a symbolic link" in _one_line(capfd)
    assert target.exists() != dangling
    if not dangling:
        assert target.read_bytes() == b"precious"


def test_never_over_an_input_whatever_the_path(bag: Path, tmp_path: Path, capfd):
    copy = tmp_path / "in.mcap"
    copy.write_bytes(bag.read_bytes())
    hard = tmp_path / "hard.mcap"
    os.link(copy, hard)
    (tmp_path / "sub").mkdir()
    for out in (copy, hard, tmp_path / "sub" / ".." / "in.mcap"):
        assert cli_main(["recover", str(copy), str(out), "--overwrite"]) == 2
        assert "is the input" in _one_line(capfd)
    link = tmp_path / "via_link.mcap"
    link.symlink_to(copy)  # the input named through a link, the output its target
    assert cli_main(["recover", str(link), str(copy), "--overwrite"]) == 2
    assert "is the input" in _one_line(capfd)
    assert copy.read_bytes() == bag.read_bytes()


def test_bad_output_places_are_refused_first(bag: Path, tmp_path: Path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(OutputError, match="is not a directory"):
        check_output(blocker / "out.mcap")
    with pytest.raises(OutputError, match=r"allowed a path ending in \.mcap"):
        recover(bag, tmp_path / "fixed.txt")
    with pytest.raises(OutputError, match="exists and is not a regular file"):
        check_output(tmp_path, overwrite=True, option="FIXED")
    with pytest.raises(OutputError, match="allowed a file path"):
        check_output(str(tmp_path) + os.sep)
    if os.geteuid() != 0:  # root may write anywhere
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o500)
        with pytest.raises(OutputError, match="is not writable"):
            recover(bag, locked / "fixed.mcap")
    assert _files(tmp_path) == ["file"]


def test_an_output_directory_is_checked_before_the_work_and_made_only_when_asked(
    tmp_path: Path,
):
    """``check_output_directory`` refuses what ``output_directory`` would refuse, in one
    line and making nothing; a missing directory under a writable one passes unmade."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    real = tmp_path / "real"
    real.mkdir()
    link = tmp_path / "link"
    link.symlink_to(real, target_is_directory=True)
    refused = {
        "": "allowed a directory path",
        str(link): "is a symbolic link",
        str(blocker): "exists and is not a directory",
        str(blocker / "sub"): "is not a directory",
    }
    if os.geteuid() != 0:  # root may write anywhere
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o500)
        refused[str(locked / "a" / "b")] = "is not writable"
        refused[str(locked)] = "is not writable"
    for path, words in refused.items():
        for check in (check_output_directory, output_directory):
            with pytest.raises(OutputError, match=words) as info:
                check(path, "--report")
            assert "\n" not in str(info.value) and str(info.value).startswith("--report")
    fresh = tmp_path / "new" / "deeper"
    assert check_output_directory(fresh) == fresh and not fresh.parent.exists()
    assert output_directory(fresh).is_dir()
    made = {p.name for p in tmp_path.iterdir()} - {"file", "link", "real", "locked"}
    assert made == {"new"} and not any(real.iterdir())
    if os.geteuid() != 0:
        assert not any((tmp_path / "locked").iterdir())


def test_a_failure_while_writing_leaves_nothing(bag: Path, tmp_path: Path, monkeypatch):
    from mcap.writer import Writer

    real_finish = Writer.finish

    def disk_full(self):
        raise OSError(28, "No space left on device")

    out_dir = tmp_path / "new" / "dirs"
    monkeypatch.setattr(Writer, "finish", disk_full)
    with pytest.raises(RecoverError, match="No space left on device; nothing written"):
        recover(bag, out_dir / "fixed.mcap")
    assert _files(tmp_path) == []  # the directories made for it are gone too

    def interrupted(self):
        raise KeyboardInterrupt

    monkeypatch.setattr(Writer, "finish", interrupted)
    with pytest.raises(KeyboardInterrupt):
        recover(bag, tmp_path / "fixed.mcap")
    assert _files(tmp_path) == []
    monkeypatch.setattr(Writer, "finish", real_finish)
    recover(bag, tmp_path / "fixed.mcap")
    assert _files(tmp_path) == ["fixed.mcap"]


def test_an_output_that_appears_meanwhile_is_not_replaced(tmp_path: Path):
    out = tmp_path / "out.mcap"
    with (
        pytest.raises(OutputError, match="exists: pass --overwrite"),
        atomic_output(out, suffix=".mcap") as partial,
    ):
        partial.write_bytes(b"new")
        out.write_bytes(b"someone else's")
    assert out.read_bytes() == b"someone else's" and _files(tmp_path) == ["out.mcap"]
    with atomic_output(out, suffix=".mcap", overwrite=True) as partial:
        assert partial.parent == tmp_path and partial.name.startswith(".out.mcap.")
        partial.write_bytes(b"new")
        assert out.read_bytes() == b"someone else's"  # nothing visible before the end
    assert out.read_bytes() == b"new" and _files(tmp_path) == ["out.mcap"]
    assert oct(out.stat().st_mode & 0o777) == oct(0o666 & ~_umask())


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _made_meanwhile(monkeypatch):
    """Another process makes the missing parent directories after the writer found them
    missing and before it makes them (the race of a sweep's two workers writing their
    first runs into one new folder)."""
    from brake_sim_ros.recording import output

    real = output._missing_parents

    def missing_then_made(directory):
        missing = real(directory)
        if sys._getframe(1).f_code.co_name == "atomic_output":  # the writer's own look
            for d in missing:
                d.mkdir()
        return missing

    monkeypatch.setattr(output, "_missing_parents", missing_then_made)


def test_a_parent_directory_made_meanwhile_by_another_writer_is_used_not_removed(
    tmp_path, monkeypatch
):
    _made_meanwhile(monkeypatch)
    target = tmp_path / "samples" / "run=1" / "part-0.parquet"
    with atomic_output(target, make_parents=True) as tmp:
        tmp.write_bytes(b"x")
    assert target.read_bytes() == b"x"
    # a failing write removes only the directories it made itself, not the other's
    other = tmp_path / "other" / "run=2" / "part-0.parquet"
    with pytest.raises(RuntimeError), atomic_output(other, make_parents=True):
        raise RuntimeError("the writer failed")
    assert other.parent.is_dir()
