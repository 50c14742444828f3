"""``brake-sim simulate`` with hostile command lines: every argument and every output is
checked before anything runs, a refusal is one line on stderr with a non-zero exit code,
and no output is left behind, partly written or otherwise.

The named cases run in-process (``cli.main``) with the simulation replaced by a tripwire,
so a case refused only after simulating fails; a hypothesis test draws whole argument
lists (durations, rates and steps that are nan, inf, negative, tiny or huge; output names,
directories and suffixes; flags) and runs them for real at durations of at most 20 ms; a
few cases run as real processes to prove that no traceback escapes ``main``.
"""

from __future__ import annotations

import contextlib
import errno
import io
import json
import os
import re
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from brake_sim_ros import cli
from brake_sim_ros.cli.simulate import MAX_SIMULATE_DURATION_S
from brake_sim_ros.stream import run as run_module
from tests import cli_process

SMALL = 'name = "small"\nduration_s = 0.01\n'
_PROGRESS = re.compile(r"^simulating .*%$")


@pytest.fixture(scope="module", autouse=True)
def _compiled():
    from brake_sim_ros.solvers.warmup import PARTS, ensure_compiled

    # every part, those compiled at first use too: a one-time notice is not part of any
    # case's stderr
    ensure_compiled(parts=tuple(PARTS))


def _main(argv: list[str]) -> tuple[int, str, str]:
    """``brake-sim ARGV`` in this process: exit code, stdout, stderr."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = cli.main(argv)
        except SystemExit as exc:  # argparse
            code = exc.code if isinstance(exc.code, int) else 1
    return code, out.getvalue(), err.getvalue()


def _error_lines(stderr: str) -> list[str]:
    """stderr's lines without the progress report."""
    lines = [line for line in re.split(r"[\r\n]+", stderr) if line.strip()]
    return [line for line in lines if not _PROGRESS.match(line)]


def _assert_one_line_refusal(code: int, stderr: str) -> str:
    assert code != 0 and "Traceback" not in stderr, stderr
    lines = _error_lines(stderr)
    assert len(lines) == 1, stderr
    assert re.match(r"^brake-sim( simulate)?: error: ", lines[0]), lines[0]
    return lines[0]


def _tree(directory: Path) -> dict[str, bytes | str]:
    """Every entry under ``directory`` with its content (files) or kind."""
    tree: dict[str, bytes | str] = {}
    for path in sorted(directory.rglob("*")):
        key = str(path.relative_to(directory))
        if path.is_symlink():
            tree[key] = f"link to {os.readlink(path)}"
        elif path.is_file():
            tree[key] = path.read_bytes()
        else:
            tree[key] = "directory" if path.is_dir() else "special"
    return tree


@pytest.fixture
def no_simulation(monkeypatch):
    """Fails a case that reaches the simulation."""

    def tripwire(*args, **kwargs):
        raise AssertionError("simulated before refusing")

    monkeypatch.setattr(run_module, "run_scenario", tripwire)


# --- named cases -----------------------------------------------------------------------------
SYMMETRIC = ["simulate", "symmetric", "--quiet"]
REFUSED_ARGUMENTS = {
    "duration -1": (["--duration", "-1"], "--duration -1.0 s: allowed a time > 0 s"),
    "duration 0": (["--duration", "0"], "--duration 0.0 s: allowed a time > 0 s"),
    "duration nan": (["--duration", "nan"], "--duration nan s: allowed"),
    "duration inf": (["--duration", "inf"], "--duration inf s: allowed"),
    "duration -inf": (["--duration=-inf"], "--duration -inf s: allowed"),
    "duration 1e9": (["--duration", "1e9"], "at most 3600 s"),
    "duration 3601": (["--duration", "3601"], "at most 3600 s"),
    "duration 1e999": (["--duration", "1e999"], "--duration inf s"),
    "duration below a sample": (["--duration", "1e-9"], "shorter than one sample"),
    "duration over the memory bound": (["--duration", "600"], "in memory: allowed at most 2.1 GB"),
    "rate too high for the memory": (
        ["--duration", "100", "--sample-rate", "1e6"],
        "100000000 samples",
    ),
    "duration not a number": (["--duration", "abc"], "invalid float value: 'abc'"),
    "duration missing": (["--duration"], "expected one argument"),
    "sample rate 0": (["--sample-rate", "0"], "--sample-rate: sample rate 0.0 Hz: allowed 1"),
    "sample rate -1": (["--sample-rate", "-1"], "--sample-rate: sample rate -1.0 Hz"),
    "sample rate nan": (["--sample-rate", "nan"], "--sample-rate: sample rate nan Hz"),
    "sample rate inf": (["--sample-rate", "inf"], "--sample-rate: sample rate inf Hz"),
    "sample rate 1e-300": (["--sample-rate", "1e-300"], "allowed 1 to 1e+06 Hz"),
    "sample rate 1e7": (["--sample-rate", "1e7"], "allowed 1 to 1e+06 Hz"),
    "max step 0": (["--max-step", "0"], "--max-step: largest physics step 0.0 s: allowed a step"),
    "max step -1": (["--max-step", "-1"], "--max-step: largest physics step -1.0 s"),
    "max step nan": (["--max-step", "nan"], "--max-step: largest physics step nan s"),
    "max step inf": (["--max-step", "inf"], "--max-step: largest physics step inf s"),
    "max step 1e-300": (["--max-step", "1e-300"], "allowed a step from 1e-08 to 0.01 s"),
    "max step 1e-9": (["--max-step", "1e-9"], "allowed a step from 1e-08 to 0.01 s"),
    "max step 1": (["--max-step", "1"], "allowed a step from 1e-08 to 0.01 s"),
    "dt 1e-3": (["--dt", "1e-3"], "--dt is gone"),
    "dt nan": (["--dt", "nan"], "--dt is gone"),
    "dt text": (["--dt", "fast"], "--dt is gone"),
    "dt alone": (["--dt"], "--dt is gone"),
    "dt before a flag": (["--dt", "--overwrite"], "--dt is gone"),
    "preset unknown": (["--preset", "turbo"], "invalid choice: 'turbo'"),
    "method unknown": (["--method", "euler"], "invalid choice: 'euler'"),
    "unknown option": (["--bogus"], "unrecognized arguments: --bogus"),
    "control characters echoed escaped": (["\x1b[2J"], "unrecognized arguments: \\x1b[2J"),
    "reference and mcap": (["--method", "reference", "--mcap", "x.mcap"], "drop --method"),
    "reference and rerun": (["--method", "reference", "--rerun", "save", "x.rrd"], "drop --method"),
    "rerun save not rrd": (["--rerun", "save", "x.txt"], "ending in .rrd"),
}


@pytest.mark.parametrize("case", sorted(REFUSED_ARGUMENTS))
def test_bad_arguments_are_one_line_before_simulating(case, tmp_path, monkeypatch, no_simulation):
    extra, fragment = REFUSED_ARGUMENTS[case]
    monkeypatch.chdir(tmp_path)
    code, _out, err = _main([*SYMMETRIC, *extra])
    line = _assert_one_line_refusal(code, err)
    assert fragment in line, line
    assert _tree(tmp_path) == {}


def _scene(tmp_path: Path) -> dict[str, str]:
    """Files and directories the output cases point at; returns names to paths."""
    (tmp_path / "s.toml").write_text(SMALL)
    (tmp_path / "s.npz").write_text(SMALL)  # a scenario file with an output's suffix
    (tmp_path / "exists.npz").write_bytes(b"precious")
    (tmp_path / "dir").mkdir()
    (tmp_path / "dirlink").symlink_to(tmp_path / "dir")
    (tmp_path / "link.npz").symlink_to(tmp_path / "exists.npz")
    (tmp_path / "dangling.npz").symlink_to(tmp_path / "nowhere.npz")
    os.link(tmp_path / "s.toml", tmp_path / "hard.mcap")
    os.mkfifo(tmp_path / "fifo.npz")
    return {"tmp": str(tmp_path)}


REFUSED_OUTPUTS = {
    "missing directory": (["--out", "{tmp}/missing/run.npz"], "does not exist"),
    "a directory": (["--out", "{tmp}/dir"], "exists and is not a regular file"),
    "a directory with a slash": (["--out", "{tmp}/dir/"], "not a directory"),
    "a directory named .npz": (["--out", "{tmp}/dir.npz/"], "not a directory"),
    "/dev/full": (["--out", "/dev/full"], "exists and is not a regular file"),
    "/dev/null": (["--out", "/dev/null"], "exists and is not a regular file"),
    "a FIFO": (["--out", "{tmp}/fifo.npz"], "exists and is not a regular file"),
    "/proc takes no file": (["--out", "/proc/brake-sim-test.npz"], "--out /proc/brake"),
    "parquet-like": (["--out", "{tmp}/x.pq"], "allowed a path ending in .npz"),
    "upper-case suffix": (["--out", "{tmp}/x.NPZ"], "allowed a path ending in .npz"),
    "no suffix": (["--out", "{tmp}/x"], "allowed a path ending in .npz"),
    "mcap not .mcap": (["--mcap", "{tmp}/x.npz"], "--mcap {tmp}/x.npz: allowed a path ending"),
    "mcap is the scenario": (["{tmp}/s.toml", "--mcap", "{tmp}/s.toml"], "is the input"),
    "out is the scenario": (["{tmp}/s.npz", "--out", "{tmp}/s.npz"], "is the input"),
    "out is the scenario, overwrite": (
        ["{tmp}/s.npz", "--out", "{tmp}/s.npz", "--overwrite"],
        "is the input",
    ),
    "hard link to the scenario": (["{tmp}/s.toml", "--mcap", "{tmp}/hard.mcap"], "is the input"),
    "a link": (["--out", "{tmp}/link.npz"], "is a symbolic link"),
    "a link, overwrite": (["--out", "{tmp}/link.npz", "--overwrite"], "is a symbolic link"),
    "a dangling link": (["--out", "{tmp}/dangling.npz"], "is a symbolic link"),
    "exists": (["--out", "{tmp}/exists.npz"], "exists: pass --overwrite to replace it"),
    "out and mcap the same": (
        ["--out", "{tmp}/a.npz", "--mcap", "{tmp}/a.npz"],
        "name the same file",
    ),
    "two rerun saves, one file": (
        ["--rerun", "save", "{tmp}/a.rrd", "--rerun", "save", "{tmp}/dir/../a.rrd"],
        "name the same file",
    ),
    "the same file through a linked directory": (
        ["--rerun", "save", "{tmp}/dir/a.rrd", "--rerun", "save", "{tmp}/dirlink/a.rrd"],
        "name the same file",
    ),
    "scenario is a FIFO": (["{tmp}/fifo.npz"], "it is a FIFO"),
    "scenario is /dev/zero": (["/dev/zero"], "it is a character device"),
    "scenario is a directory": (["{tmp}/dir"], "it is a directory"),
    "scenario is missing": (["{tmp}/missing.toml"], "no such file"),
}


@pytest.mark.parametrize("case", sorted(REFUSED_OUTPUTS))
def test_bad_outputs_are_refused_before_simulating(case, tmp_path, no_simulation):
    names = _scene(tmp_path)
    extra, fragment = REFUSED_OUTPUTS[case]
    extra = [a.format(**names) for a in extra]
    scenario = [extra.pop(0)] if not extra[0].startswith("--") else ["symmetric"]
    before = _tree(tmp_path)
    code, _out, err = _main(["simulate", *scenario, "--quiet", "--duration", "0.01", *extra])
    line = _assert_one_line_refusal(code, err)
    assert fragment.format(**names) in line, line
    assert _tree(tmp_path) == before


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into a directory of mode 555")
def test_a_read_only_directory_is_refused_before_simulating(tmp_path, no_simulation):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    code, _out, err = _main([*SYMMETRIC, "--duration", "0.01", "--out", str(ro / "x.npz")])
    assert "is not writable" in _assert_one_line_refusal(code, err)
    assert list(ro.iterdir()) == []


# --- what is written, and how ----------------------------------------------------------------
def test_overwrite_replaces_an_existing_output_whole(tmp_path):
    out = tmp_path / "run.npz"
    out.write_bytes(b"precious")
    argv = [*SYMMETRIC, "--duration", "0.01", "--out", str(out)]
    code, _out, err = _main(argv)
    assert "exists: pass --overwrite" in _assert_one_line_refusal(code, err)
    assert out.read_bytes() == b"precious"
    code, stdout, err = _main([*argv, "--overwrite"])
    assert code == 0, err
    assert np.load(out)["time_s"].size == 256 and f"time history: {out}" in stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.npz"]


def test_a_csv_history_and_its_metadata(tmp_path):
    out = tmp_path / "run.csv"
    code, _out, err = _main([*SYMMETRIC, "--duration", "0.01", "--out", str(out)])
    assert code == 0, err
    assert np.genfromtxt(out, delimiter=",", names=True)["time_s"].size == 256
    npz = tmp_path / "run.npz"
    scenario = tmp_path / "s.toml"
    scenario.write_text(SMALL)
    assert _main(["simulate", str(scenario), "--quiet", "--out", str(npz)])[0] == 0
    meta = json.loads(str(np.load(npz)["metadata"]))
    assert meta["scenario"] == "small" and meta["scenario_toml"] == SMALL


@pytest.mark.parametrize(
    "fault", [OSError(errno.ENOSPC, "No space left on device"), KeyboardInterrupt]
)
def test_a_failure_while_writing_leaves_nothing(tmp_path, monkeypatch, fault):
    """The writer dies half way (a full disk, Ctrl-C): one line, no file, no temporary."""
    out = tmp_path / "run.npz"

    def half_then_fail(file, *args, **kwargs):
        file.write(b"PK\x03\x04 half an archive")
        raise fault

    monkeypatch.setattr(np, "savez_compressed", half_then_fail)
    code, _out, err = _main([*SYMMETRIC, "--duration", "0.01", "--out", str(out)])
    if fault is KeyboardInterrupt:
        assert code == 130 and _error_lines(err) == ["brake-sim: interrupted"], err
    else:
        line = _assert_one_line_refusal(code, err)
        assert "--out" in line and "No space left on device" in line, line
    assert list(tmp_path.iterdir()) == []


@pytest.mark.ros  # the recorder needs the ROS wheels' interface definitions
@pytest.mark.filterwarnings("ignore:module 'sre_(parse|constants)' is deprecated")
def test_mcap_and_rerun_outputs_are_written_whole(tmp_path, monkeypatch):
    mcap, rrd, npz = tmp_path / "run.mcap", tmp_path / "run.rrd", tmp_path / "run.npz"
    argv = [*SYMMETRIC, "--duration", "0.02", "--out", str(npz), "--mcap", str(mcap)]
    argv += ["--rerun", "save", str(rrd)]
    code, stdout, err = _main(argv)
    assert code == 0, err
    assert f"recording: {mcap} (" in stdout and "-> save " in stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.mcap", "run.npz", "run.rrd"]
    assert min(p.stat().st_size for p in (mcap, rrd, npz)) > 1000
    # a failure while the stream is written: the history is whole, the stream files absent
    from brake_sim_ros.recording import record

    def interrupted(scenario, path, **kwargs):
        Path(path).write_bytes(b"\x89MCAP0\r\n half a recording")
        raise KeyboardInterrupt

    monkeypatch.setattr(record, "record_offline", interrupted)
    code, _out, err = _main([*argv, "--overwrite"])
    assert code == 130 and _error_lines(err) == ["brake-sim: interrupted"], err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.mcap", "run.npz", "run.rrd"]
    assert mcap.read_bytes()[:8] == b"\x89MCAP0\r\n" and b"half" not in mcap.read_bytes()


# --- random command lines --------------------------------------------------------------------
_floats_text = st.one_of(
    st.sampled_from(["nan", "-nan", "inf", "-inf", "1e999", "0", "-0", "1e-300", "abc", ""]),
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
)


def _runs_long(text: str) -> bool:
    """A finite duration a test must not run (20 ms to the memory bound)."""
    try:
        value = float(text)
    except ValueError:
        return False
    return 0.02 < value <= MAX_SIMULATE_DURATION_S


def _path(directories: list[str], names: list[str], suffixes: list[str]) -> st.SearchStrategy:
    return st.tuples(*(st.sampled_from(x) for x in (directories, names, suffixes))).map("".join)


_GOOD_DIRS, _GOOD_NAMES = ["", "dir/", "dir/../", "dirlink/"], ["run", "a b", "ü", ".hidden"]
VALID = {
    "--duration": st.one_of(
        st.sampled_from(["0.01", "0.02", "1e-3"]),
        st.floats(min_value=1e-4, max_value=0.02).map(repr),
    ),
    "--sample-rate": st.sampled_from(["1000", "25600", "1e5"]),
    "--max-step": st.sampled_from(["1e-6", "6e-5", "0.01"]),
    "--preset": st.sampled_from(["fast", "balanced", "accurate"]),
    "--method": st.sampled_from(["rk4", "semi-implicit-euler", "rk4-located"]),
    "--out": _path(_GOOD_DIRS, _GOOD_NAMES, [".npz", ".csv"]),
    "--rerun": _path(_GOOD_DIRS, _GOOD_NAMES, [".rrd"]),
}
HOSTILE = {
    "scenario": st.sampled_from(["nope", "dir", "s.npz", "fifo.npz", "/dev/zero", ""]),
    "--duration": _floats_text.filter(lambda t: not _runs_long(t)),
    "--sample-rate": st.sampled_from(["nan", "inf", "0", "-5", "1e-300", "1e7", "x"]),
    "--max-step": st.sampled_from(["nan", "0", "-1", "1e-300", "1e-9", "1", "inf"]),
    "--preset": st.sampled_from(["turbo", ""]),
    "--method": st.sampled_from(["euler", "reference"]),  # reference: with --rerun, refused
    "--out": st.one_of(
        _path(["missing/", "/proc/", "/sys/", *_GOOD_DIRS], _GOOD_NAMES, [".npz"]),
        _path(_GOOD_DIRS, ["exists", "link", "dangling", "fifo", "s"], [".npz", ".csv"]),
        _path(_GOOD_DIRS, _GOOD_NAMES, [".mcap", ".pq", "", ".NPZ", ".npz/", ".toml"]),
        st.sampled_from(["/dev/full", "/dev/null", ".", "dir", "run.rrd"]),
    ),
    "--rerun": st.one_of(
        _path(["missing/", "/proc/"], _GOOD_NAMES, [".rrd"]),
        _path(_GOOD_DIRS, _GOOD_NAMES, [".npz", ""]),
        st.sampled_from(["run.npz", "exists.npz", "link.npz"]),
    ),
    "--dt": st.sampled_from(["1e-3", "nan", "-1", ""]),
}


@st.composite
def _command_lines(draw) -> list[str]:
    """A valid command line with up to three of its parts made hostile."""
    hostile = draw(st.lists(st.sampled_from(sorted(HOSTILE)), max_size=3, unique=True))
    scenario = draw(st.sampled_from(["symmetric", "case5_left_tilted", "s.toml"]))
    argv = ["simulate", draw(HOSTILE["scenario"]) if "scenario" in hostile else scenario]
    for option in sorted((set(VALID) | set(hostile)) - {"scenario"}):
        value = None
        if option in hostile:
            value = draw(HOSTILE[option])
        elif option == "--duration" and argv[1] != "s.toml":
            value = draw(VALID[option])  # the built-in scenarios last 7.5 s
        elif option in VALID and draw(st.booleans()):
            value = draw(VALID[option])
        if value is not None:
            argv += ["--rerun", "save", value] if option == "--rerun" else [option, value]
    for flag in ("--quiet", "--overwrite"):
        if draw(st.booleans()):
            argv.append(flag)
    return argv


@pytest.mark.slow
@settings(
    max_examples=int(os.environ.get("FUZZ_EXAMPLES", "60")),
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(argv=_command_lines())
def test_random_command_lines(tmp_path_factory, argv):
    """Exit 0 with every output written whole, or non-zero with one line and the directory
    as it was (no output, no temporary file, an existing file untouched)."""
    tmp = tmp_path_factory.mktemp("cli")
    _scene(tmp)
    before = _tree(tmp)
    cwd = os.getcwd()
    os.chdir(tmp)
    try:
        code, _out, err = _main(argv)
    finally:
        os.chdir(cwd)
    after = _tree(tmp)
    event("ran" if code == 0 else "refused")  # pytest --hypothesis-show-statistics
    assert not any(".partial" in name for name in after), after.keys()
    if code != 0:
        _assert_one_line_refusal(code, err)
        assert after == before, argv
        return
    assert "Traceback" not in err and not _error_lines(err), err
    for option in ("--out", "--rerun"):
        if option in argv:
            written = Path(tmp, argv[argv.index(option) + (2 if option == "--rerun" else 1)])
            assert written.is_file() and not written.is_symlink() and written.stat().st_size
            assert str(written.relative_to(tmp)) not in before or "--overwrite" in argv


# --- real processes ---------------------------------------------------------------------------
@pytest.mark.slow
@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["simulate", "symmetric", "--duration", "nan"], "--duration nan s"),
        (["simulate", "symmetric", "--duration", "abc"], "invalid float value"),
        (["simulate", "symmetric", "--max-step", "1e-300"], "1e-08"),
        (["simulate", "symmetric", "--out", "/dev/full"], "not a regular file"),
        (["simulate", "{tmp}/fifo.npz"], "it is a FIFO"),
        (["simulate", "{tmp}/deep.toml"], "nested too deeply"),
        (["simulate", "{tmp}/s.toml", "--mcap", "{tmp}/s.toml"], "is the input"),
    ],
)
def test_real_processes_print_one_line_and_no_traceback(tmp_path, argv, fragment):
    names = _scene(tmp_path)
    (tmp_path / "deep.toml").write_text("a = " + "[" * 100_000)
    before = _tree(tmp_path)
    r = cli_process.run(
        [sys.executable, "-m", "brake_sim_ros.cli", *(a.format(**names) for a in argv)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    line = _assert_one_line_refusal(r.returncode, r.stderr)
    assert r.returncode == 2 and fragment in line, r.stderr
    assert _tree(tmp_path) == before
