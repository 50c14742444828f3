"""The compile notice: said once per source version, with the marker in the kernel cache."""

from __future__ import annotations

import numba

from brake_sim_ros.solvers import warmup


def test_compilation_is_announced_once_per_version(tmp_path, monkeypatch):
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "v1"))
    calls = []
    monkeypatch.setattr(warmup, "compile_kernels", lambda: calls.append(1) or 1.5)
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


def _record_parts(monkeypatch) -> list[str]:
    done: list[str] = []
    monkeypatch.setattr(warmup, "_compile_stepping", lambda: done.append("stepping"))
    monkeypatch.setattr(warmup, "_compile_the_rest", lambda: done.append("rest here"))
    return done


def test_the_rest_compiles_in_a_child_process_beside_the_stepping(monkeypatch, tmp_path):
    monkeypatch.setattr(warmup.os, "cpu_count", lambda: 2)
    done = _record_parts(monkeypatch)
    started = tmp_path / "child_started"
    monkeypatch.setattr(warmup, "_CHILD", f"open({str(started)!r}, 'w').close()")
    warmup.compile_kernels()
    assert done == ["stepping"]
    assert started.exists()


def test_a_failed_child_leaves_its_part_to_this_process(monkeypatch):
    monkeypatch.setattr(warmup.os, "cpu_count", lambda: 2)
    done = _record_parts(monkeypatch)
    monkeypatch.setattr(warmup, "_CHILD", "import sys; sys.exit(3)")
    warmup.compile_kernels()
    assert done == ["stepping", "rest here"]


def test_one_core_compiles_both_parts_here(monkeypatch, tmp_path):
    monkeypatch.setattr(warmup.os, "cpu_count", lambda: 1)
    done = _record_parts(monkeypatch)
    started = tmp_path / "child_started"
    monkeypatch.setattr(warmup, "_CHILD", f"open({str(started)!r}, 'w').close()")
    warmup.compile_kernels()
    assert done == ["stepping", "rest here"]
    assert not started.exists()  # no child process on one core
