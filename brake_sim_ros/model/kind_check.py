"""Whether a defect kind's catalogue entry carries every part the product reads from it,
and adding one to the catalogue.

:func:`missing_parts` lists what an entry lacks (empty: complete); :func:`register` refuses
an entry that lacks a part, and the completeness test runs it over every entry.
It reads the fidelity levels, the compiled model's growth ids and the scenario loader's
one table (the drum's harmonics), so that the catalogue itself stays pure data.

Pure logic: no files.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator
from contextlib import contextmanager

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.catalogue import (
    ACTUATION_EFFECTS,
    DRUM_KIND,
    GROWTH_LAWS,
    KIND_BY_NAME,
    KINDS,
    DefectField,
    DefectKind,
)
from brake_sim_ros.model.fidelity import LEVEL_BY_NAME
from brake_sim_ros.model.line_kinds import LINE

_NAME = re.compile(r"[a-z][a-z0-9_]{0,63}")
# the compiled model's growth ids (model/growth.py apply), by layout's GK_* names
GROWTH_IDS = frozenset(v for k, v in vars(L).items() if k.startswith("GK_"))
# the one law whose severity the compiled model integrates as a state: a lining's wear
_STATE_LAWS = {"friction_work": L.GK_WEAR}


def _field_parts(f: DefectField, attribute: bool) -> list[str]:
    out = []
    if not _NAME.fullmatch(f.name):
        out.append(f"field {f.name!r}: a name of a-z 0-9 _ (a scenario key)")
    if not f.unit or not f.description:
        out.append(f"field {f.name!r}: a unit and a description")
    numbers = (f.low, f.high, f.default)
    if not all(math.isfinite(x) for x in numbers) or not f.low <= f.default <= f.high:
        out.append(f"field {f.name!r}: finite low <= default <= high")
    if attribute and not _NAME.fullmatch(f.attribute):
        out.append(f"field {f.name!r}: its attribute's name in the ground truth")
    return out


def _range_parts(kind: DefectKind) -> list[str]:
    numbers = (kind.minimum, kind.maximum, kind.service_limit, kind.healthy_value)
    if not all(math.isfinite(x) for x in numbers):
        return ["finite minimum, maximum, service_limit and healthy_value"]
    out = []
    if not kind.minimum <= 0.0 <= kind.maximum or kind.minimum == kind.maximum:
        out.append("a range minimum <= 0 <= maximum (0: healthy), not empty")
    if kind.service_limit == 0.0 or not kind.minimum <= kind.service_limit <= kind.maximum:
        out.append("a service_limit in the range, not 0 (a severity sweep ends there)")
    return out


def _behaviour_parts(kind: DefectKind) -> list[str]:
    out = []
    if not kind.levels or not kind.levels <= set(LEVEL_BY_NAME):
        out.append(f"fidelity levels: a non-empty subset of {sorted(LEVEL_BY_NAME)}")
    if kind.growth_id is not None and kind.growth_id not in GROWTH_IDS:
        out.append(f"a growth_id the compiled model applies ({sorted(GROWTH_IDS)}) or None")
    if "step" not in kind.laws or not set(kind.laws) <= set(GROWTH_LAWS):
        out.append(f"growth laws: 'step' and others of {list(GROWTH_LAWS)}")
    for law, growth_id in _STATE_LAWS.items():
        if law in kind.laws and kind.growth_id != growth_id:
            out.append(f"growth law {law!r} only with the growth id the model integrates")
    if not callable(kind.packing):
        out.append("a packing: how it enters the kernels' parameters (model/packing.py)")
    if kind.actuation not in ACTUATION_EFFECTS:
        out.append(f"an actuation effect of {list(ACTUATION_EFFECTS)}")
    if kind.tied and not kind.on_shoes:
        out.append("tied shoes only for a kind on the shoes")
    if kind.table and kind.name != DRUM_KIND:
        out.append("a number for its severity (the scenario loader reads one table: harmonics)")
    return out


def missing_parts(kind: DefectKind) -> list[str]:
    """What ``kind``'s entry lacks, one phrase per part (empty: complete): a name, its
    locations (both shoes, the drum or the line), a unit, range, limit, description, scenario key
    and service limit, its fields (each named, with a unit, a description and a default
    in its range), fidelity levels, growth rules, its packing and an actuation effect the
    model knows."""
    out = []
    if not _NAME.fullmatch(kind.name) or not _NAME.fullmatch(kind.scenario_key):
        out.append("a name and a scenario key of a-z 0-9 _")
    if kind.locations not in (tuple(L.SIDES), ("drum",), (LINE,)):
        out.append(f"locations {list(L.SIDES)}, ['drum'] or ['{LINE}']")
    if not kind.unit or not kind.limit or not kind.description:
        out.append("a unit, a limit (why the range ends there) and a description")
    out += _range_parts(kind)
    for f in kind.fields():
        out += _field_parts(f, f in kind.attributes)
    names = [f.name for f in kind.fields()]
    if len(set(names)) != len(names):
        out.append("distinct field names")
    out += _behaviour_parts(kind)
    return out


def register(kind: DefectKind) -> None:
    """Add ``kind`` to the catalogue (after the built-in kinds): the scenario loader, the
    node's parameters, campaign axes, the label columns and ``brake-sim defects`` take it
    from here. Refused, in one line: a name, key or field already taken, or an entry that
    lacks a part (:func:`missing_parts`)."""
    if kind.name in KIND_BY_NAME:
        raise ParameterError(f"defect kind {kind.name!r} is registered already")
    taken = {f.name for k in KINDS for f in k.fields()} | {k.scenario_key for k in KINDS}
    clash = sorted(taken & ({f.name for f in kind.fields()} | {kind.scenario_key}))
    if clash:
        raise ParameterError(f"defect kind {kind.name!r}: keys {clash} are taken by another kind")
    missing = missing_parts(kind)
    if missing:
        raise ParameterError(f"defect kind {kind.name!r} lacks: {'; '.join(missing)}")
    KINDS.append(kind)
    KIND_BY_NAME[kind.name] = kind


def unregister(name: str) -> None:
    """Take the kind ``name`` out of the catalogue (a kind :func:`register` added)."""
    KINDS.remove(KIND_BY_NAME.pop(name))


@contextmanager
def registered(kind: DefectKind) -> Iterator[DefectKind]:
    """``kind`` in the catalogue for the ``with`` block (a test's kind)."""
    register(kind)
    try:
        yield kind
    finally:
        unregister(kind.name)
