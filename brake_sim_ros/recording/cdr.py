"""CDR payloads of the types this project records, checked before anything uses them.

A recording says which type each channel carries, but that is a claim of the file. Only
the types of the simulator's own topic table (:data:`~brake_sim_ros.stream.topics.TYPES`)
are accepted, and their layout is taken from the definitions installed here
(:mod:`.schemas`), never from the schema text in the file, and no module is ever imported
by a name the file gives.

:func:`check` walks one payload against that layout (XCDR1, as ROS 2 and mcap_ros2 write
it): every length is compared with the bytes left before anything is read, so a truncated
payload or a sequence length of 4 billion is refused at once; strings must be
NUL-terminated UTF-8 within their bound, booleans 0 or 1, and at most
:data:`MAX_TRAILING_BYTES` may follow the last field (alignment padding some
serializers add). It costs one step per field, not per array element: about 20 µs for a
250-sample PivotForceChunk. :func:`decoder` then gives mcap_ros2's decoder built from the
installed definition (used by ``view``, after the check).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from mcap_ros2._dynamic import _for_each_msgdef, generate_dynamic

from brake_sim_ros.recording import schemas
from brake_sim_ros.stream.topics import TYPES

MAX_TRAILING_BYTES = 8
_ENCAPSULATIONS = {b"\x00\x00": False, b"\x00\x01": True}  # CDR big / little endian
_SIZES = {
    "bool": 1, "byte": 1, "char": 1, "int8": 1, "uint8": 1, "int16": 2, "uint16": 2,
    "int32": 4, "uint32": 4, "float32": 4, "int64": 8, "uint64": 8, "float64": 8,
}  # fmt: skip


class CdrError(ValueError):
    """A payload that is not a valid CDR encoding of its type (the message says where)."""


@dataclass(frozen=True)
class _Field:
    name: str
    kind: str  # "prim", "string" or "msg"
    size: int  # bytes of one primitive element (1 for strings and messages: their minimum)
    count: int | None  # None: one value; -1: a sequence (uint32 length first); n: fixed array
    bound: int | None  # sequence bound (T[<=n])
    string_bound: int | None  # string<=n
    nested: str | None  # the nested message type
    is_bool: bool


def _check_type(type_name: str) -> None:
    if type_name not in TYPES:
        raise CdrError(
            f"type {type_name!r} is not one this project records; allowed: "
            + ", ".join(sorted(TYPES))
        )


@functools.cache
def _layouts(type_name: str) -> dict[str, tuple[_Field, ...]]:
    """Field layouts of ``type_name`` and every type it contains (``pkg/Name`` keys)."""
    _check_type(type_name)
    specs: dict[str, Any] = {}

    def keep(_full_name: str, short_name: str, spec: Any) -> None:
        specs[short_name] = spec

    _for_each_msgdef(type_name, schemas.full_definition(type_name), keep)
    layouts: dict[str, tuple[_Field, ...]] = {}
    for short_name, spec in specs.items():
        fields = []
        for f in spec.fields:
            t = f.type
            if t.is_array:
                count = t.array_size if t.is_fixed_size_array() else -1
                bound = t.array_size if t.is_upper_bound else None
            else:
                count, bound = None, None
            if not t.is_primitive_type():
                nested = f"{t.pkg_name}/{t.type}"
                fields.append(_Field(f.name, "msg", 1, count, bound, None, nested, False))
            elif t.type == "string":
                fields.append(
                    _Field(f.name, "string", 4, count, bound, t.string_upper_bound, None, False)
                )
            elif t.type in _SIZES:
                size, is_bool = _SIZES[t.type], t.type == "bool"
                fields.append(_Field(f.name, "prim", size, count, bound, None, None, is_bool))
            else:  # wstring: in no recorded type
                raise CdrError(f"{type_name}: field {f.name} of type {t.type} is not supported")
        layouts[short_name] = tuple(fields)
    return layouts


def _short(type_name: str) -> str:
    package, _, name = type_name.rpartition("/")
    return f"{package.split('/')[0]}/{name}"


class _Walker:
    __slots__ = ("data", "end", "layouts", "little", "offset")

    def __init__(
        self, data: bytes | memoryview, layouts: dict[str, tuple[_Field, ...]], *, little: bool
    ) -> None:
        self.data = data
        self.end = len(data)
        self.layouts = layouts
        self.little = little
        self.offset = 4

    def need(self, n: int, what: str) -> None:
        if n > self.end - self.offset:
            raise CdrError(
                f"{what} needs {n} bytes at byte {self.offset}, {self.end - self.offset} left"
            )

    def align(self, size: int) -> None:
        if size > 1:
            self.offset += -(self.offset - 4) % size

    def uint32(self, what: str) -> int:
        self.align(4)
        self.need(4, what)
        raw = self.data[self.offset : self.offset + 4]
        self.offset += 4
        return int.from_bytes(raw, "little" if self.little else "big")

    def string(self, bound: int | None, what: str) -> None:
        length = self.uint32(what)
        if length == 0:
            raise CdrError(f"{what}: a string of length 0 (allowed: at least the NUL)")
        if bound is not None and length - 1 > bound:
            raise CdrError(f"{what}: {length - 1} characters, allowed at most {bound}")
        self.need(length, what)
        raw = bytes(self.data[self.offset : self.offset + length])
        if raw[-1] != 0 or 0 in raw[:-1]:
            raise CdrError(f"{what}: not a NUL-terminated string")
        try:
            raw[:-1].decode("utf-8")
        except UnicodeDecodeError:
            raise CdrError(f"{what}: not UTF-8") from None
        self.offset += length

    def message(self, short_name: str, path: str) -> None:
        fields = self.layouts.get(short_name)
        if fields is None:
            raise CdrError(f"{path}: no definition of {short_name}")
        if not fields:  # an empty message is one placeholder byte
            self.need(1, path)
            self.offset += 1
            return
        for f in fields:
            what = f"{path}.{f.name}" if path else f.name
            if f.count is None:
                self.one(f, what)
                continue
            n = self.uint32(what) if f.count < 0 else f.count
            if f.bound is not None and n > f.bound:
                raise CdrError(f"{what}: {n} elements, allowed at most {f.bound}")
            if n == 0:
                continue
            if f.kind == "prim":
                self.align(f.size)
                self.need(n * f.size, what)
                if f.is_bool:
                    raw = bytes(self.data[self.offset : self.offset + n])
                    if raw.translate(None, b"\x00\x01"):
                        raise CdrError(f"{what}: booleans other than 0 and 1")
                self.offset += n * f.size
            else:
                self.need(n, what)  # every element takes at least one byte: n is bounded
                for i in range(n):
                    self.one(f, f"{what}[{i}]")

    def one(self, f: _Field, what: str) -> None:
        if f.kind == "prim":
            self.align(f.size)
            self.need(f.size, what)
            if f.is_bool and self.data[self.offset] > 1:
                raise CdrError(f"{what}: boolean {self.data[self.offset]}, allowed 0 or 1")
            self.offset += f.size
        elif f.kind == "string":
            self.string(f.string_bound, what)
        else:
            assert f.nested is not None
            self.message(f.nested, what)


def check(type_name: str, data: bytes | memoryview) -> None:
    """Refuse a payload that is not a complete CDR encoding of ``type_name``.

    Raises:
        CdrError: an unknown type, an unknown encapsulation, a field that runs past the
            end, a length over its bound, a bad string or boolean, or more than
            :data:`MAX_TRAILING_BYTES` after the last field. The message names the field
            and byte offset, never the payload's contents.
    """
    layouts = _layouts(type_name)
    if len(data) < 4:
        raise CdrError(f"{len(data)} bytes: a CDR payload has a 4-byte header")
    little = _ENCAPSULATIONS.get(bytes(data[:2]))
    if little is None:
        raise CdrError(f"encapsulation 0x{bytes(data[:2]).hex()}: allowed CDR (0x0000 or 0x0001)")
    walker = _Walker(data, layouts, little=little)
    walker.message(_short(type_name), "")
    trailing = walker.end - walker.offset
    if trailing > MAX_TRAILING_BYTES:
        raise CdrError(
            f"{trailing} bytes after the last field (allowed at most {MAX_TRAILING_BYTES})"
        )


@functools.cache
def decoder(type_name: str) -> Callable[[bytes], Any]:
    """mcap_ros2's decoder of ``type_name`` built from the installed definition.

    Use it only on payloads :func:`check` accepted.
    """
    _check_type(type_name)
    return generate_dynamic(type_name, schemas.full_definition(type_name))[type_name]
