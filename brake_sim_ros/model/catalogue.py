"""The defect catalogue: every kind of brake defect the model knows, each entry carrying
its behaviour, and the ground truth of a brake's condition as a list of active defects.

Each kind (:class:`DefectKind`) has a name, the locations it can sit at, a severity in a
physical unit (0 for a healthy brake, so a label column reads 0 where the defect is
absent), the range the model accepts and a line on what it changes; and what the rest of
the product reads from it instead of a table of its own: the numbers a scenario and a
node parameter set (:meth:`DefectKind.fields`: the severity's key and any attributes,
:class:`DefectField`), whether and how it may grow during a run (its id in the compiled
model's growth update, the laws it takes, an initial condition, two tied shoes), the
fidelity levels that represent it and whether it reshapes the actuation. The scenario
loader, the node's parameters, campaign axes, the label columns and ``brake-sim defects``
are generated from :data:`KINDS`; :func:`brake_sim_ros.model.kind_check.register` adds a
kind, checked complete there (:func:`~brake_sim_ros.model.kind_check.missing_parts`).
The records themselves (:class:`DefectKind`, :class:`DefectField`) are :mod:`.defect_kind`'s.

The ground truth of a brake (``Defects.active``, :mod:`.defects`) is a list of
:class:`ActiveDefect`, one per kind and location in force, so a consumer (the
``DefectState`` message, Parquet label columns, file metadata, a scorer) needs no change
when a kind is added here. Onsets and growth laws: :mod:`.growth_law`.

Pure data and logic: no files.
"""

from __future__ import annotations

from dataclasses import dataclass

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model import layout as L
from brake_sim_ros.model import packing
from brake_sim_ros.model.adjuster import ADJUSTER_KIND
from brake_sim_ros.model.defect_kind import DefectField, DefectKind
from brake_sim_ros.model.growth_law import (  # noqa: F401 (re-exported: the catalogue's laws)
    DEFAULT_WEAR_RATE_MM_PER_MJ,
    GROWTH_KEYS,
    GROWTH_LAWS,
    LAW_EXPONENTIAL,
    LAW_FRICTION_WORK,
    LAW_LINEAR,
    LAW_PARAMETERS,
    LAW_STEP,
    MAX_GROWTH_TIME_S,
    MAX_WEAR_RATE_MM_PER_MJ,
    Growth,
    severity_at,
    severity_series,
)
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.model.line_kinds import CIRCUIT_LEVELS, LINE, LINE_KINDS

DRUM_KIND = "drum_out_of_round"
WEAR_KIND = "lining_wear"
FLAT_KIND = "drum_flat"
# Thickness of a new lining, mm: passenger-car drum-brake shoe linings are typically 4-6
# mm thick new (a typical figure, not from TESTBED.md); a wear beyond it is refused.
LINING_THICKNESS_MM = 5.0
# Thickness left at the usual replacement limit, mm: 1.6 mm (1/16 in) above the shoe
# table for bonded linings (a typical workshop figure), so 3.4 mm of wear.
LINING_MINIMUM_MM = 1.6
# Highest pulsation frequency of an actuation, Hz: a hydraulic line's pressure pulsation
# (a pump, ABS modulation) stays far below the contact's kHz dynamics.
MAX_PULSATION_HZ = 1000.0
# The frequency Defects.single gives a pulsation (a severity sweep), Hz: about the ABS
# modulation rate of a wheel (10-20 Hz).
DEFAULT_PULSATION_HZ = 15.0
# The width a flat gets when a scenario names none (and in a severity sweep), deg: about
# 16 mm of arc on a 180 mm drum, a short window as a crack's edge or a local flat is.
DEFAULT_FLAT_WIDTH_DEG = 5.0
# Widest flat, deg: a wider dip is a low lobe, a harmonic (drum_out_of_round).
MAX_FLAT_WIDTH_DEG = 90.0
# the fidelity levels (model/fidelity.py LEVELS), cheapest first
ALL_LEVELS = frozenset({"contact_regime_rigid", "contact_regime", "rigid", "full"})
IMPACT_LEVELS = frozenset({"rigid", "full"})
# what a kind does to a shoe's actuation (DefectKind.actuation): "history" reshapes the
# commanded force history (a delay, lag or pulsation), "release" acts on the force that
# reaches the shoe (a weak return spring); both take the kernel's shaped-force path
ACTUATION_EFFECTS = ("", "history", "release")
# where a defect can sit: a shoe, the drum, the hydraulic line (the service brake's
# circuit: model/line_kinds.py)
LOCATIONS = (*SIDES, "drum", LINE)


# the registry: every kind, in catalogue order (kind_check.register() adds one)
KINDS: list[DefectKind] = [
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
        levels=ALL_LEVELS,
        growth_id=L.GK_PIVOT,
        packing=packing.pack_pivot,
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
        levels=ALL_LEVELS,
        growth_id=None,
        packing=packing.pack_nothing,
        initial_condition=True,
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
        levels=ALL_LEVELS,
        growth_id=L.GK_SHARE,
        packing=packing.pack_share,
        tied=True,
    ),
    DefectKind(
        name="friction_change",
        locations=SIDES,
        unit="%",
        minimum=-90.0,
        maximum=50.0,
        limit=(
            "a lining keeps some friction; +50 % of the nominal 0.285 is 0.43, the top of"
            " drum-brake linings; a shoe that would self-lock (mu h >= d) is refused at"
            " assembly"
        ),
        description=(
            "change of the shoe's lining friction coefficient, in % of the nominal one;"
            " negative for fade (hot) or contamination (oil, water)"
        ),
        scenario_key="friction_change_pct",
        service_limit=-50.0,  # fade and contamination can halve mu (TESTBED.md)
        levels=ALL_LEVELS,  # a coefficient per lining: the same shoe balance
        growth_id=L.GK_FRICTION,
        packing=packing.pack_friction,
    ),
    DefectKind(
        name="actuation_gain_change",
        locations=SIDES,
        unit="%",
        minimum=-90.0,
        maximum=50.0,
        limit="a wheel cylinder that still pushes, up to half again the commanded force",
        description=(
            "change of the force the shoe's wheel cylinder delivers for the commanded one,"
            " in %; negative for low line pressure"
        ),
        scenario_key="actuation_gain_change_pct",
        service_limit=-27.0,  # graded efficiency down to 73 % (UCI hydraulic rig, TESTBED.md)
        levels=ALL_LEVELS,  # a gain, as the share's
        growth_id=L.GK_GAIN,
        packing=packing.pack_gain_change,
    ),
    DefectKind(
        name="actuation_delay",
        locations=SIDES,
        unit="ms",
        minimum=0.0,
        maximum=500.0,
        limit="beyond 0.5 s a brake no longer answers within the 0.36 s expected of a car",
        description="dead time between the commanded actuation and the shoe's, in ms",
        scenario_key="actuation_delay_ms",
        service_limit=100.0,  # a whole healthy hydraulic rise (under 0.1 s, TESTBED.md)
        # a shaped actuation history: the contact-regime levels reuse a balance while the
        # actuation holds, and a delayed, lagging or pulsating force does not hold
        levels=IMPACT_LEVELS,
        growth_id=None,
        packing=packing.pack_delay,
        actuation="history",
    ),
    DefectKind(
        name="actuation_lag",
        locations=SIDES,
        unit="ms",
        minimum=0.0,
        maximum=500.0,
        limit="beyond 0.5 s a brake no longer answers within the 0.36 s expected of a car",
        description=(
            "time constant of a first-order lag of the shoe's actuation (a slow rise), in ms"
        ),
        scenario_key="actuation_lag_ms",
        service_limit=120.0,  # 95 % of a step in 0.36 s, a car's response (TESTBED.md)
        levels=IMPACT_LEVELS,  # a shaped history (actuation_delay)
        growth_id=None,
        packing=packing.pack_lag,
        actuation="history",
    ),
    DefectKind(
        name="actuation_pulsation",
        locations=SIDES,
        unit="%",
        minimum=0.0,
        maximum=100.0,
        limit="a pulsating force still only pushes",
        description=(
            "amplitude of a pulsation of the shoe's actuation force, in % of it, at the"
            " frequency actuation_pulsation_hz (attribute frequency_hz)"
        ),
        scenario_key="actuation_pulsation_pct",
        service_limit=20.0,  # no service figure in TESTBED.md: a clearly felt pulsation
        levels=IMPACT_LEVELS,  # a shaped history (actuation_delay)
        growth_id=L.GK_PULSATION,
        packing=packing.pack_pulsation,
        actuation="history",
        attributes=(
            DefectField(
                "actuation_pulsation_hz",
                "Hz",
                0.0,
                0.0,
                MAX_PULSATION_HZ,
                "the pulsation's frequency, Hz (> 0 with a pulsation)",
                attribute="frequency_hz",
                needed=True,
                present_default=DEFAULT_PULSATION_HZ,
            ),
        ),
    ),
    DefectKind(
        name="return_spring_weakening",
        locations=SIDES,
        unit="%",
        minimum=0.0,
        maximum=100.0,
        limit="a spring loses at most all of its preload (100 %: broken)",
        description=(
            "preload the shoe's return spring has lost, in %; past 67 % (the stop's margin"
            " over the residual line pressure) the shoe drags on the drum without actuation"
        ),
        scenario_key="return_spring_weakening_pct",
        service_limit=100.0,  # a broken spring
        # the spring acts on the force that reaches the shoe in the kernel: the
        # contact-regime levels take the commanded history
        levels=IMPACT_LEVELS,
        growth_id=None,
        packing=packing.pack_spring_release,
        actuation="release",
    ),
    DefectKind(
        name=DRUM_KIND,
        locations=("drum",),
        unit="um",
        minimum=0.0,
        maximum=3500.0,
        limit=(
            "the peak runout stays below the gap between the resting shoes and the drum"
            " (the running clearance, 3.63 mm on the study brake, checked at assembly) and"
            " the surface slope sum k a_k / R0 at most 0.05"
        ),
        description=(
            "drum radius harmonics r(psi) = R0 + sum a_k cos(k psi + phi_k), psi in the"
            " drum's frame; the severity is the peak runout sum a_k, each harmonic's"
            " amplitude and phase are attributes (order_<k>_amplitude_um,"
            " order_<k>_phase_deg)"
        ),
        scenario_key="harmonics",
        service_limit=150.0,  # service runouts 50-150 um (about 50 um a common limit)
        levels=IMPACT_LEVELS,
        growth_id=L.GK_DRUM,
        packing=packing.pack_harmonics,
        speed_dependent=True,
        table=True,
    ),
    DefectKind(
        name=WEAR_KIND,
        locations=SIDES,
        unit="mm",
        minimum=0.0,
        maximum=LINING_THICKNESS_MM,
        limit=f"a new lining is {LINING_THICKNESS_MM:g} mm thick (a typical passenger-car figure)",
        description=(
            "lining thickness the shoe has lost, in mm: the lining surface moves in, the gap"
            " to the drum grows by as much (the shoe turns further before it touches), but"
            " on the service brake, whose self-adjuster takes the wear up in whole steps,"
            " the wear present at the start and, as it grows, at each application"
            " (adjuster_seized: what it failed to); growth friction_work wears it with the"
            " shoe's own friction work"
        ),
        scenario_key="lining_wear_mm",
        # replaced at 1.6 mm left of 5 mm (1/16 in above the table: a typical workshop limit)
        service_limit=LINING_THICKNESS_MM - LINING_MINIMUM_MM,
        # a worn lining is geometry (the lining's radius), as a pivot's place: the same
        # shoe balance; wear that grows is a growth (fidelity.GROWTH_LEVELS)
        levels=ALL_LEVELS,
        growth_id=L.GK_WEAR,
        packing=packing.pack_lining_wear,
        laws=("step", "linear", "exponential", "friction_work"),
    ),
    DefectKind(
        name=ADJUSTER_KIND,
        locations=SIDES,
        unit="mm",
        minimum=0.0,
        maximum=LINING_THICKNESS_MM,
        limit=(f"a new lining is {LINING_THICKNESS_MM:g} mm thick: no more wear to fall behind"),
        description=(
            "lining wear the shoe's self-adjuster has failed to take up (seized), in mm: the"
            " running clearance at rest grows by as much, so the piston travels further and"
            " the circuit takes more fluid before the lining touches (a low pedal, a later"
            " and harder first contact; service brake only)"
        ),
        scenario_key="adjuster_seized_mm",
        # 1 mm: the clearance 0.3 -> 1.3 mm a shoe, 1.9 mm more piston travel and 0.55 ml
        # more fluid a wheel cylinder (scripts/adjuster_figures.py); an estimate of a pedal
        # clearly low that still brakes (workshops adjust at about 1 mm on the diameter)
        service_limit=1.0,
        levels=CIRCUIT_LEVELS,  # the service brake runs the full model only
        growth_id=None,
        packing=packing.pack_adjuster_seized,
        service_only=True,
    ),
    DefectKind(
        name=FLAT_KIND,
        locations=("drum",),
        unit="um",
        minimum=0.0,
        maximum=1000.0,
        limit=(
            "a flat deeper than 1 mm is a broken drum; the flat's slope pi d / (2 w R0) at"
            " most 0.05 (w its half width), as the harmonics'"
        ),
        description=(
            "a local flat or crack edge of the drum: its radius dips by up to the depth over"
            " an angular window (attributes centre_deg, in the drum's frame, and width_deg),"
            " d (1 + cos(pi x / w)) / 2 within x = psi - centre of |x| < w = width / 2; the"
            " severity is the depth"
        ),
        scenario_key="flat_depth_um",
        service_limit=100.0,  # no service figure in TESTBED.md: twice the 50 um runout limit
        # a flat passes the shoe once per revolution: the drum angle and the shoes'
        # dynamics, as the harmonics
        levels=IMPACT_LEVELS,
        growth_id=L.GK_FLAT,
        packing=packing.pack_flat,
        speed_dependent=True,
        attributes=(
            DefectField(
                "flat_centre_deg",
                "deg",
                0.0,
                -360.0,
                360.0,
                "the flat's centre in the drum's frame, deg",
                attribute="centre_deg",
            ),
            DefectField(
                "flat_width_deg",
                "deg",
                DEFAULT_FLAT_WIDTH_DEG,
                0.0,
                MAX_FLAT_WIDTH_DEG,
                "the flat's whole width, deg",
                attribute="width_deg",
                low_open=True,
                limit="a wider dip is a harmonic, drum_out_of_round",
            ),
        ),
    ),
    # the hydraulic line's kinds (a module of their own)
    *LINE_KINDS,
]
KIND_BY_NAME: dict[str, DefectKind] = {k.name: k for k in KINDS}


# per location: the catalogue it was built from, the kinds there and their fields. A shoe's
# or the drum's defects ask for them at every field they read (a campaign's plan builds
# thousands); a kind (un)registered since (kind_check) makes them built again.
_AT: dict[str, tuple[tuple[DefectKind, ...], tuple[DefectKind, ...], tuple[DefectField, ...]]] = {}


def _at(
    location: str,
) -> tuple[tuple[DefectKind, ...], tuple[DefectKind, ...], tuple[DefectField, ...]]:
    catalogue = tuple(KINDS)
    built = _AT.get(location)
    if built is None or built[0] != catalogue:  # same kinds: compared by identity, fast
        kinds = tuple(k for k in catalogue if location in k.locations)
        built = (catalogue, kinds, tuple(f for k in kinds for f in k.fields()))
        _AT[location] = built
    return built


def brake_kinds(circuit: bool) -> tuple[DefectKind, ...]:
    """The kinds a brake can carry, in catalogue order: every kind on a brake with a
    hydraulic circuit (the service brake), all but the service brake's own (the line's and
    the self-adjuster's) without one (the study brake, an ideal force source with a fixed
    clearance, refuses them)."""
    return tuple(k for k in KINDS if circuit or not k.service_only)


def kinds_at(location: str) -> tuple[DefectKind, ...]:
    """The kinds that can sit at ``location`` (:data:`LOCATIONS`), in catalogue order."""
    return _at(location)[1]


def fields_at(location: str) -> tuple[DefectField, ...]:
    """Every number that sets a defect at ``location``, in catalogue order: the fields
    of a shoe (``left``/``right``), of the drum, less its tables (the harmonics), or of
    the line."""
    return _at(location)[2]


def kind_of_field(location: str, name: str) -> DefectKind:
    """The kind whose field ``name`` sits at ``location`` (KeyError if none)."""
    for k in kinds_at(location):
        if any(f.name == name for f in k.fields()):
            return k
    raise KeyError(name)


@dataclass(frozen=True)
class ActiveDefect:
    """One defect in force.

    Attributes:
        kind: a name from :data:`KINDS`.
        location: where it sits (one of the kind's locations).
        severity: its size now (or, describing a whole run, its final size), in the
            kind's unit (non-zero).
        unit: the kind's unit.
        onset_s: simulated time it started, s.
        growth: how it evolves after the onset (:data:`GROWTH_LAWS`).
        growth_rate: the law's rate (:attr:`Growth.rate`): linear the kind's unit per
            second, exponential 1/s (``ln 2 / doubling time``), step 0.
        attributes: what else describes it, by name (each name ends in its unit), e.g.
            the amplitude and phase of each harmonic of a drum out of round; a defect
            that changes in time adds ``final_severity_<unit>`` (and an exponential
            ``start_severity_<unit>``; ``%`` spelled ``pct``, none for a ratio).
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


def refuse_without_circuit(line: object) -> None:
    """Refuse, in one line, a line's defect (``line``: a :class:`.defects.LineDefect`) on a
    brake without a hydraulic circuit (the study brake)."""
    given = [
        f"{k.scenario_key}={getattr(line, k.scenario_key):g}"
        for k in kinds_at(LINE)
        if getattr(line, k.scenario_key) != k.healthy_value
    ]
    if given:
        raise ParameterError(
            f"defect line {', '.join(given)} is invalid on the study brake (an ideal force"
            ' source, no hydraulic circuit): allowed only with brake = "service"'
        )
