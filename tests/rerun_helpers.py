"""Reading back .rrd files for the Rerun tests: ``rerun rrd verify`` and the chunk reader."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

os.environ.setdefault("RERUN_ANALYTICS", "0")  # no network from tests


def rerun_cli() -> str:
    exe = Path(sys.executable).with_name("rerun")
    return str(exe) if exe.exists() else (shutil.which("rerun") or "rerun")


def verify(path: Path) -> None:
    """``rerun rrd verify`` (footers checked) must accept the file."""
    r = subprocess.run(
        [rerun_cli(), "rrd", "verify", str(path)], capture_output=True, text=True, timeout=60
    )
    assert r.returncode == 0, r.stdout + r.stderr
    assert "verified without error" in r.stdout + r.stderr


@dataclass
class Contents:
    """Per entity path: rows on ``sim_time`` with their times (ns), values, texts."""

    times_ns: dict[str, list[np.ndarray]] = field(default_factory=lambda: defaultdict(list))
    scalars: dict[str, list[np.ndarray]] = field(default_factory=lambda: defaultdict(list))
    texts: dict[str, list[str]] = field(default_factory=lambda: defaultdict(list))
    static: set[str] = field(default_factory=set)
    blueprints: int = 0

    def times(self, path: str) -> np.ndarray:
        return np.sort(np.concatenate(self.times_ns[path])) if self.times_ns[path] else np.zeros(0)

    def values(self, path: str) -> np.ndarray:
        return np.concatenate(self.scalars[path]) if self.scalars[path] else np.zeros(0)

    @property
    def timed_paths(self) -> set[str]:
        return {p for p, v in self.times_ns.items() if v}


def read(path: Path) -> Contents:
    from rerun.chunk import RrdReader

    reader = RrdReader(path)
    out = Contents(blueprints=len(reader.blueprints()))
    for chunk in reader.stream():
        entity = chunk.entity_path.lstrip("/")
        if chunk.is_static:
            out.static.add(entity)
            continue
        rb = chunk.to_record_batch()
        names = rb.schema.names
        if "sim_time" not in names:
            continue
        t = rb.column("sim_time").cast("int64").to_numpy()
        out.times_ns[entity].append(t)
        if "Scalars:scalars" in names:
            col = rb.column("Scalars:scalars").to_pylist()
            out.scalars[entity].append(np.array([v[0] for v in col], dtype=float))
        for text_col in ("TextLog:text", "TextDocument:text"):
            if text_col in names:
                out.texts[entity] += [v[0] for v in rb.column(text_col).to_pylist()]
    return out
