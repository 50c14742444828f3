"""A scenario file's text, read as hostile input: a regular file never waited on, at most
:data:`MAX_SCENARIO_BYTES`, UTF-8 without NUL characters (campaign files are read the same
way); and whether a name the user gave is a path or a built-in's name.
"""

from __future__ import annotations

import os

from brake_sim_ros import regular_file
from brake_sim_ros.errors import ScenarioError
from brake_sim_ros.regular_file import FileRefusedError, read_regular_file

# the largest scenario (or campaign) file, bytes: a real scenario is a few kB
MAX_SCENARIO_BYTES = 1024 * 1024


def shown_path(path: str | os.PathLike[str]) -> str:
    """A path for a message: as given when printable and short, else its repr, cut."""
    text = os.fspath(path)
    if isinstance(text, bytes):
        text = os.fsdecode(text)
    shown = text if text.isprintable() else repr(text)
    return shown if len(shown) <= 300 else f"{shown[:150]}...{shown[-100:]}"


def _refusal(name: str, exc: FileRefusedError) -> str:
    """The one-line message for a scenario file :func:`read_regular_file` refused."""
    cannot = f"{name}: cannot read the scenario file"
    if exc.reason == regular_file.MISSING:
        return f"{cannot}: no such file"
    if exc.reason == regular_file.NOT_A_PATH:
        return f"{cannot}: not a valid path"
    if exc.reason == regular_file.NOT_REGULAR:
        if exc.detail:
            return f"{cannot}: it is {exc.detail}; allowed a regular file"
        return f"{cannot}: not a regular file; allowed one"
    if exc.reason in (regular_file.TOO_LARGE, regular_file.GREW):
        return (
            f"{name}: the scenario file is larger than {MAX_SCENARIO_BYTES} bytes (1 MiB):"
            " allowed at most that"
        )
    return f"{cannot}: {exc.detail}"


def read_scenario_text(path: str | os.PathLike[str], *, follow_symlinks: bool = True) -> str:
    """The text of a scenario file, read as hostile input: the file-level limits of
    :func:`read_scenario_file` (a regular file that is never waited on, at most
    :data:`MAX_SCENARIO_BYTES`, UTF-8 without NUL characters), checked on the open file.

    Args:
        follow_symlinks: False refuses a final symbolic link (O_NOFOLLOW): for paths
            resolved and checked before opening, so a link swapped in later is not followed.

    Raises:
        ScenarioError: one line naming the file and the rule; never the file's content.
    """
    name = shown_path(path)
    try:
        data = read_regular_file(path, MAX_SCENARIO_BYTES, follow_symlinks=follow_symlinks)
    except FileRefusedError as exc:
        raise ScenarioError(_refusal(name, exc)) from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        column = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        raise ScenarioError(
            f"{name}: not UTF-8 text (a byte that is not UTF-8 at line {line}, column"
            f" {column}): allowed a UTF-8 TOML file"
        ) from None
    if "\x00" in text:
        raise ScenarioError(f"{name}: contains NUL characters: allowed a UTF-8 TOML file")
    return text.removeprefix("\ufeff")


def is_path(name_or_path: str | os.PathLike[str]) -> bool:
    """Whether ``load_scenario`` reads a file: a Path, a name ending in .toml, or a name an
    existing file or directory has (so that it is refused as one, not as a name)."""
    if not isinstance(name_or_path, str):
        return True
    if name_or_path.endswith(".toml") or "/" in name_or_path or os.sep in name_or_path:
        return True
    try:
        return os.path.lexists(name_or_path)
    except (OSError, ValueError):
        return False
