"""Write the bytecode (.pyc) of every module brake-sim and its tests import, once, at set-up.

pip installs with ``--no-compile`` (scripts/setup.sh: it halves pip's time), and where
``PYTHONDONTWRITEBYTECODE`` is set Python never writes a .pyc on import either: every
``brake-sim`` process then compiles numpy, scipy, numba, rclpy and the project from source
as it imports them, about a second of CPU a process. This imports, with bytecode writing
on, every module outside the package that the package's sources or the tests name in an
import statement (at module level or inside a function, found in their syntax trees), so
that each writes its .pyc and those of what it imports; byte-compiles the test runner's
packages whole (:data:`RUNNER`: pytest loads its plugins by name, not by an import
statement); and compiles the package's own sources without importing them (a module
imported for its side effects, such as the sweep's worker warm-up, must not run here).

A module that cannot be imported here (an optional part missing, the ROS interfaces not
built yet) is counted in the last line and left to compile at its first use, as before.
"""

from __future__ import annotations

import ast
import compileall
import importlib
import importlib.util
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = "brake_sim_ros"
TESTS = "tests"  # the suite's own package: the set-up installs the test extra
LOCAL = {PACKAGE, TESTS}
# The test runner's packages (the test extra's), byte-compiled whole: each of the suite's
# workers and subprocesses would otherwise compile them from source
RUNNER = ("pytest", "_pytest", "pluggy", "iniconfig", "xdist", "execnet", "hypothesis",
          "_hypothesis_pytestplugin")  # fmt: skip


def imported_names(root: Path) -> set[str]:
    """Every absolute module name an import statement in the package's or the tests'
    sources names: ``import a.b`` names ``a.b``; ``from a import b`` names ``a`` and,
    where ``b`` is a submodule (``from scipy import signal``), ``a.b``."""
    names: set[str] = set()
    sources = [p for folder in (PACKAGE, TESTS) for p in (root / folder).rglob("*.py")]
    for path in sources:
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names.add(node.module)
                if node.module.split(".")[0] in LOCAL:  # find_spec would import its parent
                    continue
                names.update(
                    f"{node.module}.{alias.name}"
                    for alias in node.names
                    if _is_module(f"{node.module}.{alias.name}")
                )
    return names


def _is_module(name: str) -> bool:
    """Whether ``name`` is a module one could import (not a class or function of one)."""
    try:
        return importlib.util.find_spec(name) is not None
    except (ImportError, ValueError):  # its parent is not a package, or not importable
        return False


def _compile_installed(name: str) -> None:
    """Byte-compile the installed module or package ``name`` whole (nothing if missing)."""
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):
        return
    if spec is None:
        return
    if spec.submodule_search_locations:
        for folder in spec.submodule_search_locations:
            compileall.compile_dir(folder, quiet=1)
    elif spec.origin and spec.origin.endswith(".py"):
        compileall.compile_file(spec.origin, quiet=1)


def main() -> int:
    sys.dont_write_bytecode = False  # whatever PYTHONDONTWRITEBYTECODE says
    sys.path.insert(0, str(ROOT))
    start = time.process_time()
    names = sorted(
        n for n in imported_names(ROOT) if n != "__main__" and n.split(".")[0] not in LOCAL
    )
    failed = []
    for i, name in enumerate(names):
        if i % 100 == 0:  # the set-up's progress lines show the latest
            print(f"{i} of {len(names)} imported", flush=True)
        try:
            importlib.import_module(name)
        except Exception:  # any failure: left to compile at its first use
            failed.append(name)
    for name in RUNNER:
        _compile_installed(name)
    own = compileall.compile_dir(str(ROOT / PACKAGE), quiet=1)
    left = f"; {len(failed)} could not be imported here: {', '.join(failed)}" if failed else ""
    print(
        f"bytecode of {len(sys.modules)} modules and of the package written or up to date"
        f" ({time.process_time() - start:.1f} s of CPU){left}"
        + ("" if own else "; the package's own could not all be compiled")
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
