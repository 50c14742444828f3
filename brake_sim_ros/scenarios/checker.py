"""The strict checker of a TOML table: each value's type, range and keys, and a one-line
error for the first that is wrong, naming the file, the key, the value and what is allowed.

Scenario files (:mod:`.loader` and its table parsers) and campaign files
(:mod:`brake_sim_ros.campaigns.loader`) are checked with it, so their messages read alike.
A message never echoes the file: a value or key is quoted only when short
(:data:`SHOWN_CHARS`), else described (:func:`show_value`: "a string of 300 characters").
"""

from __future__ import annotations

import math
from collections.abc import Set
from typing import Any

from brake_sim_ros.errors import ScenarioError
from brake_sim_ros.identifiers import IDENTIFIER_RULE, is_identifier

# a value or key is quoted in an error message only up to this many characters (its repr);
# a longer one is described ("a string of 300 characters"): messages never echo the file
SHOWN_CHARS = 24

# a key the file does not give: Checker.fail says it is missing, not what it is
MISSING = object()


def describe_value(value: Any) -> str:
    """What ``value`` is, without quoting it."""
    if isinstance(value, dict):
        return f"a table of {len(value)} key{'s' * (len(value) != 1)}"
    if isinstance(value, list):
        return f"an array of {len(value)} item{'s' * (len(value) != 1)}"
    if isinstance(value, str):
        return f"a string of {len(value)} characters"
    if isinstance(value, int) and not isinstance(value, bool):
        return f"an integer of {len(str(abs(value)))} digits"
    return f"a {type(value).__name__} value"


def _short(value: Any) -> bool:
    """Whether ``value``'s repr is cheap and possibly short (no deep or long content)."""
    if isinstance(value, str):
        return len(value) <= SHOWN_CHARS
    if isinstance(value, int) and not isinstance(value, bool):
        return abs(value) < 10**SHOWN_CHARS
    if isinstance(value, dict):
        return len(value) <= 8 and all(_short(k) and _short_scalar(v) for k, v in value.items())
    if isinstance(value, list):
        return len(value) <= 8 and all(_short_scalar(v) for v in value)
    return True


def _short_scalar(value: Any) -> bool:
    return not isinstance(value, dict | list) and _short(value)


def show_value(value: Any) -> str:
    """``value`` for a one-line message: its repr when short and printable (at most
    :data:`SHOWN_CHARS` characters), else what it is ("a string of 300 characters")."""
    if isinstance(value, bool):
        return "true" if value else "false"
    text = repr(value) if _short(value) else ""
    return text if 0 < len(text) <= SHOWN_CHARS and text.isprintable() else describe_value(value)


def show_key(key: str) -> str:
    """A key of the file for a message (keys longer than 40 characters are described)."""
    if len(key) <= 40 and key.isprintable():
        return key
    return f"<a key of {len(key)} characters>"


class Checker:
    """The checks of one file's values; every error names ``source`` (the file).

    Each check returns the value (a number as float) or raises the one-line
    :class:`~brake_sim_ros.errors.ScenarioError` of :meth:`fail`; ``key`` is the dotted
    key of the value in the file (``"actuation.peak_force_n"``, ``"cycle.segments[2]"``).
    """

    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, key: str, value: Any, allowed: str) -> ScenarioError:
        """The error for ``key`` = ``value`` (:data:`MISSING`: not given) and what is
        ``allowed``; returned, for the caller to raise."""
        if value is MISSING:
            return ScenarioError(f"{self.source}: key '{key}' is missing: allowed {allowed}")
        return ScenarioError(
            f"{self.source}: key '{key}' = {show_value(value)} is invalid: allowed {allowed}"
        )

    def table(self, data: Any, key: str, allowed_keys: Set[str]) -> dict[str, Any]:
        """``data``, a table whose keys are all in ``allowed_keys`` (``key`` "": the top)."""
        if not isinstance(data, dict):
            raise self.fail(key, data, "a table")
        for k in data:
            if k not in allowed_keys:
                where = f"{key}.{show_key(k)}" if key else show_key(k)
                raise self.fail(
                    where, data[k], f"one of the keys {sorted(allowed_keys)} (unknown key)"
                )
        return data

    def number(
        self,
        value: Any,
        key: str,
        lo: float = -math.inf,
        hi: float = math.inf,
        lo_open: bool = False,
    ) -> float:
        """A finite number from ``lo`` to ``hi`` (``lo_open``: above ``lo``), as float."""
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(key, value, "a number")
        value = float(value)
        if not math.isfinite(value):
            raise self.fail(key, value, "a finite number")
        if value < lo or value > hi or (lo_open and value == lo):
            low = f"> {lo:g}" if lo_open else f">= {lo:g}"
            raise self.fail(key, value, f"a number {low} and <= {hi:g}")
        return value

    def string(self, value: Any, key: str, choices: tuple[str, ...] | None = None) -> str:
        """A string, one of ``choices`` when given."""
        if not isinstance(value, str):
            raise self.fail(key, value, "a string")
        if choices is not None and value not in choices:
            raise self.fail(key, value, f"one of {list(choices)}")
        return value

    def integer(self, value: Any, key: str, lo: int, hi: int) -> int:
        """An integer (not a boolean) from ``lo`` to ``hi``."""
        if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
            raise self.fail(key, value, f"an integer from {lo} to {hi}")
        return value

    def seed(self, value: Any, key: str) -> int:
        """A seed: an integer from 0 to 2^63 - 1."""
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < 2**63:
            raise self.fail(key, value, "an integer from 0 to 2^63 - 1")
        return value

    def identifier(self, value: Any, key: str) -> str:
        """An identifier, such as a brake unit's id (:mod:`brake_sim_ros.identifiers`)."""
        if not is_identifier(value):
            raise self.fail(key, value, IDENTIFIER_RULE)
        return value


def number_table(
    ctx: Checker,
    data: Any,
    table: str,
    limits: tuple[tuple[str, float, float], ...],
    open_low: set[str],
) -> dict[str, float]:
    """A table of optional numbers, each within its (name, low, high) limits (``open_low``:
    the names whose low limit is excluded); only the keys given."""
    data = ctx.table(data, table, {name for name, _lo, _hi in limits})
    return {
        name: ctx.number(data[name], f"{table}.{name}", lo, hi, lo_open=name in open_low)
        for name, lo, hi in limits
        if name in data
    }


def value_range(
    ctx: Checker, value: Any, key: str, limits: tuple[float, float], allowed: str
) -> tuple[float, float]:
    """``[low, high]``, two numbers within ``limits`` with low <= high (``allowed``: what
    the one-line error says is allowed)."""
    if not isinstance(value, list) or len(value) != 2:
        raise ctx.fail(key, value, allowed)
    low, high = (ctx.number(v, f"{key}[{i}]", *limits) for i, v in enumerate(value))
    if low > high:
        raise ctx.fail(key, value, allowed)
    return low, high
