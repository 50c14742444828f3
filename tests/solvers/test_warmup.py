"""The kernels' compile: the default paths' parts ahead of use, the others at first use with
the same progress lines, each part once per source version (a marker in the kernel cache),
one process at a time."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numba
import pytest

from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.solvers import kernel_parts as warmup  # the parts' machinery
from brake_sim_ros.solvers import warmup as _registers_the_default_parts  # noqa: F401
from brake_sim_ros.solvers.contact_regime import run_contact_regime
from brake_sim_ros.solvers.reference import run_reference

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """An empty kernel cache for the markers (numba's compiled functions stay where they are:
    each function's cache location is fixed when it is decorated)."""
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "v1"))
    return tmp_path


def _fake_parts(monkeypatch, done: list[str], seconds: float = 0.0) -> None:
    """Every part recorded in ``done`` (after ``seconds``) instead of compiled."""

    def part(key: str):
        return lambda: (time.sleep(seconds), done.append(key))

    fakes = {key: (name, part(key)) for key, (name, _) in warmup.PARTS.items()}
    monkeypatch.setattr(warmup, "PARTS", fakes)


def test_compilation_is_announced_once_per_version(cache, monkeypatch):
    calls = []
    monkeypatch.setattr(warmup, "compile_kernels", lambda _say, parts: calls.append(parts) or 1.5)
    said: list[str] = []
    assert not warmup.is_compiled()
    warmup.ensure_compiled(said.append)
    assert calls == [list(warmup.DEFAULT_PARTS)] and len(said) == 2
    assert "compiling the physics kernels (fixed-step kernel, default sensors;" in said[0]
    assert "1.5 s" in said[1]
    assert warmup.is_compiled()
    assert not warmup.is_compiled(["reference"])  # the set-up's parts only
    warmup.ensure_compiled(said.append)  # cached: silent, nothing compiled
    assert len(calls) == 1 and len(said) == 2
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(cache / "v2"))  # another version
    assert not warmup.is_compiled()


def test_only_a_missing_part_compiles(cache, monkeypatch):
    done: list[str] = []
    _fake_parts(monkeypatch, done)
    monkeypatch.setattr(warmup.os, "cpu_count", lambda: 1)
    warmup.ensure_compiled(lambda _line: None, ["stepping"])
    warmup.ensure_compiled(lambda _line: None, ["stepping", "reference"])
    assert done == ["stepping", "reference"]


def _compile(monkeypatch, tmp_path, cores: int, child_fails: bool = False):
    """compile_kernels of the default parts on ``cores`` cores, the parts recorded, not
    compiled, and a child that leaves a file with its arguments (or fails); returns the parts
    run here and the child's arguments (None: no child)."""
    done: list[str] = []
    _fake_parts(monkeypatch, done)
    monkeypatch.setattr(warmup.os, "cpu_count", lambda: cores)
    started = tmp_path / "child_started"
    child = f"import sys; open({str(started)!r}, 'w').write(' '.join(sys.argv[1:]))"
    monkeypatch.setattr(warmup, "_CHILD", child + ("; raise SystemExit(3)" if child_fails else ""))
    warmup.compile_kernels()
    return done, started.read_text() if started.exists() else None


def test_the_other_parts_compile_in_a_child_process_beside_the_first(monkeypatch, tmp_path):
    assert _compile(monkeypatch, tmp_path, cores=2) == (["stepping"], "sensors")


def test_a_failed_child_leaves_its_parts_to_this_process(monkeypatch, tmp_path):
    done = _compile(monkeypatch, tmp_path, cores=2, child_fails=True)
    assert done == (["stepping", "sensors"], "sensors")


def test_one_core_compiles_every_part_here(monkeypatch, tmp_path):
    assert _compile(monkeypatch, tmp_path, cores=1) == (["stepping", "sensors"], None)


def test_a_long_compile_says_how_far_it_is_while_it_runs(cache, monkeypatch):
    (cache / "v1" / "model_x").mkdir(parents=True)
    for name in ("a-1.py311.nbi", "b-2.py311.nbi"):
        (cache / "v1" / "model_x" / name).touch()
    monkeypatch.setattr(warmup, "TICK_S", 0.05)
    monkeypatch.setattr(warmup.os, "cpu_count", lambda: 1)
    _fake_parts(monkeypatch, [], seconds=0.4)
    said: list[str] = []
    warmup.compile_kernels(said.append)
    assert len(said) >= 4  # at least one line per tick while each part ran
    assert all("s so far," in line and "2 functions in the cache" in line for line in said)
    assert "0 of 2 parts done" in said[0] and "fixed-step kernel: compiling" in said[0]
    assert "1 of 2 parts done" in said[-1]
    assert "fixed-step kernel: done, default sensors: compiling" in said[-1]
    count = len(said)
    time.sleep(0.2)
    assert len(said) == count  # no line once it is over


@pytest.mark.parametrize(
    ("part", "first_use"),
    [
        ("reference", lambda: run_reference(BrakeSetup(), 0.002, rtol=1e-6)),
        ("contact-regime", lambda: run_contact_regime(BrakeSetup(), 0.01)),
    ],
)
def test_a_part_left_out_of_the_set_up_compiles_at_first_use_saying_so(
    cache, monkeypatch, capsys, part, first_use
):
    done: list[str] = []
    _fake_parts(monkeypatch, done, seconds=0.3)
    monkeypatch.setattr(warmup, "TICK_S", 0.05)
    assert part not in warmup.DEFAULT_PARTS
    first_use()  # the driver runs in full after its part's compile
    err = capsys.readouterr().err.splitlines()
    name = warmup.PARTS[part][0]
    assert done == [part]
    assert err[0].startswith(f"brake-sim: compiling the physics kernels ({name}; once")
    ticks = [line for line in err if "s so far, 0 of 1 parts done" in line]
    assert ticks and all(f"{name}: compiling" in line for line in ticks)
    assert err[-1].startswith("brake-sim: kernels compiled in") and err[-1].endswith(f"({name})")
    first_use()  # compiled: silent
    assert done == [part] and capsys.readouterr().err == ""


def test_processes_asking_at_once_compile_a_part_once(tmp_path):
    """Two processes (say, two test workers) that need an uncompiled part at once: one
    compiles it, the other waits for the lock and finds it in the cache."""
    log = tmp_path / "compiled.log"
    code = textwrap.dedent(
        f"""
        import time, numba
        from brake_sim_ros.solvers import warmup
        numba.config.CACHE_DIR = {str(tmp_path / "cache")!r}
        def slow():
            time.sleep(1.0)
            with open({str(log)!r}, "a") as f:
                f.write("compiled\\n")
        warmup.PARTS["reference"] = ("reference solver", slow)
        warmup.ensure_compiled(print, ["reference"])
        print("ready", warmup.is_compiled(["reference"]))
        """
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    runs = [
        subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True, env=env)
        for _ in range(2)
    ]
    outs = [run.communicate(timeout=120)[0] for run in runs]
    assert [run.returncode for run in runs] == [0, 0]
    assert log.read_text() == "compiled\n"
    assert all(out.splitlines()[-1] == "ready True" for out in outs)
    assert sum("kernels compiled in" in out for out in outs) == 1


def test_a_cache_one_cannot_write_to_still_compiles(tmp_path, monkeypatch):
    (tmp_path / "a_file").write_text("")
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "a_file" / "cache"))
    done: list[str] = []
    _fake_parts(monkeypatch, done)
    said: list[str] = []
    warmup.ensure_compiled(said.append, ["reference"])  # no lock, no marker: no error
    assert done == ["reference"] and said[-1].startswith("brake-sim: kernels compiled in")


def test_the_lines_say_the_child_s_parts_are_done_as_soon_as_it_ended(cache, monkeypatch):
    monkeypatch.setattr(warmup, "TICK_S", 0.05)
    monkeypatch.setattr(warmup.os, "cpu_count", lambda: 2)
    monkeypatch.setattr(warmup, "_CHILD", "pass")  # a child that ends at once, well
    _fake_parts(monkeypatch, [], seconds=2.0)  # the first part, here, takes long
    said: list[str] = []
    warmup.compile_kernels(said.append)
    assert "fixed-step kernel: compiling, default sensors: done" in said[-1]
    assert "1 of 2 parts done" in said[-1]


def test_the_marker_is_found_before_the_model_is_imported(tmp_path):
    """A fresh interpreter that imports only the warm-up (as ``brake-sim simulate`` does
    before the command's own imports) looks for the markers in the kernel cache directory,
    not nowhere (which compiled the kernels again at every start)."""
    code = (
        "from brake_sim_ros.solvers import kernel_parts, warmup\n"
        "print(kernel_parts._marker(kernel_parts.DEFAULT_PARTS[0]))"
    )
    env = {**os.environ, "BRAKE_SIM_CACHE_DIR": str(tmp_path)}
    env.pop("NUMBA_CACHE_DIR", None)
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
    ).stdout.strip()
    assert out.startswith(str(tmp_path / "numba")), out


def test_without_a_cache_directory_of_ours_no_lock_is_taken(tmp_path, monkeypatch):
    """numba's CACHE_DIR empty (its own places beside the sources): the compile's turn
    takes no lock and leaves no lock file in the working directory."""
    monkeypatch.setattr(numba.config, "CACHE_DIR", "")
    monkeypatch.chdir(tmp_path)
    with warmup.turn():
        pass
    assert list(tmp_path.iterdir()) == []
