"""Checks the parameter dataclasses run on construction: one-line errors naming the field,
its value and what is allowed."""

from __future__ import annotations

import math
from dataclasses import fields
from typing import Any

from brake_sim_ros.errors import ParameterError


def require(condition: bool, name: str, value: Any, allowed: str) -> None:
    """Raise :class:`ParameterError` ``parameter name=value is invalid: allowed ...``
    unless ``condition``."""
    if not condition:
        raise ParameterError(f"parameter {name}={value!r} is invalid: allowed {allowed}")


def require_finite(obj: Any) -> None:
    """Refuse a dataclass ``obj`` with a numeric field that is not finite."""
    for f in fields(obj):
        value = getattr(obj, f.name)
        if isinstance(value, float | int) and not isinstance(value, bool):
            require(math.isfinite(value), f.name, value, "a finite number")
