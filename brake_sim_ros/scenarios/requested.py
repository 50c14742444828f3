"""Scenarios named by a remote caller (the node's ``~/reset`` service): checked, bounded.

A service request is hostile until checked. It may name

* a built-in scenario (a bare name, no ``/``, not ending in ``.toml``), or
* a ``.toml`` regular file inside one of the directories the operator allowed
  (``scenario_dirs``; none by default, so no file at all). A relative path is looked up
  in each allowed directory in order. The path is resolved (``realpath``: symlinks and
  ``..``) before the check, so neither a symlink nor ``../`` leads outside.

The file is opened without following a final symlink and without blocking (a FIFO never
hangs the caller), must pass :func:`~brake_sim_ros.scenarios.files.read_scenario_text`'s
limits (a regular file of at most 1 MiB, UTF-8 without NUL characters) and be TOML nested
at most :data:`~brake_sim_ros.scenarios.loader.MAX_NESTING` deep. Refusals are
:class:`~brake_sim_ros.errors.ScenarioError` with one line that never quotes the file's
content: a TOML syntax error gives its position only, a scenario the strict loader refuses
gives no detail (the loader's message quotes keys and values).

The operator's own ``--scenario`` option is not a request and goes through
``scenarios.loader.load_scenario`` unchanged.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable, Sequence
from importlib import resources
from pathlib import Path

from brake_sim_ros.errors import BrakeSimError, ScenarioError
from brake_sim_ros.scenarios.files import read_scenario_text
from brake_sim_ros.scenarios.loader import (
    BUILTIN_PACKAGE,
    builtin_names,
    parse_scenario,
    parse_toml,
)
from brake_sim_ros.scenarios.types import Scenario

MAX_REQUEST_CHARS = 1024  # a scenario name or path in a request
_SHOWN_CHARS = 64  # at most this much of the caller's own text is echoed back
_TOML_POSITION = re.compile(r"\(at line (\d+), column (\d+)\)|\(at end of document\)")


def _shown(text: str) -> str:
    """The caller's text for an error message: repr (one line), cut to a bounded length."""
    short = text if len(text) <= _SHOWN_CHARS else text[:_SHOWN_CHARS] + "..."
    return repr(short)


def allowed_dirs(entries: Iterable[str]) -> tuple[Path, ...]:
    """The operator's ``scenario_dirs`` entries as resolved, existing directories.

    Each entry may itself hold several directories separated by ``:``; empty entries
    are ignored.

    Raises:
        ScenarioError: an entry that is not an existing directory.
    """
    out: list[Path] = []
    for entry in entries:
        for part in str(entry).split(os.pathsep):
            if not part.strip():
                continue
            real = Path(os.path.realpath(os.path.expanduser(part)))
            if not real.is_dir():
                raise ScenarioError(
                    f"scenario_dirs entry {_shown(part)}: allowed an existing directory"
                )
            if real not in out:
                out.append(real)
    return tuple(out)


def _inside(path: Path, directory: Path) -> bool:
    return os.path.commonpath([path, directory]) == str(directory)


def resolve_requested_path(request: str, dirs: Sequence[Path]) -> Path:
    """The real path of the file ``request`` names, checked to lie in one of ``dirs``.

    Raises:
        ScenarioError: no directory is allowed, the path leads outside them, or it is not a
            ``.toml`` file that exists.
    """
    if not dirs:
        raise ScenarioError(
            f"scenario {_shown(request)}: files are not accepted from service requests on"
            " this node (the operator allows none: node parameter scenario_dirs); allowed"
            f" the built-in scenarios {builtin_names()}"
        )
    given = Path(request)
    candidates = [given] if given.is_absolute() else [d / given for d in dirs]
    where = ", ".join(str(d) for d in dirs)
    for candidate in candidates:
        real = Path(os.path.realpath(candidate))
        if not any(_inside(real, d) for d in dirs):
            raise ScenarioError(
                f"scenario file {_shown(request)} lies outside the allowed directories"
                f" ({where}; symlinks and '..' resolved): refused"
            )
        if real.suffix != ".toml":
            raise ScenarioError(
                f"scenario file {_shown(request)}: allowed only .toml files in {where}"
            )
        if os.path.lexists(real):
            return real
    raise ScenarioError(f"scenario file {_shown(request)}: no such file in {where}")


def parse_requested_text(text: str, source: str) -> Scenario:
    """Parse a requested file's text; errors say where, never what.

    Raises:
        ScenarioError: not TOML (with its position), nested too deep, or not a valid
            scenario (no detail: the strict loader's reasons quote the file).
    """
    try:
        parse_toml(text, source)
    except ScenarioError as exc:
        if "nested too deeply" in str(exc):  # says nothing of the content
            raise
        found = _TOML_POSITION.search(str(exc))
        where = found.group(0).strip("()") if found else "position unknown"
        raise ScenarioError(f"{source}: not valid TOML ({where})") from None
    try:
        return parse_scenario(text, source)
    except (BrakeSimError, RecursionError, ArithmeticError, ValueError, TypeError):
        raise ScenarioError(
            f"{source}: not a valid scenario (the reasons quote the file, so they are not"
            " sent to service callers; the operator sees them with brake-sim simulate)"
        ) from None


def load_requested_scenario(request: str, dirs: Sequence[Path]) -> Scenario:
    """The scenario a service request names: a built-in name, or a checked file in ``dirs``.

    Raises:
        ScenarioError: one line, fit for a service reply (see the module docstring).
    """
    if len(request) > MAX_REQUEST_CHARS:
        raise ScenarioError(
            f"scenario of {len(request)} characters: allowed at most {MAX_REQUEST_CHARS}"
        )
    if not request.isprintable():
        raise ScenarioError(
            f"scenario {_shown(request)}: allowed printable characters only (no control"
            " characters or line breaks)"
        )
    if "/" not in request and not request.endswith(".toml"):
        if request not in builtin_names():
            raise ScenarioError(
                f"unknown scenario {_shown(request)}: allowed one of the built-in scenarios"
                f" {builtin_names()}, or a .toml file in the directories the node's"
                " scenario_dirs parameter allows"
            )
        # not load_scenario: it would first look for a file of that name in the cwd
        text = resources.files(BUILTIN_PACKAGE).joinpath(f"{request}.toml").read_text("utf-8")
        return parse_scenario(text, f"<built-in {request}>")
    path = resolve_requested_path(request, dirs)
    return parse_requested_text(read_scenario_text(path, follow_symlinks=False), str(path))
