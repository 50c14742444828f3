"""User detectors that fail, in ``score``, ``fit`` and ``monitor``: whatever the user's code
raises (in ``__init__``, ``fit``, ``assess``, at import; ``SystemExit`` and ``MemoryError``
too) is one line naming the class and the method and the exception, exit 2, the traceback
only with ``--debug``; a window longer than every run scores no window and is refused.
Run on a real small sweep.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pytest

from brake_sim_ros import cli
from brake_sim_ros.campaigns import load_campaign
from brake_sim_ros.datasets.sweep import sweep
from brake_sim_ros.detection.detector import Assessment, Detector
from brake_sim_ros.ros.harness import domain_id_for, ros_environment
from tests import cli_process

ROOT = Path(__file__).resolve().parents[2]
HERE = "tests.detection.test_detector_fuzz"
CAMPAIGN = """
name = "users"
base = "symmetric"
seed = 4
units = 3
[outputs]
duration_s = 0.3
sample_rate_hz = 2560.0
[[axes]]
defects = ["initial_angle"]
severities = [1.0]
healthy = true
"""


class _Base(Detector):
    name = "hostile"
    channels = ("backing_plate_accel_y",)
    window_s = 0.05

    def assess(
        self, window: Mapping[str, np.ndarray], last_sample_index: int, sample_rate_hz: float
    ) -> Assessment:
        return Assessment(last_sample_index, last_sample_index / sample_rate_hz, 0.5, False)


class InitTypeError(_Base):
    def __init__(self) -> None:
        super().__init__()
        raise TypeError("bad init")


class FitKeyError(_Base):
    def fit(self, windows) -> None:
        raise KeyError("missing")


class FitExitsZero(_Base):
    def fit(self, windows) -> None:
        sys.exit(0)


class FitMemoryError(_Base):
    def fit(self, windows) -> None:
        raise MemoryError


class AssessZeroDivision(_Base):
    def assess(self, window, last_sample_index, sample_rate_hz):
        return 1 / 0


class AssessExitsZero(_Base):
    def assess(self, window, last_sample_index, sample_rate_hz):
        raise SystemExit(0)


class AssessMemoryError(_Base):
    def assess(self, window, last_sample_index, sample_rate_hz):
        raise MemoryError("out")


class AssessReturnsNone(_Base):
    def assess(self, window, last_sample_index, sample_rate_hz):
        return None


class WindowOf1e9Seconds(_Base):
    window_s = 1e9


class WindowLongerThanRuns(_Base):
    window_s = 1.0  # the runs last 0.3 s


class WindowAsText(_Base):
    window_s = "0.1"  # type: ignore[assignment]


class UnknownChannel(_Base):
    channels = ("no_such_channel",)


# class -> (the method named in the line, the exception named; "" when not the user's code)
FAILING = {
    "InitTypeError": ("__init__", "TypeError"),
    "FitKeyError": ("fit", "KeyError"),
    "FitExitsZero": ("fit", "SystemExit"),
    "FitMemoryError": ("fit", "MemoryError"),
    "AssessZeroDivision": ("assess", "ZeroDivisionError"),
    "AssessExitsZero": ("assess", "SystemExit"),
    "AssessMemoryError": ("assess", "MemoryError"),
    "AssessReturnsNone": ("assess", "not an Assessment"),
    "WindowOf1e9Seconds": ("", "no window"),
    "WindowLongerThanRuns": ("", "no window"),
    "WindowAsText": ("window_samples", "TypeError"),
    "UnknownChannel": ("", "no_such_channel"),
}
MODULES = {
    "syntax_error": "def broken(:\n",
    "exits_at_import": "raise SystemExit(0)\n",
    "memory_at_import": "raise MemoryError('import')\n",
    "value_at_import": "raise ValueError('configured wrong')\n",
}


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("users")
    (folder / "c.toml").write_text(CAMPAIGN)
    summary, _ = sweep(load_campaign(folder / "c.toml"), folder / "out", workers=2, quiet=True)
    assert summary.failed == 0
    return folder / "out"


@pytest.fixture(scope="module")
def modules(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("modules")
    for name, text in MODULES.items():
        (folder / f"hostile_{name}.py").write_text(text)
    return folder


def _main(capsys, args: list[str]) -> tuple[int, str, str]:
    try:
        code = cli.main(args)
    except SystemExit as exc:  # must not happen: a user's SystemExit is an error
        code = f"SystemExit({exc.code})"
    out = capsys.readouterr()
    return code, out.out, out.err


def _one_line(code, err: str, *words: str) -> None:
    assert code == 2, (code, err)
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for word in words:
        assert word in err, (word, err)


@pytest.mark.parametrize("name", list(FAILING))
def test_score_and_fit_report_a_user_error_in_one_line(tmp_path, capsys, dataset, name):
    method, exception = FAILING[name]
    spec = f"{HERE}:{name}"
    words = (name, method, exception) if method else (exception,)
    code, _, err = _main(capsys, ["score", str(dataset), "--detector", spec])
    _one_line(code, err, *words)
    out = tmp_path / "m.json"
    code, _, err = _main(capsys, ["fit", str(dataset), "--detector", spec, "--out", str(out)])
    # fit saves, and a user's class has no saved form: refused before it runs
    _one_line(code, err, *((name, "__init__") if name == "InitTypeError" else ("no saved form",)))
    assert not out.exists()


def test_debug_shows_the_users_traceback(capsys, dataset):
    spec = f"{HERE}:AssessZeroDivision"
    code, _, err = _main(capsys, ["score", str(dataset), "--detector", spec, "--debug"])
    assert code == 2 and "Traceback" in err and "1 / 0" in err
    assert err.rstrip().splitlines()[-1].startswith("brake-sim: error: detector ")


@pytest.mark.parametrize("module", list(MODULES))
def test_a_module_that_fails_at_import_is_one_line(capsys, monkeypatch, dataset, modules, module):
    monkeypatch.syspath_prepend(str(modules))
    spec = f"hostile_{module}:Anything"
    code, _, err = _main(capsys, ["score", str(dataset), "--detector", spec])
    _one_line(code, err, f"hostile_{module}")
    sys.modules.pop(f"hostile_{module}", None)


def _monitor(*args: str, path: Path | None = None) -> subprocess.CompletedProcess[str]:
    env = ros_environment(domain_id_for(31))
    paths = [str(ROOT)] + ([str(path)] if path else [])
    env["PYTHONPATH"] = os.pathsep.join([*paths, env.get("PYTHONPATH", "")])
    return cli_process.run(
        [sys.executable, "-m", "brake_sim_ros.cli", "monitor", *args],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )


@pytest.mark.parametrize(
    ("spec", "fit", "words"),
    [
        (f"{HERE}:InitTypeError", False, ("InitTypeError", "__init__", "TypeError")),
        (f"{HERE}:FitKeyError", True, ("FitKeyError", "fit", "KeyError")),
        (f"{HERE}:FitExitsZero", True, ("FitExitsZero", "fit", "SystemExit")),
        (f"{HERE}:WindowOf1e9Seconds", True, ("no window",)),
        (f"{HERE}:WindowOf1e9Seconds", False, ("window_s 1000000000.0", "up to 60 s")),
        ("hostile_syntax_error:X", False, ("hostile_syntax_error", "SyntaxError")),
        ("hostile_exits_at_import:X", False, ("hostile_exits_at_import", "SystemExit")),
        ("hostile_memory_at_import:X", False, ("hostile_memory_at_import", "MemoryError")),
    ],
)
def test_monitor_reports_a_user_error_at_start_in_one_line(dataset, modules, spec, fit, words):
    args = ["--detector", spec] + (["--fit", str(dataset)] if fit else [])
    result = _monitor(*args, path=modules)
    assert result.returncode == 2, result.stderr
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.stderr, result.stderr
    for word in words:
        assert word in result.stderr
