"""The numbers of the defects at one place of the brake (a shoe, the drum), by the
catalogue's field names: the storage :class:`~brake_sim_ros.model.defects.ShoeDefect` and
:class:`~brake_sim_ros.model.defects.DrumDefect` share, generated from the catalogue's
entries (:func:`.catalogue.fields_at`), so a kind registered there is a field here.

Pure logic: no files.
"""

from __future__ import annotations

import math

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.catalogue import DefectKind, fields_at, kinds_at


def _finite(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _rebuild(cls: type, values: dict[str, float], extra: dict[str, object]) -> object:
    """Unpickle a :class:`FieldSet` (its own values as given)."""
    return cls(**extra, **values)


class FieldSet:
    """The numbers of the defects at one place (a shoe, the drum), by field name: the
    catalogue's fields there (:func:`.catalogue.fields_at`), each read as an attribute
    (``shoe.actuation_lag_ms``). Built from keyword values (the rest take their
    defaults: a healthy brake); immutable; equal when every field is. Each kind's
    severity and attributes are checked against its catalogue entry."""

    _LOCATION = "left"  # where its fields come from (both shoes have the same)
    _WHAT = "shoe"

    def __init__(self, **values: float) -> None:
        known = {f.name for f in fields_at(self._LOCATION)}
        for name, value in values.items():
            if name not in known:
                raise ParameterError(
                    f"{self._WHAT} defect {name}={value!r} is invalid: allowed one of the"
                    f" {self._WHAT}'s fields {sorted(known)} (brake-sim defects)"
                )
            if not _finite(value):
                raise ParameterError(f"defect {name}={value!r} is invalid: allowed a finite number")
        object.__setattr__(self, "_given", dict(values))
        for kind in kinds_at(self._LOCATION):
            severity = self.severity_of(kind)
            if not kind.table:  # a table's bound needs the assembled brake (assembly.pack)
                kind.check(severity)
            for f in kind.attributes:
                f.check(float(getattr(self, f.name)), kind.name, severity != 0.0)

    def __getattr__(self, name: str) -> float:
        if name.startswith("_"):
            raise AttributeError(name)
        given = object.__getattribute__(self, "_given")
        if name in given:
            return given[name]
        for f in fields_at(self._LOCATION):
            if f.name == name:
                return f.default
        raise AttributeError(f"{type(self).__name__} has no field {name!r}")

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError(f"{type(self).__name__} is immutable: use replace()")

    def values(self) -> dict[str, float]:
        """Every field's value, by name, in catalogue order."""
        return {f.name: getattr(self, f.name) for f in fields_at(self._LOCATION)}

    def _extra(self) -> dict[str, object]:
        return {}

    def replace(self, **changes: float) -> FieldSet:
        """A copy with the fields ``changes`` names set (checked again)."""
        return type(self)(**self._extra(), **{**self._given, **changes})

    def __eq__(self, other: object) -> bool:
        return (
            type(other) is type(self)
            and self._extra() == other._extra()  # type: ignore[attr-defined]
            and self.values() == other.values()  # type: ignore[attr-defined]
        )

    def __hash__(self) -> int:
        return hash((tuple(self._extra().items()), tuple(self.values().items())))

    def __repr__(self) -> str:
        shown = {**self._extra(), **{k: v for k, v in self._given.items()}}
        inner = ", ".join(f"{k}={v!r}" for k, v in shown.items())
        return f"{type(self).__name__}({inner})"

    def __reduce__(self) -> tuple:
        return (_rebuild, (type(self), dict(self._given), self._extra()))

    def severity_of(self, kind: DefectKind) -> float:
        """The severity of ``kind`` here, in its unit (0: absent): its key's value less
        the healthy one."""
        return float(getattr(self, kind.scenario_key)) - kind.healthy_value

    def severities(self) -> dict[str, float]:
        """The severity of each catalogue kind that can sit here (0: absent), in the
        kind's unit (:mod:`.catalogue`)."""
        return {k.name: self.severity_of(k) for k in kinds_at(self._LOCATION)}

    @property
    def is_healthy(self) -> bool:
        return not any(self.severities().values())

    def attributes_of(self, kind: DefectKind) -> tuple[tuple[str, float], ...]:
        """``kind``'s attributes here by their ground-truth names (:class:`DefectField`)."""
        return tuple((f.attribute, float(getattr(self, f.name))) for f in kind.attributes)


def present_values(kind: DefectKind, severity: float) -> dict[str, float]:
    """The fields of ``kind`` at ``severity`` (its key) with each attribute at the value a
    defect made without one takes (:attr:`DefectField.present_default`)."""
    values = {kind.scenario_key: kind.healthy_value + severity}
    for f in kind.attributes:
        values[f.name] = f.default if f.present_default is None else f.present_default
    return values


def tied_value(kind: DefectKind, shoe: FieldSet) -> dict[str, float]:
    """The key of a tied ``kind`` (:attr:`.catalogue.DefectKind.tied`) on the other shoe
    than ``shoe``: the mirror about the healthy value, ``2 healthy - value`` (the
    actuation shares: ``1 - share``)."""
    return {kind.scenario_key: 2.0 * kind.healthy_value - getattr(shoe, kind.scenario_key)}
