"""Complete ``ros2msg`` message definitions, as rosbag2 stores them in MCAP schemas.

A reader that does not know a type (Foxglove, rosbags, Rerun) decodes its CDR bytes from
the schema alone, so the schema holds the type's ``.msg`` text followed by every type it
depends on, recursively. The layout is rosbag2's (``docs/message_definition_encoding.md``,
``LocalMessageDefinitionSource`` in rosbag2_cpp, Jazzy): the root definition first, then
for each dependency, in the order a depth-first walk over sorted field types meets it,

    ================================================================================
    MSG: <package>/<Name as written in the field>
    <its .msg text>

The ``.msg`` files come from the installed interface packages: each prefix of
``AMENT_PREFIX_PATH`` (a sourced ROS 2 install or workspace), then this interpreter's
prefix (the PyPI wheels and our ``brake_sim_msgs`` install into the venv), looked up in
``<prefix>/share/<package>/msg/<Name>.msg``. The type hash (``RIHS01_...``, what rosbag2
Jazzy stores as ``topic_type_hash``) comes from the ``<Name>.json`` type description that
rosidl installs beside it.
"""

from __future__ import annotations

import functools
import json
import os
import re
import sys
from pathlib import Path

from brake_sim_ros.errors import BrakeSimError

DELIMITER = "=" * 80
PRIMITIVE_TYPES = frozenset(
    {
        "bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16",
        "int32", "uint32", "int64", "uint64", "string", "wstring",
    }
)  # fmt: skip
_TYPE_NAME = re.compile(r"^([A-Za-z0-9_]+)/(?:msg/)?([A-Za-z0-9_]+)$")
# a field's type at the start of a line: "pkg/Type[<=3] name", "Type name", "string<=8 s"
_FIELD_TYPE = re.compile(r"^\s*([A-Za-z0-9_/]+)(?:<=\d+)?(?:\[[^\]]*\])?\s+\S")


class SchemaError(BrakeSimError, LookupError):
    """A message definition that cannot be found or understood."""


def interface_prefixes() -> list[Path]:
    """Install prefixes searched for interface files, in order (see the module doc)."""
    prefixes = [Path(p) for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    prefixes.append(Path(sys.prefix))
    return list(dict.fromkeys(prefixes))


def _split(type_name: str) -> tuple[str, str]:
    match = _TYPE_NAME.match(type_name)
    if match is None:
        raise SchemaError(
            f"message type {type_name!r}: allowed 'package/msg/Name' or 'package/Name'"
        )
    return match.group(1), match.group(2)


def _interface_file(type_name: str, suffix: str) -> Path:
    package, name = _split(type_name)
    for prefix in interface_prefixes():
        path = prefix / "share" / package / "msg" / f"{name}{suffix}"
        if path.is_file():
            return path
    searched = ", ".join(str(p) for p in interface_prefixes())
    raise SchemaError(
        f"no {name}{suffix} for {type_name} in share/{package}/msg under any of: {searched}"
        " (source a ROS 2 Jazzy setup or install the interface package)"
    )


@functools.cache
def msg_text(type_name: str) -> str:
    """The installed ``.msg`` text of one type (``package/msg/Name`` or ``package/Name``)."""
    return _interface_file(type_name, ".msg").read_text()


def dependencies(text: str, package: str) -> list[str]:
    """Non-primitive field types of a ``.msg`` text, sorted, package-qualified.

    Constants (``uint8 A=1``) have primitive types and are skipped like other primitives.
    """
    found: set[str] = set()
    for line in text.splitlines():
        match = _FIELD_TYPE.match(line.split("#", 1)[0])
        if match is None:
            continue
        field_type = match.group(1)
        if field_type in PRIMITIVE_TYPES:
            continue
        if field_type == "Header":  # the ROS 1 shorthand, still accepted by rosidl
            field_type = "std_msgs/Header"
        found.add(field_type if "/" in field_type else f"{package}/{field_type}")
    return sorted(found)


@functools.cache
def full_definition(type_name: str) -> str:
    """The complete ``ros2msg`` definition of ``type_name`` (see the module doc).

    Raises:
        SchemaError: when the type or one of its dependencies is not installed.
    """
    seen: set[str] = set()

    def walk(name: str, depth: int) -> str:
        if depth > 32:
            raise SchemaError(f"definition of {type_name}: dependencies nested too deep")
        text = msg_text(name)
        package, _ = _split(name)
        out = text
        for dep in dependencies(text, package):
            if dep not in seen:
                seen.add(dep)
                out += f"\n{DELIMITER}\nMSG: {dep}\n" + walk(dep, depth + 1)
        return out

    return walk(type_name, 0)


@functools.cache
def type_hash(type_name: str) -> str:
    """The ``RIHS01_<sha256>`` type hash of ``type_name`` ("" when rosidl did not install one)."""
    try:
        path = _interface_file(type_name, ".json")
    except SchemaError:
        return ""
    package, name = _split(type_name)
    wanted = f"{package}/msg/{name}"
    for entry in json.loads(path.read_text()).get("type_hashes", []):
        if entry.get("type_name") == wanted:
            return str(entry["hash_string"])
    return ""
