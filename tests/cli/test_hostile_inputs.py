"""Hostile inputs a sweep found (session 32): each refused in one line before any work,
nothing written: replay's options, validate's report directory through a link, a damaged
.npz run for plot."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import numpy as np
import pytest

from brake_sim_ros import cli


def _main(argv: list[str]) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = cli.main(argv)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
    return code, err.getvalue()


@pytest.mark.parametrize(
    ("option", "value"),
    [
        ("--rate", "nan"),
        ("--rate", "inf"),
        ("--rate", "0"),
        ("--start-offset", "-1"),
        ("--start-offset", "nan"),
        ("--wait-for-subscribers", "-1"),
    ],
)
def test_replay_refuses_a_bad_option_in_one_line(tmp_path, option, value):
    code, err = _main(["replay", str(tmp_path / "x.mcap"), option, value])
    assert code == 2 and err.count("\n") == 1, err
    assert err.startswith(f"brake-sim replay: error: {option} ")


def test_replay_names_a_missing_recording_as_an_error(tmp_path):
    code, err = _main(["replay", str(tmp_path / "missing.mcap")])
    assert code == 1 and err.count("\n") == 1 and err.startswith("brake-sim replay: error: ")


def test_validate_never_writes_its_report_through_a_link(tmp_path):
    real = tmp_path / "real"
    real.mkdir()
    (tmp_path / "link").symlink_to(real, target_is_directory=True)
    code, err = _main(["validate", "--out", str(tmp_path / "link")])
    assert code == 2 and err.count("\n") == 1 and "symbolic link" in err
    assert not any(real.iterdir())


def test_plot_refuses_a_truncated_npz_in_one_line(tmp_path):
    whole = tmp_path / "run.npz"
    np.savez(whole, time_s=np.arange(5000) / 2560.0, x=np.zeros(5000))
    cut = tmp_path / "cut.npz"
    cut.write_bytes(whole.read_bytes()[: whole.stat().st_size // 2])
    code, err = _main(["plot", str(cut), "--out", str(tmp_path / "p.png")])
    assert code == 2 and err.count("\n") == 1 and "not a readable .npz file" in err, err
    assert not Path(tmp_path / "p.png").exists()
