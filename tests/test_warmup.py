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
