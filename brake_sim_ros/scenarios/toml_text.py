"""TOML text from parsed TOML data, so a varied scenario can be re-read by the scenario
loader and stored whole in a run's metadata.

Only what :func:`tomllib.loads` returns for a scenario is written (tables, arrays,
strings, integers, floats, booleans); every table and array is written inline, each key
quoted, so the text round-trips: ``tomllib.loads(dumps(data)) == data``.
"""

from __future__ import annotations

import json
import math
from typing import Any


def _string(text: str) -> str:
    # JSON's escapes are TOML's (\" \\ \n \uXXXX ...); DEL must be escaped too in TOML
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")


def _value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        text = repr(value)
        return text if any(c in text for c in ".en") else f"{text}.0"
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, list):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_string(k)} = {_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"TOML text: a {type(value).__name__} value is not written")


def dumps(data: dict[str, Any]) -> str:
    """``data`` (a top-level table) as TOML text, one ``key = value`` line per key."""
    return "".join(f"{_string(k)} = {_value(v)}\n" for k, v in data.items())
