"""Write the bytecode (.pyc) of what brake-sim and its tests run, once, at set-up.

pip installs with ``--no-compile`` (scripts/setup.sh: it halves pip's time), and where
``PYTHONDONTWRITEBYTECODE`` is set Python never writes a .pyc on import either: every
process then compiles from source what it imports, numba's typing and lowering modules
(imported as it loads or compiles a kernel), scipy, numpy, rclpy and the project, one to
three seconds of CPU a process; the test suite starts hundreds. This byte-compiles the
venv's installed packages whole (what a process imports lazily is in them too); imports,
with bytecode writing on, every module that the package's or the tests' sources name in
an import statement (at module level or inside a function, found in their syntax trees),
so that those outside the venv (a system ROS 2's rclpy) write theirs where they may; and
compiles the package's own sources without importing them (a module imported for its side
effects, such as the sweep's worker warm-up, must not run here). The test modules'
assertion-rewritten bytecode is pytest's to write, at the suite's first run
(tests/conftest.py lets it whatever ``PYTHONDONTWRITEBYTECODE`` says): collecting the
suite here took 12 s of CPU on the set-up's critical path, and the suite's workers write
it in parallel.

A module that cannot be imported here (an optional part missing, the ROS interfaces not
built yet) is counted in the last line and left to compile at its first use, as before.
"""

from __future__ import annotations

import ast
import compileall
import importlib
import importlib.util
import re
import sys
import sysconfig
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = "brake_sim_ros"
TESTS = "tests"  # the suite's own package: the set-up installs the test extra
LOCAL = {PACKAGE, TESTS}


def imported_names(root: Path, compiled: list[Path] | None = None) -> set[str]:
    """Every absolute module name an import statement in the package's or the tests'
    sources names: ``import a.b`` names ``a.b``; ``from a import b`` names ``a`` and,
    where ``b`` is a submodule (``from scipy import signal``), ``a.b``; but not for an
    ``a`` installed in ``compiled`` (folders compiled whole: looking ``a.b`` up would
    import ``a`` for nothing)."""
    names: set[str] = set()
    sources = [p for folder in (PACKAGE, TESTS) for p in (root / folder).rglob("*.py")]
    for path in sources:
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names.add(node.module)
                top = node.module.split(".")[0]
                if top in LOCAL or (compiled and _installed_in(top, compiled)):
                    continue  # find_spec would import its parent
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


def installed_folders() -> list[Path]:
    """This interpreter's environment's site-packages folders (the venv's)."""
    paths = dict.fromkeys(sysconfig.get_path(key) for key in ("purelib", "platlib"))
    return [Path(p) for p in paths if p]


def _installed_in(top: str, folders: list[Path]) -> bool:
    """Whether the top-level module or package ``top`` is installed in one of ``folders``."""
    try:
        spec = importlib.util.find_spec(top)  # top level: imports nothing
    except (ImportError, ValueError):
        return False
    # a namespace package has no origin, only its folders
    places = [] if spec is None else list(spec.submodule_search_locations or [spec.origin])
    return any(Path(p).is_relative_to(f) for p in places if p for f in folders)


def outside(names: list[str], folders: list[Path]) -> list[str]:
    """Those of ``names`` whose top-level package is not installed in ``folders`` (a system
    ROS 2's rclpy, the standard library): what compiling ``folders`` leaves out."""
    return [name for name in names if not _installed_in(name.split(".")[0], folders)]


# Left to compile at their first import, if ever: the installed packages' own test suites
# (28 % of the venv's Python source: scipy's, numpy's, scikit-learn's ...) and the
# installers, which brake-sim and its tests never import.
SKIPPED_FOLDERS = re.compile(r"[/\\]tests[/\\]")
SKIPPED_PACKAGES = frozenset({"pip", "setuptools", "pkg_resources", "_distutils_hack"})


def compile_installed(say=print) -> bool:
    """Byte-compile the packages installed in this interpreter's environment (the venv's
    site-packages), each top-level entry in turn but :data:`SKIPPED_PACKAGES` and every
    folder :data:`SKIPPED_FOLDERS` matches, saying how far every 100 entries; those up to
    date are only looked at. False if a file would not compile."""
    entries = sorted(e for folder in installed_folders() for e in folder.glob("*"))
    ok = True
    for i, entry in enumerate(entries):
        if i % 100 == 0:  # the set-up's progress lines show the latest
            say(f"{i} of {len(entries)} installed packages byte-compiled")
        if entry.name in SKIPPED_PACKAGES:
            continue
        if entry.is_dir() and not entry.name.endswith((".dist-info", ".egg-info")):
            ok &= bool(compileall.compile_dir(str(entry), quiet=2, rx=SKIPPED_FOLDERS))
        elif entry.suffix == ".py":
            ok &= bool(compileall.compile_file(str(entry), quiet=2))
    return ok


def main() -> int:
    sys.dont_write_bytecode = False  # whatever PYTHONDONTWRITEBYTECODE says
    sys.path.insert(0, str(ROOT))
    start = time.process_time()
    installed = compile_installed(lambda line: print(line, flush=True))
    folders = installed_folders()
    names = outside(
        sorted(
            n
            for n in imported_names(ROOT, folders)
            if n != "__main__" and n.split(".")[0] not in LOCAL
        ),
        folders,
    )
    failed = []
    for i, name in enumerate(names):
        if i % 100 == 0:  # the set-up's progress lines show the latest
            print(f"{i} of {len(names)} imported", flush=True)
        try:
            importlib.import_module(name)
        except Exception:  # any failure: left to compile at its first use
            failed.append(name)
    own = compileall.compile_dir(str(ROOT / PACKAGE), quiet=1)
    left = f"; {len(failed)} could not be imported here: {', '.join(failed)}" if failed else ""
    print(
        f"bytecode of the installed packages, of {len(sys.modules)} modules imported and of"
        f" the package written or up to date ({time.process_time() - start:.1f} s of CPU)"
        + left
        + ("" if installed else "; some installed files would not compile (left as they are)")
        + ("" if own else "; the package's own could not all be compiled")
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
