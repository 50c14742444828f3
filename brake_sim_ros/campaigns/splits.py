"""Leak-free splits: whole units to train, validation and test; held-out values to test.

A unit (one physical brake) is never in two splits: its runs share its build, so a
classifier tested on a unit it was trained on looks better than it is (CWRU's leakage).
A held-out value (of any varied column) appears only in the test split: its runs are
made on test units only, and not at all on the other units.

Pure logic: no files.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from brake_sim_ros.campaigns.axes import SPLITS_STREAM, Value

SPLITS = ("train", "validation", "test")


@dataclass(frozen=True)
class HeldOut:
    """Runs whose ``column`` takes one of ``values`` (or, for a number, lies within
    ``[minimum, maximum]``) go to the test split only."""

    column: str
    values: tuple[Value, ...] = ()
    minimum: float | None = None
    maximum: float | None = None

    def matches(self, columns: Mapping[str, Value]) -> bool:
        value = columns.get(self.column)
        if value is None:
            return False
        if any(_same(value, v) for v in self.values):
            return True
        if self.minimum is None and self.maximum is None:
            return False
        if isinstance(value, bool) or not isinstance(value, int | float):
            return False
        lo = -math.inf if self.minimum is None else self.minimum
        hi = math.inf if self.maximum is None else self.maximum
        return lo <= value <= hi


def value_kind(value: object) -> str:
    """``"bool"``, ``"number"`` or ``"string"``: the kinds of value a column takes."""
    if isinstance(value, bool):
        return "bool"
    return "number" if isinstance(value, int | float) else "string"


def held_out_kind_problem(
    values: Sequence[Value], ranged: bool, kinds: set[str]
) -> tuple[str, object, str] | None:
    """What makes a held-out rule hold nothing out by its kinds, as ``(key suffix, value,
    what is allowed)``, or None: a value of a kind the column never takes, a range on a
    column of no numbers."""
    for i, value in enumerate(values):
        if kinds and value_kind(value) not in kinds:
            return f".values[{i}]", value, f"a value of the column's kind ({sorted(kinds)})"
    if ranged and kinds and "number" not in kinds:
        return "", "min/max", f"'values' (the column holds {sorted(kinds)}, no numbers)"
    return None


def _same(a: Value, b: Value) -> bool:
    if isinstance(a, bool) or isinstance(b, bool):
        return a is b
    if isinstance(a, str) or isinstance(b, str):
        return a == b
    return float(a) == float(b)


def unit_counts(n_units: int, fractions: Mapping[str, float]) -> dict[str, int]:
    """Units per split: the largest-remainder rounding of ``n_units * fraction``, with at
    least one unit in every split of non-zero fraction.

    Raises:
        ValueError: fewer units than splits of non-zero fraction.
    """
    wanted = [s for s in SPLITS if fractions.get(s, 0.0) > 0.0]
    if n_units < len(wanted):
        raise ValueError(
            f"{n_units} unit(s) cannot fill the {len(wanted)} splits {wanted}: allowed at least"
            f" {len(wanted)} units (a unit is in one split only)"
        )
    exact = {s: n_units * fractions.get(s, 0.0) for s in SPLITS}
    counts = {s: (max(1, math.floor(exact[s])) if s in wanted else 0) for s in SPLITS}
    while sum(counts.values()) > n_units:  # the minimum of one took too many
        s = max((s for s in wanted if counts[s] > 1), key=lambda s: counts[s] - exact[s])
        counts[s] -= 1
    by_remainder = sorted(wanted, key=lambda s: (exact[s] - counts[s], -SPLITS.index(s)))
    while sum(counts.values()) < n_units:
        counts[by_remainder.pop()] += 1
        if not by_remainder:
            by_remainder = sorted(wanted, key=lambda s: -SPLITS.index(s))
    return counts


def assign_units(
    unit_ids: Sequence[str], fractions: Mapping[str, float], seed: int
) -> dict[str, str]:
    """Each unit's split: the units shuffled by the campaign seed, then dealt out in
    :func:`unit_counts`' numbers (train first)."""
    counts = unit_counts(len(unit_ids), fractions)
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(SPLITS_STREAM,)))
    order = [unit_ids[i] for i in rng.permutation(len(unit_ids))]
    out, start = {}, 0
    for split in SPLITS:
        for unit in order[start : start + counts[split]]:
            out[unit] = split
        start += counts[split]
    return out


def leaks(rows: Iterable[Mapping[str, Value]], held_out: Sequence[HeldOut] = ()) -> list[str]:
    """Leakage in a manifest's rows (each with ``unit_id``, ``split`` and the varied
    columns): a unit in two splits, a held-out value outside test, an unknown split. One
    line per problem, empty when leak-free."""
    problems: list[str] = []
    seen: dict[str, set[str]] = {}
    for row in rows:
        split = str(row["split"])
        if split not in SPLITS:
            problems.append(f"run {row.get('run_id')}: split {split!r} is not one of {SPLITS}")
        seen.setdefault(str(row["unit_id"]), set()).add(split)
        for rule in held_out:
            if split != "test" and rule.matches(row):
                problems.append(
                    f"run {row.get('run_id')} ({split}): held-out {rule.column} value outside test"
                )
    for unit, splits in sorted(seen.items()):
        if len(splits) > 1:
            problems.append(f"unit {unit} is in the splits {sorted(splits)}")
    return problems


def idle_rule(
    rows: Sequence[Mapping[str, Value]], held_out: Sequence[HeldOut]
) -> tuple[int, str] | None:
    """The first held-out rule that matches none of ``rows`` (a campaign's condition
    points as manifest columns): ``(its index, why)``; None when every rule holds
    something out. Such a rule holds nothing out while the dataset claims it does."""
    for i, rule in enumerate(held_out):
        if any(rule.matches(row) for row in rows):
            continue
        seen = sorted({str(row[rule.column]) for row in rows if rule.column in row})
        shown = ", ".join(seen[:6]) + (", ..." if len(seen) > 6 else "")
        hint = (
            " (defect_severity is in each kind's unit; a fraction of the service limit is"
            " defect_severity_fraction)"
            if rule.column == "defect_severity"
            else ""
        )
        return i, f"matches no run; allowed values {rule.column} takes: {shown}{hint}"
    return None
