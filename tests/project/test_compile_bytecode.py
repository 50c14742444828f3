"""scripts/compile_bytecode.py finds what brake-sim and its tests import, lazily imported
modules too, and compiles the package's own modules without running them."""

from __future__ import annotations

import importlib.util
import os
import subprocess
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


def test_what_only_the_tests_import_is_found_and_the_local_packages_are_not():
    """The suite's imports (its workers and subprocesses import them in every run) and
    none of the two local packages, which are byte-compiled or rewritten, not imported."""
    script = _script()
    names = script.imported_names(ROOT)
    assert {"hypothesis", "pytest", "rosbags.typesys"} <= names
    assert any(n.startswith("tests.") for n in names)  # found, then left out by main()


def test_the_installed_packages_are_compiled_whole_with_their_lazy_imports(tmp_path, monkeypatch):
    """Every installed package is byte-compiled, modules nothing imports at set-up too
    (numba imports its typing modules as it compiles), but for the packages' own tests and
    the installers; and how far it is is said."""
    script = _script()
    site = tmp_path / "site-packages"
    (site / "lazy").mkdir(parents=True)
    (site / "lazy" / "__init__.py").write_text("")
    (site / "lazy" / "deep.py").write_text("raise SystemExit('imported')\n")
    (site / "single.py").write_text("X = 1\n")
    (site / "lazy-1.0.dist-info").mkdir()
    # a package's own test suite and the installer: nothing brake-sim runs imports them
    (site / "lazy" / "tests").mkdir()
    (site / "lazy" / "tests" / "test_deep.py").write_text("X = 2\n")
    (site / "pip").mkdir()
    (site / "pip" / "__init__.py").write_text("")
    monkeypatch.setattr(script.sysconfig, "get_path", lambda key: str(site))
    said: list[str] = []
    assert script.compile_installed(said.append)
    assert list((site / "lazy" / "__pycache__").glob("deep.*.pyc"))
    assert list((site / "__pycache__").glob("single.*.pyc"))
    assert not list(site.glob("lazy/tests/__pycache__/*.pyc"))
    assert not list(site.glob("pip/__pycache__/*.pyc"))
    assert said == ["0 of 4 installed packages byte-compiled"]


def test_the_package_is_compiled_not_imported(tmp_path, monkeypatch):
    """The package's own sources are byte-compiled, not imported: a module imported for its
    side effects (the sweep's worker warm-up runs a scenario) must not run at set-up."""
    script = _script()
    package = tmp_path / script.PACKAGE
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "side_effect.py").write_text("raise SystemExit('imported')\n")
    monkeypatch.setattr(script, "ROOT", tmp_path)
    monkeypatch.setattr(sys, "path", list(sys.path))  # main() puts ROOT first
    monkeypatch.setattr(sys, "dont_write_bytecode", sys.dont_write_bytecode)  # and sets it
    monkeypatch.setattr(script, "imported_names", lambda root, compiled=None: {"json"})
    monkeypatch.setattr(script, "compile_installed", lambda say: True)
    assert script.main() == 0
    assert list((package / "__pycache__").glob("side_effect.*.pyc"))


def test_only_what_lies_outside_the_installed_packages_is_imported():
    """What the venv's packages hold is compiled whole and not imported again; what lies
    elsewhere (the standard library here, a system ROS 2's rclpy) is imported."""
    script = _script()
    kept = script.outside(
        ["json.decoder", "numpy.linalg", "no_such_module"], script.installed_folders()
    )
    assert kept == ["json.decoder", "no_such_module"]
    # nor are the submodules of an installed package looked up (that would import it)
    names = script.imported_names(ROOT, script.installed_folders())
    assert "scipy" in names and "scipy.signal" not in names


def test_the_suite_writes_its_modules_rewritten_bytecode_whatever_the_environment_says(
    tmp_path,
):
    """With PYTHONDONTWRITEBYTECODE set pytest writes no assertion-rewritten .pyc; beside
    the suite's conftest it does, so that later runs (and the workers of this one that
    import a module after another) read it instead of rewriting it."""
    import pytest

    tag = f"{sys.implementation.cache_tag}-pytest-{pytest.__version__}.pyc"
    tests = tmp_path / "suite"  # not "tests": that is the suite's package, imported below
    tests.mkdir()
    module = tests / "test_one.py"
    module.write_text("def test_sum():\n    assert 1 + 1 == 2\n")
    pyc = tests / "__pycache__" / f"test_one.{tag}"
    command = [sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:xdist"]
    command += ["-p", "no:cacheprovider", "--rootdir", str(tmp_path), str(module)]
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1", "PYTHONPATH": str(ROOT)}
    for conftest in (False, True):
        if conftest:  # the suite's conftest, imported: what its import does, not its hooks
            (tests / "conftest.py").write_text("import tests.conftest  # noqa: F401\n")
        done = subprocess.run(command, cwd=tmp_path, env=env, capture_output=True, text=True)
        assert done.returncode == 0, done.stdout + done.stderr
        assert pyc.is_file() == conftest
