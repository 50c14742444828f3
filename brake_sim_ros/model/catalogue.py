"""The defect catalogue: every kind of brake defect the model knows, as data, and the
ground truth of a brake's condition as a list of active defects.

Each kind has a name, the locations it can sit at, a severity in a physical unit (0 for a
healthy brake, so a label column reads 0 where the defect is absent), the range the model
accepts and a line on what it changes. The ground truth of a brake (``Defects.active``,
:mod:`.defects`) is a list of :class:`ActiveDefect`, one per kind and location in force,
so a consumer (the ``DefectState`` message, Parquet label columns, file metadata, a
scorer) needs no change when a kind is added here.

Time: every defect in force today is a step at the start of the run (onset 0 s, growth
``step``): a run keeps its defects until a reset. The onset and growth fields are part of
the description so that defects that grow during a run carry them without a new format.

Pure data and logic: no numerics, no files.
"""

from __future__ import annotations

from dataclasses import dataclass

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.layout import SIDES

GROWTH_LAWS: tuple[str, ...] = ("step",)  # how a severity evolves after its onset
DRUM_KIND = "drum_out_of_round"


@dataclass(frozen=True)
class DefectKind:
    """One kind of defect.

    Attributes:
        name: the kind's name in ground truth, label columns and the CLI.
        locations: where it can sit (a shoe: ``left``/``right``; ``drum``).
        unit: the severity's unit.
        minimum, maximum: the severities the model accepts, in ``unit`` (the limit's
            reason is in ``limit``).
        limit: why the range stops there.
        description: what it changes in the brake, and the sign convention.
        scenario_key: the key that sets it in a scenario's ``[defects.<location>]`` and
            the node parameter ``<location>_<key>``.
        healthy_value: what that key reads on a healthy brake (the value set is
            ``healthy_value + severity``).
        service_limit: a size seen in service (shared figures: the study's cases), in
            ``unit``, signed: where a severity sweep ends.
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
    healthy_value: float = 0.0

    def check(self, severity: float, where: str = "") -> None:
        """Refuse a severity outside the range, in one line naming the limit."""
        if not self.minimum <= severity <= self.maximum:
            h = self.healthy_value
            raise ParameterError(
                f"defect {where}{self.scenario_key}={h + severity:g} is invalid: allowed"
                f" {h + self.minimum:g} to {h + self.maximum:g} ({self.limit})"
            )


KINDS: tuple[DefectKind, ...] = (
    DefectKind(
        name="pivot_radius_change",
        locations=SIDES,
        unit="%",
        minimum=-20.0,
        maximum=20.0,
        limit="the range the shoe's assembly on its abutments is built and tested for",
        description=(
            "the anchor pin's distance from the drum centre, in % of the nominal radius;"
            " positive moves the pin outward, toward the drum"
        ),
        scenario_key="pivot_radius_change_pct",
        service_limit=3.0,  # the study's cases: +-3 %
    ),
    DefectKind(
        name="initial_angle",
        locations=SIDES,
        unit="deg",
        minimum=-10.0,
        maximum=10.0,
        limit="the range the shoe's assembly on its abutments is built and tested for",
        description=(
            "the shoe's assembled angle about its pivot; negative tilts it toward the"
            " drum centre, away from the drum"
        ),
        scenario_key="initial_angle_deg",
        service_limit=-2.0,  # the study's cases: -2 deg
    ),
    DefectKind(
        name="actuation_share_change",
        locations=SIDES,
        unit="1",
        minimum=-0.5,
        maximum=0.5,
        limit="a shoe's share of the total force lies between 0 and 1",
        description=(
            "the shoe's share of the total actuation force minus the healthy 0.5 (a"
            " scenario sets the share itself: 0.55 is +0.05); the shares sum to 1"
        ),
        scenario_key="actuation_share",
        service_limit=0.05,  # the study's cases: +-10 % of the share (0.55)
        healthy_value=0.5,
    ),
    DefectKind(
        name=DRUM_KIND,
        locations=("drum",),
        unit="um",
        minimum=0.0,
        maximum=3500.0,
        limit=(
            "the peak runout stays below the gap between the resting shoes and the drum"
            " (the running clearance, 3.5 mm nominal, checked at assembly) and the surface"
            " slope sum k a_k / R0 at most 0.05"
        ),
        description=(
            "drum radius harmonics r(psi) = R0 + sum a_k cos(k psi + phi_k), psi in the"
            " drum's frame; the severity is the peak runout sum a_k, each harmonic's"
            " amplitude and phase are attributes (order_<k>_amplitude_um,"
            " order_<k>_phase_deg)"
        ),
        scenario_key="harmonics",
        service_limit=150.0,  # service runouts 50-150 um (about 50 um a common limit)
    ),
)
KIND_BY_NAME: dict[str, DefectKind] = {k.name: k for k in KINDS}


@dataclass(frozen=True)
class ActiveDefect:
    """One defect in force.

    Attributes:
        kind: a name from :data:`KINDS`.
        location: where it sits (one of the kind's locations).
        severity: its size now, in the kind's unit (non-zero).
        unit: the kind's unit.
        onset_s: simulated time it started, s.
        growth: how it evolves after the onset (:data:`GROWTH_LAWS`).
        growth_rate: the law's rate, unit/s (0 for a step).
        attributes: what else describes it, by name (each name ends in its unit), e.g.
            the amplitude and phase of each harmonic of a drum out of round.
    """

    kind: str
    location: str
    severity: float
    unit: str
    onset_s: float = 0.0
    growth: str = "step"
    growth_rate: float = 0.0
    attributes: tuple[tuple[str, float], ...] = ()

    @property
    def label(self) -> str:
        """One readable line, e.g. ``left pivot_radius_change +3 %``."""
        unit = "" if self.unit == "1" else f" {self.unit}"
        return f"{self.location} {self.kind} {self.severity:+g}{unit}"

    def as_dict(self) -> dict[str, object]:
        return {
            "kind": self.kind,
            "location": self.location,
            "severity": self.severity,
            "unit": self.unit,
            "onset_s": self.onset_s,
            "growth": self.growth,
            "growth_rate": self.growth_rate,
            "attributes": dict(self.attributes),
        }


def label_column(kind: DefectKind, location: str) -> str:
    """The per-sample label column of a kind at a location: its severity, 0 if absent."""
    return f"defect:{kind.name}:{location} [{kind.unit}]"


def label_columns() -> tuple[str, ...]:
    """Every label column, in catalogue order."""
    return tuple(label_column(k, loc) for k in KINDS for loc in k.locations)
