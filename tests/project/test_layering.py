"""The package graph points one way: model <- sensing <- analysis <- solvers <- (fleet,
scenarios) <- stream <- (ros, recording, viz), with app, studies and the CLI on top.

A unit is a top-level module or package of ``brake_sim_ros``: every module of a package
(the CLI's ``cli/simulate.py`` as much as ``cli/__init__.py``) counts as its package.

Every ``import`` of every module counts, also those inside functions (lazy imports) and
under ``if TYPE_CHECKING:``: a dependency deferred is still a dependency.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = "brake_sim_ros"
ROOT = Path(__file__).resolve().parents[2] / PACKAGE

# the top-level modules errors.py, identifiers.py, regular_file.py, command_line.py and the
# package's __init__
_BASE = {"errors", "identifiers", "regular_file", "command_line", "__init__"}
_CORE = _BASE | {"model"}
_SOLVERS = _CORE | {"analysis", "sensing", "solvers"}
_LIBRARY = _SOLVERS | {"fleet", "scenarios"}
_STREAM = _LIBRARY | {"stream"}
_ADAPTERS = {"ros", "recording", "viz"}

# Which top-level units of the package each one may import (itself always allowed):
# model <- sensing <- analysis <- solvers <- (fleet, scenarios) <- stream <- (ros, recording,
# viz) <- the top.
ALLOWED: dict[str, set[str]] = {
    "__init__": set(),
    "errors": set(),
    "identifiers": set(),
    "regular_file": set(),  # the bounded read of every checked file
    "command_line": set(),  # the one-line parser of every command line
    "model": _BASE,
    "sensing": _CORE,  # what sensors measure of the physics' sample blocks
    "analysis": _CORE | {"sensing"},  # features of measured channels too
    "solvers": _CORE | {"analysis", "sensing"},  # warmup compiles the sensors' paths too
    "fleet": _CORE | {"sensing"},  # unit scatter draws sensor calibration as well
    "scenarios": _SOLVERS | {"fleet"},  # a scenario names its solver preset and method
    "stream": _LIBRARY,
    "ros": _STREAM,  # never recording or viz: the node is a leaf adapter
    "recording": _STREAM,
    "viz": _STREAM | {"recording"},  # the viewer reads MCAP recordings
    "campaigns": _LIBRARY,  # campaign files: varied scenarios, read by the scenario loader
    # tables of runs (Parquet) and sweeps: campaigns run, files written by recording.output
    "datasets": _STREAM | {"campaigns", "recording"},
    "detection": _STREAM | {"datasets"},  # detectors and their scoring, on datasets
    "studies": _STREAM | _ADAPTERS | {"campaigns", "datasets", "detection"},
    "app": _STREAM | _ADAPTERS,
    "cli": _STREAM | _ADAPTERS | {"app", "studies", "datasets", "detection", "campaigns"},
}


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(ROOT.rglob("*.py"))}


MODULES = _modules()


def _imports(module: str, path: Path) -> set[str]:
    """Package modules imported anywhere in ``path`` (resolved to modules, not names)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    is_package = path.name == "__init__.py"
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split(".")
                base = base if is_package else base[:-1]
                base = base[: len(base) - (node.level - 1)]
                parent = ".".join(base + ([node.module] if node.module else []))
            else:
                parent = node.module or ""
            # "from pkg import sub" imports the module pkg.sub when it is one
            names = [
                f"{parent}.{alias.name}" if f"{parent}.{alias.name}" in MODULES else parent
                for alias in node.names
            ]
        else:
            continue
        for name in names:
            if name == PACKAGE or name.startswith(PACKAGE + "."):
                while name not in MODULES:  # "import a.b.c" where c is a name
                    name = name.rsplit(".", 1)[0]
                out.add(name)
    out.discard(module)
    return out


def _unit(module: str) -> str:
    parts = module.split(".")
    return "__init__" if len(parts) == 1 else parts[1]


GRAPH = {m: _imports(m, p) for m, p in MODULES.items()}


def test_every_unit_is_in_the_allowed_graph():
    units = {_unit(m) for m in MODULES}
    assert units <= ALLOWED.keys(), f"units missing from ALLOWED: {units - ALLOWED.keys()}"


def _violations(graph: dict[str, set[str]]) -> list[str]:
    """Every import in ``graph`` of a unit its importer's unit may not import."""
    bad = []
    for module, imported in graph.items():
        unit = _unit(module)
        for target in imported:
            other = _unit(target)
            if other == unit or other in ALLOWED[unit]:
                continue
            bad.append(f"{module} imports {target} ({unit} may import {sorted(ALLOWED[unit])})")
    return sorted(bad)


def test_no_package_imports_one_above_it():
    bad = _violations(GRAPH)
    assert not bad, "\n".join(bad)


def test_ros_imports_neither_recording_nor_viz():
    bad = [
        f"{m} imports {t}"
        for m, imported in GRAPH.items()
        if _unit(m) == "ros"
        for t in imported
        if _unit(t) in ("recording", "viz")
    ]
    assert not bad, bad


def test_no_import_cycle_between_modules():
    """Depth-first search over the module graph; reports the first cycle found."""
    state: dict[str, int] = {}  # 1 = on the stack, 2 = done
    stack: list[str] = []

    def visit(module: str) -> list[str] | None:
        state[module] = 1
        stack.append(module)
        for target in sorted(GRAPH.get(module, ())):
            if state.get(target) == 1:
                return [*stack[stack.index(target) :], target]
            if target in GRAPH and state.get(target) is None:
                found = visit(target)
                if found:
                    return found
        stack.pop()
        state[module] = 2
        return None

    for module in sorted(GRAPH):
        if state.get(module) is None:
            cycle = visit(module)
            assert cycle is None, " -> ".join(cycle)


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("from brake_sim_ros.recording.record import x", "brake_sim_ros.recording.record"),
        ("def f():\n    from brake_sim_ros.viz import commands", "brake_sim_ros.viz.commands"),
        ("from ..viz import commands", "brake_sim_ros.viz.commands"),
        ("import brake_sim_ros.ros.node", "brake_sim_ros.ros.node"),
    ],
)
def test_the_parser_sees_every_kind_of_import(tmp_path, source, expected):
    """The check itself can fail: lazy, relative and plain imports are all found."""
    fake = tmp_path / "node.py"
    fake.write_text(source)
    assert expected in _imports("brake_sim_ros.ros.commands", fake)


def test_the_cli_is_one_unit():
    """The CLI is a package: each of its modules is checked as the unit ``cli``."""
    cli_modules = {m for m in MODULES if m == f"{PACKAGE}.cli" or m.startswith(f"{PACKAGE}.cli.")}
    assert {f"{PACKAGE}.cli", f"{PACKAGE}.cli.common", f"{PACKAGE}.cli.simulate"} <= cli_modules
    assert {_unit(m) for m in cli_modules} == {"cli"}


@pytest.mark.parametrize(
    "source",
    [
        "from brake_sim_ros.cli import main",
        "from brake_sim_ros import cli",
        "def f():\n    from brake_sim_ros.cli.simulate import cmd_simulate",
        "import brake_sim_ros.cli.common",
        "from ..cli import common",
    ],
)
def test_the_library_importing_the_cli_is_refused(tmp_path, source):
    """The check can fail for the CLI package: the model importing any of its modules."""
    fake = tmp_path / "kernel.py"
    fake.write_text(source)
    module = f"{PACKAGE}.model.kernel"
    imported = _imports(module, fake)
    assert {_unit(t) for t in imported} == {"cli"}
    assert _violations({module: imported})
