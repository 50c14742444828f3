"""The Python class of each message type of the topic table, imported by name, only those."""

from __future__ import annotations

import importlib

from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.stream.topics import TYPES


def message_class(type_name: str) -> type:
    """The Python class of a type of the topic table (``pkg/msg/Name``).

    Only the table's types are imported, from the module their name gives; any other name
    (one read from a file, say) is refused before anything is imported.

    Raises:
        BrakeSimError: a type outside the table, or one not installed here.
    """
    if type_name not in TYPES:
        raise BrakeSimError(
            f"message type {type_name!r} is not one this project publishes; allowed: "
            + ", ".join(sorted(TYPES))
        )
    package, kind, name = type_name.split("/")
    try:
        return getattr(importlib.import_module(f"{package}.{kind}"), name)
    except (ImportError, AttributeError):
        raise BrakeSimError(
            f"message type {type_name} is not installed here (no Python module"
            f" {package}.{kind} with {name}); run scripts/setup.sh or source the workspace"
            " that provides it"
        ) from None
