"""scripts/compile_bytecode.py finds what brake-sim imports, lazily imported modules too,
and never imports a ``__main__`` module (that would run a command)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _script():
    spec = importlib.util.spec_from_file_location(
        "compile_bytecode", ROOT / "scripts" / "compile_bytecode.py"
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("compile_bytecode", module)
    spec.loader.exec_module(module)
    return module


def test_the_imports_inside_functions_are_found_too():
    names = _script().imported_names(ROOT)
    # imported only inside functions (sensing/transducers.py, solvers/reference.py, the
    # Rerun sinks): the modules a process would otherwise compile at its first use
    assert {"scipy.signal", "scipy.integrate", "rerun"} <= names
    assert {"numpy", "numba", "rclpy"} <= names


def test_no_main_module_is_imported():
    modules = _script().project_modules()
    assert "brake_sim_ros.cli.simulate" in modules
    assert not [m for m in modules if m.endswith("__main__")]
