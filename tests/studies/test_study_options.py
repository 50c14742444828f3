"""The studies' command lines (``brake-sim bench ...``, ``brake-sim severity``): a bad
option is refused in one line before any work, and a bad output before any run."""

from __future__ import annotations

import os

import pytest

from brake_sim_ros.cli import main


def _refusal(argv: list[str], capsys) -> str:
    """The last stderr line of a refused command line (exit 2, no traceback)."""
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err
    return err.strip().splitlines()[-1]


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["bench", "cycle", "--chunk-s", "nan"], "--chunk-s nan: allowed 0.001 to 1 s"),
        (["bench", "cycle", "--chunk-s", "0"], "--chunk-s 0.0: allowed 0.001 to 1 s"),
        (["bench", "cycle", "--repeats", "0"], "--repeats 0: allowed 1 to 20"),
        (["bench", "cycle", "--repeats", "1000000000"], "--repeats 1000000000: allowed 1 to 20"),
        (["bench", "units", "--units", "abc"], "argument --units: invalid int value: 'abc'"),
        (["bench", "units", "--seed", "-1"], "--seed -1: allowed 0 to 2^63 - 1"),
        (["bench", "fleet", "--units", "4"], "--units 4: allowed 5 to 20"),
        (["bench", "fleet", "--workers", "0"], "--workers 0: allowed 1 to 1024"),
        (["bench", "fleet", "--draws", "abc"], "argument --draws: invalid int value: 'abc'"),
        (["severity", "--duration", "nan"], "--duration nan: allowed 0.4 to 60 s"),
        (["severity", "--out", ""], "--out '': allowed a directory path"),
    ],
)
def test_a_bad_option_is_refused_in_one_line(argv, expected, capsys):
    line = _refusal(argv, capsys)
    assert expected in line
    assert line.startswith("brake-sim")


def test_severity_refuses_a_link_among_its_outputs_before_any_run(tmp_path, capsys):
    """A figure's name in ``--out`` that is a link is refused before the first run (the
    sweep takes tens of seconds), and nothing is written there."""
    out = tmp_path / "sev"
    out.mkdir()
    target = tmp_path / "elsewhere.png"
    target.write_bytes(b"x")
    (out / "left_friction_change.png").symlink_to(target)
    line = _refusal(["severity", "--out", str(out)], capsys)
    assert "left_friction_change.png is a symbolic link" in line
    assert sorted(os.listdir(out)) == ["left_friction_change.png"]
    assert target.read_bytes() == b"x"


@pytest.mark.parametrize("kind", ["dangling link", "file", "unmakeable"])
def test_severity_refuses_an_out_that_is_no_directory_in_one_line(kind, tmp_path, capsys):
    out = tmp_path / "sev"
    if kind == "dangling link":
        out.symlink_to(tmp_path / "nowhere")
        expected = "is a symbolic link"
    elif kind == "file":
        out.write_text("not a directory")
        expected = "exists and is not a directory"
    else:
        blocker = tmp_path / "blocker"
        blocker.write_text("a file where a directory would go")
        out = blocker / "sev"
        expected = f"{blocker} is not a directory"
    line = _refusal(["severity", "--out", str(out)], capsys)
    assert expected in line


def test_bench_cycle_refuses_a_chunk_beyond_the_streams_bound(tmp_path, capsys):
    """1 s chunks at 102.4 kHz are 102,400 samples a block: beyond the stream's 65,536."""
    from brake_sim_ros.scenarios import load_scenario

    text = load_scenario("urban").text.replace(
        "sample_rate_hz = 25600.0", "sample_rate_hz = 102400.0"
    )
    assert "sample_rate_hz = 102400.0" in text
    path = tmp_path / "urban_fast.toml"
    path.write_text(text)
    line = _refusal(["bench", "cycle", "--scenario", str(path), "--chunk-s", "1"], capsys)
    assert "102400 samples at 102400 Hz; allowed at most 65536 samples a chunk" in line
