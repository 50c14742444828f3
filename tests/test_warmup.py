"""The compile notice: said once per source version, with the marker in the kernel cache."""

from __future__ import annotations

import os
import subprocess
import sys
import time

import numba

from brake_sim_ros.solvers import warmup


def test_compilation_is_announced_once_per_version(tmp_path, monkeypatch):
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "v1"))
    calls = []
    monkeypatch.setattr(warmup, "compile_kernels", lambda _say: calls.append(1) or 1.5)
    said: list[str] = []
    assert not warmup.is_compiled()
    warmup.ensure_compiled(said.append)
    assert calls == [1] and len(said) == 2
    assert "compiling the physics kernels" in said[0] and "1.5 s" in said[1]
    assert warmup.is_compiled()
    warmup.ensure_compiled(said.append)  # cached: silent, nothing compiled
    assert calls == [1] and len(said) == 2
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "v2"))  # another version
    assert not warmup.is_compiled()


def test_the_marker_is_found_before_the_model_is_imported(tmp_path):
    """A fresh interpreter that imports only the warm-up (as ``brake-sim simulate`` does
    before the command's own imports) looks for the marker in the kernel cache directory,
    not nowhere (which compiled the kernels again at every start)."""
    code = "from brake_sim_ros.solvers import warmup; print(warmup._marker())"
    env = {**os.environ, "BRAKE_SIM_CACHE_DIR": str(tmp_path)}
    env.pop("NUMBA_CACHE_DIR", None)
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
    ).stdout.strip()
    assert out.startswith(str(tmp_path / "numba")) and out.endswith(warmup._MARKER), out


def _compile(monkeypatch, tmp_path, cores: int, child_fails: bool = False):
    """compile_kernels on ``cores`` cores with both parts recorded, not compiled, and a
    child that leaves a file (or fails); returns the parts run here and whether a child
    started."""
    done: list[str] = []
    monkeypatch.setattr(warmup.os, "cpu_count", lambda: cores)
    monkeypatch.setattr(warmup, "_compile_stepping", lambda: done.append("stepping"))
    monkeypatch.setattr(warmup, "_compile_the_rest", lambda: done.append("rest here"))
    started = tmp_path / "child_started"
    child = f"open({str(started)!r}, 'w').close()"
    monkeypatch.setattr(warmup, "_CHILD", child + ("; raise SystemExit(3)" if child_fails else ""))
    warmup.compile_kernels()
    return done, started.exists()


def test_the_rest_compiles_in_a_child_process_beside_the_stepping(monkeypatch, tmp_path):
    assert _compile(monkeypatch, tmp_path, cores=2) == (["stepping"], True)


def test_a_failed_child_leaves_its_part_to_this_process(monkeypatch, tmp_path):
    done = _compile(monkeypatch, tmp_path, cores=2, child_fails=True)
    assert done == (["stepping", "rest here"], True)


def test_one_core_compiles_both_parts_here(monkeypatch, tmp_path):
    # no child process on one core
    assert _compile(monkeypatch, tmp_path, cores=1) == (["stepping", "rest here"], False)


def test_a_long_compile_says_how_far_it_is_while_it_runs(monkeypatch, tmp_path):
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    (tmp_path / "model_x").mkdir()
    for name in ("a-1.py311.nbi", "b-2.py311.nbi"):
        (tmp_path / "model_x" / name).touch()
    monkeypatch.setattr(warmup, "TICK_S", 0.05)
    monkeypatch.setattr(warmup.os, "cpu_count", lambda: 1)
    monkeypatch.setattr(warmup, "_compile_stepping", lambda: time.sleep(0.5))
    monkeypatch.setattr(warmup, "_compile_the_rest", lambda: time.sleep(0.3))
    said: list[str] = []
    warmup.compile_kernels(said.append)
    assert len(said) >= 4  # at least one line per tick while each part ran
    assert all("s so far, 2 functions in the cache" in line for line in said)
    assert "fixed-step kernel: compiling" in said[0]
    assert "fixed-step kernel: done, reference, regimes and sensors: compiling" in said[-1]
    count = len(said)
    time.sleep(0.2)
    assert len(said) == count  # no line once it is over
