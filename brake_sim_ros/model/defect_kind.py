"""The two records of the defect catalogue (:mod:`.catalogue`): a kind of defect
(:class:`DefectKind`) and one number that sets it (:class:`DefectField`), with their
range checks. The catalogue holds the kinds' table and the registry's look-ups.

Pure data and logic: no files.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model import packing
from brake_sim_ros.model.layout import SIDES


@dataclass(frozen=True)
class DefectField:
    """One number a defect kind is set by: its severity's key or an attribute of it.

    Attributes:
        name: the key in a scenario's ``[defects.<location>]``, the field of the shoe or
            drum (:mod:`.defects`) and the node parameter ``defects.<location>.<name>``;
            it ends in its unit.
        unit: its unit.
        default: its value on a healthy brake (an attribute: when the scenario gives none).
        low, high: the values allowed, in ``unit`` (``low_open``: ``low`` itself refused).
        description: what it is, one line (the node parameter's description).
        attribute: its name in the ground truth's attributes ("" for a severity's key).
        needed: an attribute that must be above ``low`` when the defect is present (and
            at ``low`` without it).
        present_default: the value :meth:`.defects.Defects.single` gives an attribute (a
            severity sweep), or None: ``default``.
        limit: why the range stops there (in the refusal).
    """

    name: str
    unit: str
    default: float
    low: float
    high: float
    description: str
    attribute: str = ""
    needed: bool = False
    present_default: float | None = None
    low_open: bool = False
    limit: str = ""

    def check(self, value: float, kind: str, present: bool, where: str = "") -> None:
        """Refuse ``value`` outside the range (or a needed attribute at ``low`` while the
        defect ``kind`` is ``present``), in one line naming what is allowed."""
        low_ok = value > self.low if self.low_open else value >= self.low
        if self.needed and present and value == self.low:
            low_ok = False
        if low_ok and value <= self.high:
            return
        low = f"> {self.low:g}" if self.low_open or self.needed else f"{self.low:g}"
        why = f" ({self.limit})" if self.limit else ""
        if self.needed:
            why = f" while {kind} is present ({self.low:g} without it){why}"
        raise ParameterError(
            f"defect {where}{self.name}={value:g} is invalid: allowed {low} to"
            f" {self.high:g} {self.unit}{why}"
        )


@dataclass(frozen=True)
class DefectKind:
    """One kind of defect, with what the product reads from it.

    Attributes:
        name: the kind's name in ground truth, label columns and the CLI.
        locations: where it can sit (a shoe: ``left``/``right``; ``drum``; ``line``, the
            service brake's hydraulic circuit).
        unit: the severity's unit.
        minimum, maximum: the severities the model accepts, in ``unit`` (the limit's
            reason is in ``limit``).
        limit: why the range stops there.
        description: what it changes in the brake, and the sign convention.
        scenario_key: the key that sets it in a scenario's ``[defects.<location>]`` and
            the node parameter ``defects.<location>.<key>``.
        service_limit: a size seen in service (shared figures: the study's cases), in
            ``unit``, signed: where a severity sweep (a campaign's defect axis) ends.
        levels: the fidelity levels that represent it (:data:`ALL_LEVELS`; the reason
            beside the entry).
        growth_id: its id in the compiled model's growth update (``layout.GK_*``,
            :func:`brake_sim_ros.model.growth.apply`), or None: it cannot change during a
            run (only a step at 0 s).
        packing: how it enters the kernels' packed parameter vector: a function of a
            :class:`.packing.PackSite` that writes its slots at one location, for any
            severity (:mod:`.packing`; :func:`.assembly.pack` calls it).
        healthy_value: what ``scenario_key`` reads on a healthy brake (the value set is
            ``healthy_value + severity``).
        attributes: the other numbers that describe it (:class:`DefectField`), e.g. a
            pulsation's frequency or a flat's width.
        laws: the growth laws it takes (:data:`GROWTH_LAWS`).
        initial_condition: it acts only through the state at t = 0: only a step at 0 s.
        tied: the two shoes' severities are tied (opposite): a scenario states one shoe.
        actuation: what it does to the shoe's actuation (:data:`ACTUATION_EFFECTS`).
        speed_dependent: its effect on a shoe follows the drum speed (no one-shoe model).
        table: its severity is not one number but a table of the scenario (a drum's
            harmonics): no node parameter, read by :mod:`brake_sim_ros.scenarios.defect_tables`.
        service_only: only the service brake has what it acts on (its hydraulic circuit,
            its self-adjuster): the study brake refuses it (:func:`.catalogue.brake_kinds`).
    """

    name: str
    locations: tuple[str, ...]
    unit: str
    minimum: float
    maximum: float
    limit: str
    description: str
    scenario_key: str
    service_limit: float
    levels: frozenset[str]
    growth_id: int | None
    packing: Callable[[packing.PackSite], None]
    healthy_value: float = 0.0
    attributes: tuple[DefectField, ...] = ()
    laws: tuple[str, ...] = ("step", "linear", "exponential")
    initial_condition: bool = False
    tied: bool = False
    actuation: str = ""
    speed_dependent: bool = False
    table: bool = False
    service_only: bool = False

    def check(self, severity: float, where: str = "") -> None:
        """Refuse a severity outside the range, in one line naming the limit."""
        if not self.minimum <= severity <= self.maximum:
            h = self.healthy_value
            raise ParameterError(
                f"defect {where}{self.scenario_key}={h + severity:g} is invalid: allowed"
                f" {h + self.minimum:g} to {h + self.maximum:g} ({self.limit})"
            )

    @property
    def severity_field(self) -> DefectField | None:
        """The number that sets the severity (None for a table, :attr:`table`)."""
        if self.table:
            return None
        h = self.healthy_value
        return DefectField(
            self.scenario_key,
            self.unit,
            h,
            h + self.minimum,
            h + self.maximum,
            self.description,
            limit=self.limit,
        )

    def fields(self) -> tuple[DefectField, ...]:
        """Every number that sets it: its severity's key (unless a table), then its
        attributes."""
        first = self.severity_field
        return ((first,) if first is not None else ()) + self.attributes

    @property
    def on_shoes(self) -> bool:
        return set(self.locations) <= set(SIDES)
