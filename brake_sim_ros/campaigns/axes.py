"""What a campaign varies: axes of scenario values and of catalogue defects, expanded
into condition points (a grid of the listed values times the drawn points).

An axis either lists its values (``values``, or ``linspace = [start, stop, num]``): the
listed axes form a cartesian grid; or it draws from ``uniform = [low, high]``: the drawn
axes share ``[draws]`` points (independent uniform ``"random"`` draws or a Latin hypercube
``"lhs"``, :mod:`scipy.stats.qmc`), from the campaign seed. Every grid point is crossed
with every drawn point.

Pure logic: no files, no numerics beyond the draws.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any

import numpy as np

from brake_sim_ros.model.catalogue import KIND_BY_NAME, LINE, fields_at, kinds_at
from brake_sim_ros.model.defects import Defects

DEFECT_AXIS = "defect"
# the manifest columns a defect axis fills (kind "healthy" and location "" for no defect):
# ``defect_severity`` in the kind's unit (``brake-sim defects``), signed as its service
# limit; ``defect_severity_fraction`` that severity over the kind's service limit (the
# value of the axis's ``severities``, 0 when healthy); ``defect_repeat`` which of the
# axis's ``healthy = N`` healthy runs (0 to N - 1; 0 for a defect)
DEFECT_COLUMNS = (
    "defect_kind",
    "defect_location",
    "defect_severity",
    "defect_severity_fraction",
    "defect_repeat",
)
# those of them that hold numbers (the rest hold strings)
DEFECT_NUMBER_COLUMNS = ("defect_severity", "defect_severity_fraction", "defect_repeat")
# a column derived from the others: not part of a run's identity (its seed)
DERIVED_COLUMNS = ("defect_severity_fraction",)
HEALTHY = "healthy"
DRAW_METHODS = ("random", "lhs")
# spawn keys of the campaign seed's streams (run seeds use the run's identity instead)
DRAWS_STREAM = 1
SPLITS_STREAM = 2

Value = bool | int | float | str


@dataclass(frozen=True)
class DefectChoice:
    """One value of a defect axis: a single catalogue defect, or a healthy brake.

    Attributes:
        kind: a catalogue kind name, or ``"healthy"``.
        location: one of the kind's locations ("" when healthy).
        severity: in the kind's unit (0 when healthy).
        fraction: ``severity`` over the kind's service limit (0 when healthy).
        repeat: which healthy run of the axis's ``healthy = N`` (0 for a defect): each
            its own run, with its own seed.
    """

    kind: str
    location: str
    severity: float
    fraction: float = 0.0
    repeat: int = 0

    def defects(self) -> Defects:
        if self.kind == HEALTHY:
            return Defects()
        return Defects.single(self.kind, self.location, self.severity)

    def columns(self) -> dict[str, Value]:
        values = (self.kind, self.location, self.severity, self.fraction, self.repeat)
        return dict(zip(DEFECT_COLUMNS, values, strict=True))


@dataclass(frozen=True)
class Axis:
    """One varied scenario value.

    Attributes:
        name: its manifest column.
        key: the dotted path into the scenario's TOML data it sets (``actuation.peak_force_n``).
        values: the listed values (empty when drawn).
        uniform: ``(low, high)`` of a drawn axis, in the key's unit; None when listed.
    """

    name: str
    key: str
    values: tuple[Value, ...] = ()
    uniform: tuple[float, float] | None = None


@dataclass(frozen=True)
class DefectAxis:
    """The brake's defect, one catalogue defect at a time (or healthy)."""

    choices: tuple[DefectChoice, ...]
    name: str = DEFECT_AXIS


AnyAxis = Axis | DefectAxis


def defect_choices(
    kinds: tuple[str, ...], fractions: tuple[float, ...], healthy: bool | int
) -> tuple[DefectChoice, ...]:
    """Every kind at each of its locations at each severity, a severity being a fraction
    of the kind's service limit (``catalogue.DefectKind.service_limit``, signed), after
    ``healthy`` healthy brakes (True: one; each its own run and seed), so that a dataset
    can hold minutes of healthy operation beside every defect."""
    out = [DefectChoice(HEALTHY, "", 0.0, 0.0, i) for i in range(int(healthy))]
    for name in kinds:
        kind = KIND_BY_NAME[name]
        for location in kind.locations:
            out += [DefectChoice(name, location, f * kind.service_limit, f) for f in fractions]
    return tuple(out)


def defects_table(defects: Defects) -> dict[str, Any]:
    """``defects`` as a scenario's ``[defects]`` table (the inverse of the scenario
    loader's reading): each shoe's catalogue fields that differ from a healthy shoe, the
    drum's harmonics and the fields of each drum defect present, and the line's fields
    that differ from a sound line (``fields_at``)."""
    table: dict[str, Any] = {}
    for side in ("left", "right"):
        shoe = getattr(defects, side)
        changed = {
            f.name: float(getattr(shoe, f.name))
            for f in fields_at(side)
            if getattr(shoe, f.name) != f.default
        }
        if changed:
            table[side] = changed
    drum: dict[str, Any] = {}
    if defects.drum.harmonics:
        drum["harmonics"] = [
            {"order": h.order, "amplitude_um": float(h.amplitude_um), "phase_deg": h.phase_deg}
            for h in defects.drum.harmonics
        ]
    for kind in kinds_at("drum"):
        if defects.drum.severity_of(kind) and not kind.table:
            for f in kind.fields():
                drum[f.name] = float(getattr(defects.drum, f.name))
    if drum:
        table["drum"] = drum
    line = {
        f.name: float(getattr(defects.line, f.name))
        for f in fields_at(LINE)
        if getattr(defects.line, f.name) != f.default
    }
    if line:
        table[LINE] = line
    return table


def drawn_points(
    axes: tuple[AnyAxis, ...], method: str, n: int, seed: int
) -> list[dict[str, float]]:
    """``n`` points of the drawn axes (``uniform``), unit-cube draws scaled to each range;
    empty when no axis is drawn."""
    drawn = [a for a in axes if isinstance(a, Axis) and a.uniform is not None]
    if not drawn:
        return [{}]
    from scipy.stats import qmc

    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(DRAWS_STREAM,)))
    if method == "lhs":
        cube = qmc.LatinHypercube(d=len(drawn), seed=rng).random(n)
    else:
        cube = rng.random((n, len(drawn)))
    return [
        {
            a.name: float(a.uniform[0] + u * (a.uniform[1] - a.uniform[0]))
            for a, u in zip(drawn, row, strict=True)
        }
        for row in cube
    ]


def condition_points(
    axes: tuple[AnyAxis, ...], method: str, n: int, seed: int
) -> list[dict[str, Value | DefectChoice]]:
    """Every condition of a campaign: the grid of listed values (axis order, the last
    axis varying fastest) crossed with the drawn points; axis name -> value."""
    listed = [a for a in axes if isinstance(a, DefectAxis) or a.uniform is None]
    options = [a.choices if isinstance(a, DefectAxis) else a.values for a in listed]
    draws = drawn_points(axes, method, n, seed)
    return [
        {**dict(zip((a.name for a in listed), combo, strict=True)), **drawn}
        for combo in itertools.product(*options)
        for drawn in draws
    ]


def point_columns(point: dict[str, Value | DefectChoice]) -> dict[str, Value]:
    """A condition point as manifest columns (a defect choice fills :data:`DEFECT_COLUMNS`)."""
    out: dict[str, Value] = {}
    for name, value in point.items():
        if isinstance(value, DefectChoice):
            out.update(value.columns())
        else:
            out[name] = value
    return out
