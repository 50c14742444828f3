"""Unit-to-unit variability: the manufacturing scatter that makes each brake of a fleet
its own, as one table of facts, and the pure functions that draw a unit from it.

A **unit** is one brake as built: the scenario's values (the drawing) plus deviations
drawn, per parameter, from the distribution in :data:`SCATTER` (brake) and
:data:`SENSOR_SCATTER` (its sensors). The unit :data:`NOMINAL_UNIT` is the drawing
itself, with no deviation: :func:`unit_parameters` and :func:`unit_sensors` return their
input object unchanged, bit for bit.

**Distributions.** Every deviation is a normal of standard deviation ``sigma`` truncated
at ``+-limit``: a part outside its tolerance is rejected at inspection, so no unit
carries one, and the truncation is what keeps every unit a valid brake (the tests check
the corners of the tolerance box). Where a drawing tolerance is the source, the process
is taken as just capable (Cp = 1, ``limit = 3 sigma``). A deviation is ``relative`` (the
value times ``1 + d``) or ``absolute`` (the value plus ``d``, in the parameter's SI unit).
The limits apply around the scenario's value: a scenario that sets a parameter sets the
drawing's value, and its units scatter around it (a relative deviation keeps a positive
value positive; an absolute one near a limit of the model may leave it, and the unit is
then refused in one line naming the parameter).

**Each brake its table.** The study brake's is :data:`SCATTER`; the service brake's,
:data:`SERVICE_SCATTER`, scatters what it reads: not the study coupling's stiffness and
damping (its tyre replaces them), its running clearance around its own 0.3 mm with a
self-adjuster's tolerance, and its return spring's preload, its circuit's compliance and
its tyre's presliding stiffness. A key both tables hold draws the same uniform for a unit.

**What does not scatter:** the flywheel inertia and the initial speed (the vehicle's load
and speed: operating conditions, not the brake), the friction smoothing width (a numerical
choice), Poisson's ratios (material constants), the lining arc's ends and the shoe's mass
centre (their tolerances move nothing the model resolves), the tone ring's tooth count and
the wheel-cylinder bore (exact, or far tighter than their effect), and the structure's
modes (no measured figures of their spread exist here). Both shoes share one geometry in
the model (the right mirrors the left), so geometry deviations are common to both shoes;
a left/right difference is what the defects describe.

**Random numbers.** Each deviation has its own generator,
``Generator(PCG64(SeedSequence([seed, DOMAIN, unit key, parameter key])))``, keys the
first 8 bytes (big-endian) of SHA-256 of the unit id and of the parameter's key (for a
sensor ``sensor.<channel>.<field>``), ``DOMAIN`` the same of ``brake_sim_ros unit
scatter``: never Python's ``hash()``, so a unit id and seed give the same bits in any
process. The seed here is the fleet's (a scenario's ``fleet_seed``), not the run's: a unit
is the same brake in every run, whatever noise and conditions the run's seed draws.
One uniform draw per deviation, mapped through the truncated normal's inverse
distribution function, so adding, removing or reordering parameters of the table changes
no other parameter's deviation, and a unit's sensor channel keeps its deviation when other
channels are added. The four-word entropy never equals the sensor noise's two-word
``[seed, channel key]`` (:mod:`.sensors`), so the streams are independent.

Pure: numpy and scipy only.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy import special

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.parameters import BrakeParameters, unit_of
from brake_sim_ros.sensing.sensors import IDEAL, SensorChannel, SensorSet

NOMINAL_UNIT = "nominal"  # the drawing's brake: no scatter


def _key64(text: str) -> int:
    return int.from_bytes(hashlib.sha256(text.encode()).digest()[:8], "big")


def keyed_uniform(seed: int, *names: str) -> float:
    """One uniform draw in [0, 1) of its own generator,
    ``Generator(PCG64(SeedSequence([seed, *keys])))``, each key the first 8 bytes
    (big-endian) of SHA-256 of a name: the same seed and names give the same bits in any
    process; other names, an independent stream."""
    sequence = np.random.SeedSequence([int(seed), *(_key64(n) for n in names)])
    return float(np.random.Generator(np.random.PCG64(sequence)).random())


DOMAIN = "brake_sim_ros unit scatter"


@dataclass(frozen=True)
class Scatter:
    """The distribution of one parameter's deviation between units.

    Attributes:
        key: ``<group>.<field>`` of :class:`BrakeParameters` (``service.<field>``,
            ``service.tyre.<field>`` of the service brake; the node's parameter name),
            or for a sensor ``<field>`` of its :class:`SensorChannel` / transducer.
        mode: ``relative`` (value x (1 + d), d dimensionless) or ``absolute`` (value + d,
            d in the parameter's SI unit).
        sigma: standard deviation of the normal before truncation, in d's unit.
        limit: the truncation, ``|d| <= limit`` (the tolerance), in d's unit.
        source: where the figure comes from, or why it was chosen.
    """

    key: str
    mode: str
    sigma: float
    limit: float
    source: str

    def __post_init__(self) -> None:
        if self.mode not in ("relative", "absolute"):
            raise ParameterError(
                f"scatter {self.key}: mode {self.mode!r}: allowed 'relative' or 'absolute'"
            )
        if not (self.sigma > 0.0 and self.limit > 0.0 and math.isfinite(self.limit)):
            raise ParameterError(f"scatter {self.key}: sigma and limit must be > 0 and finite")
        if self.mode == "relative" and self.limit >= 1.0:
            raise ParameterError(f"scatter {self.key}: a relative limit must be < 1")

    @property
    def truncation(self) -> float:
        """The truncation in standard deviations, ``limit / sigma``."""
        return self.limit / self.sigma

    @property
    def std(self) -> float:
        """Standard deviation of the truncated normal, in d's unit (below ``sigma``)."""
        c = self.truncation
        mass = special.ndtr(c) - special.ndtr(-c)
        pdf = math.exp(-0.5 * c * c) / math.sqrt(2.0 * math.pi)
        return self.sigma * math.sqrt(1.0 - 2.0 * c * pdf / mass)

    def draw(self, uniform: float) -> float:
        """The deviation at ``uniform`` in [0, 1) of the truncated normal's probability."""
        low = special.ndtr(-self.truncation)
        z = float(special.ndtri(low + uniform * (1.0 - 2.0 * low)))
        return max(-self.limit, min(self.limit, self.sigma * z))

    def apply(self, value: float, deviation: float) -> float:
        return value * (1.0 + deviation) if self.mode == "relative" else value + deviation

    def describe(self, unit: str) -> str:
        """``+-4.5 % (sigma 1.5 %)`` or ``+-0.5 mm (sigma 0.167 mm)`` for a table."""
        if self.mode == "relative":
            return f"+-{100 * self.limit:.3g} % (sigma {100 * self.sigma:.3g} %)"
        scale, shown = (1e3, "mm") if unit == "m" else (1.0, unit)
        return f"+-{scale * self.limit:.3g} {shown} (sigma {scale * self.sigma:.3g} {shown})"


def _tolerance(key: str, limit: float, source: str, mode: str = "absolute") -> Scatter:
    """A drawing tolerance held by a just capable process: sigma = limit / 3."""
    return Scatter(key, mode, limit / 3.0, limit, source)


_ISO2768 = "ISO 2768-1 class m general tolerance"
# The brake's parameters, in draw-independent order (each has its own generator).
SCATTER: tuple[Scatter, ...] = (
    _tolerance(
        "driveline.drum_inertia_kg_m2",
        0.045,
        "assumed: a cast and machined drum's mass within a few percent; inertia follows it",
        "relative",
    ),
    _tolerance(
        "driveline.coupling_stiffness_n_m_per_rad",
        0.15,
        "assumed: tyre make, inflation and hub between vehicles of one model",
        "relative",
    ),
    _tolerance(
        "driveline.coupling_damping_n_m_s_per_rad",
        0.30,
        "assumed: tyre damping is known to no better than tens of percent",
        "relative",
    ),
    _tolerance(
        "shoe.drum_radius_m",
        0.035e-3,
        "drum bore to ISO 286 IT9 (0.14 mm on a 360 mm diameter): radius +-0.035 mm",
    ),
    _tolerance(
        "shoe.pivot_radius_m",
        0.5e-3,
        f"{_ISO2768}, 120-400 mm: +-0.5 mm (the pin 148 mm from the drum centre)",
    ),
    _tolerance(
        "shoe.pivot_polar_angle_deg",
        10.0 / 60.0,
        f"{_ISO2768} for angles, legs 120-400 mm: +-10' (+-0.17 deg)",
    ),
    _tolerance(
        "shoe.running_clearance_m",
        0.3e-3,
        "assumed: the 0.2 mm band of a new brake's adjusted clearance (0.3-0.5 mm) widened"
        " for the adjuster's step and the drum bore",
    ),
    _tolerance("shoe.lining_width_m", 0.3e-3, f"{_ISO2768}, 30-120 mm: +-0.3 mm"),
    _tolerance(
        "shoe.tip_x_m", 0.2e-3, f"{_ISO2768}, 6-30 mm: +-0.2 mm (the piston 27 mm off axis)"
    ),
    _tolerance("shoe.tip_y_m", 0.5e-3, f"{_ISO2768}, 120-400 mm: +-0.5 mm"),
    _tolerance(
        "shoe.mass_kg",
        0.045,
        "assumed: lining thickness and density and the stamped web; the inertia about the"
        " pin scales with the mass (same shape, more or less material)",
        "relative",
    ),
    _tolerance(
        "contact.drum_youngs_modulus_pa",
        0.065,
        "grey iron EN-GJL-250, 103-118 GPa (EN 1561): +-6.5 % around 110 GPa",
        "relative",
    ),
    _tolerance(
        "contact.shoe_youngs_modulus_pa",
        0.15,
        "assumed: friction material compressibility from batch to batch",
        "relative",
    ),
    _tolerance(
        "contact.damping_n_s_per_m",
        0.30,
        "assumed: contact damping is known to no better than tens of percent",
        "relative",
    ),
    _tolerance(
        "friction.coefficient",
        0.15,
        "SAE J866 edge code: one grade's friction lies in a band 0.10 wide (E: 0.25-0.35),"
        " +-17 % around its centre; +-15 % kept",
        "relative",
    ),
)
# The service brake's table (brake = "service"): what it reads. Not the study coupling's
# stiffness and damping (its tyre replaces them); the running clearance around its own
# 0.3 mm with a self-adjuster's tolerance; its return spring, circuit and tyre. Every other
# entry is the study brake's, so a key common to both draws the same uniform for a unit.
_NOT_READ_BY_SERVICE = (
    "driveline.coupling_stiffness_n_m_per_rad",
    "driveline.coupling_damping_n_m_s_per_rad",
)
_SERVICE_OWN: tuple[Scatter, ...] = (
    _tolerance(
        "shoe.running_clearance_m",
        0.1e-3,
        "assumed: a self-adjuster holds the clearance within about one step of its star"
        " wheel (0.05-0.1 mm at the lining); +-0.1 mm around the 0.3 mm a shoe",
    ),
    _tolerance(
        "service.return_spring_preload_n",
        0.10,
        "estimate: an extension spring's force at its installed length within +-10 % (a"
        " commercial grade of spring-force tolerance, as remembered, not checked)",
        "relative",
    ),
    _tolerance(
        "service.line_compliance_m3_per_pa",
        0.30,
        "assumed: hose swell, the fluid's air and water and the pedal and booster spread"
        " between cars; pedal travel per bar is known to no better than tens of percent",
        "relative",
    ),
    _tolerance(
        "service.tyre.presliding_stiffness_per_m",
        0.20,
        "assumed: tread stiffness with tyre make, inflation and tread depth between"
        " vehicles of one model (the study coupling's 15 % widened for tread wear)",
        "relative",
    ),
)
_SERVICE_KEYS = {s.key for s in _SERVICE_OWN}
SERVICE_SCATTER: tuple[Scatter, ...] = (
    tuple(s for s in SCATTER if s.key not in _NOT_READ_BY_SERVICE and s.key not in _SERVICE_KEYS)
    + _SERVICE_OWN
)
# Parameters that follow another's deviation rather than drawing their own.
FOLLOWERS: dict[str, str] = {"shoe.inertia_about_pivot_kg_m2": "shoe.mass_kg"}

# A sensor's scatter, per field and per kind of channel it applies to. Only channels with
# a real transducer scatter (an ``ideal`` one is exact by definition).
SENSOR_SCATTER: dict[str, dict[str, Scatter]] = {
    "sensitivity_ratio": {
        "accelerometer": _tolerance(
            "sensitivity_ratio",
            0.05,
            "assumed: a MEMS accelerometer's initial sensitivity within +-5 %, uncalibrated",
            "relative",
        ),
        "load_pin": _tolerance(
            "sensitivity_ratio",
            0.02,
            "assumed: a strain-gauge pin calibrated on a rig to +-2 %",
            "relative",
        ),
        "line_pressure": _tolerance(
            "sensitivity_ratio",
            0.01,
            "assumed: a pressure transducer's accuracy class, +-1 % of reading",
            "relative",
        ),
    },
    "resonance_hz": {
        "accelerometer": _tolerance(
            "resonance_hz",
            0.15,
            "assumed: the mounted resonance moves with stud torque, adhesive and surface",
            "relative",
        ),
    },
}
SENSOR_UNITS = {"sensitivity_ratio": "1", "resonance_hz": "Hz"}

SCATTER_BY_KEY: dict[str, Scatter] = {s.key: s for s in SCATTER}


def scatter_table(brake: str) -> tuple[Scatter, ...]:
    """The scatter table of the brake named ``brake`` ("study": :data:`SCATTER`,
    "service": :data:`SERVICE_SCATTER`; read at each call)."""
    tables = {"study": SCATTER, "service": SERVICE_SCATTER}
    if brake not in tables:
        raise ParameterError(f"brake {brake!r}: allowed one of {list(tables)}")
    return tables[brake]


def _uniform(unit_id: str, seed: int, key: str) -> float:
    return keyed_uniform(seed, DOMAIN, unit_id, key)


def _check(unit_id: str, seed: int) -> None:
    if not isinstance(unit_id, str) or not unit_id:
        raise ParameterError(f"unit id {unit_id!r}: allowed a non-empty string")
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**63:
        raise ParameterError(f"unit seed {seed!r}: allowed an integer from 0 to 2^63 - 1")


def deviations(unit_id: str, seed: int, brake: str = "study") -> dict[str, float]:
    """The brake's deviations of unit ``unit_id`` drawn with ``seed``, per key of the
    scatter table of ``brake`` (:func:`scatter_table`; all 0 for :data:`NOMINAL_UNIT`), in
    each scatter's unit."""
    _check(unit_id, seed)
    table = scatter_table(brake)
    if unit_id == NOMINAL_UNIT:
        return {s.key: 0.0 for s in table}
    return {s.key: s.draw(_uniform(unit_id, seed, s.key)) for s in table}


def _field(params: BrakeParameters, key: str) -> float:
    """The value at a dotted key (``shoe.mass_kg``, ``service.tyre.<field>``)."""
    value: Any = params
    for name in key.split("."):
        value = getattr(value, name)
    return value


def _with_values(params: BrakeParameters, values: Mapping[str, float]) -> BrakeParameters:
    """``params`` with the value at each dotted key replaced (the core checks each group
    built again: ParameterError for an invalid one)."""
    nested: dict[str, Any] = {}
    for key, value in values.items():
        *path, name = key.split(".")
        level = nested
        for part in path:
            level = level.setdefault(part, {})
        level[name] = value

    def rebuilt(obj: Any, changes: dict[str, Any]) -> Any:
        return replace(
            obj,
            **{
                k: rebuilt(getattr(obj, k), v) if isinstance(v, dict) else v
                for k, v in changes.items()
            },
        )

    return rebuilt(params, nested)


def parameter_unit(key: str) -> str:
    """The SI unit of a brake parameter from its name (``shoe.tip_x_m`` -> ``m``; "1"
    for a dimensionless one)."""
    unit = unit_of(key)
    return "1" if unit == "dimensionless" else unit


def unit_parameters(nominal: BrakeParameters, unit_id: str, seed: int) -> BrakeParameters:
    """The brake of unit ``unit_id`` (seed ``seed``): ``nominal`` (the scenario's values)
    with the unit's deviations applied; ``nominal`` itself for :data:`NOMINAL_UNIT`.

    Raises:
        ParameterError: a unit whose drawn values leave the model's validity (only
            possible when the scenario's values sit within a tolerance of a limit); one
            line naming the unit and the core's reason.
    """
    drawn = deviations(unit_id, seed, nominal.brake)
    if unit_id == NOMINAL_UNIT:
        return nominal
    try:
        return with_deviations(nominal, drawn)
    except ParameterError as exc:
        raise ParameterError(
            f"unit {unit_id!r} (seed {seed}) is not a valid brake: {exc} (the scenario's"
            " value lies within the unit scatter's tolerance of the model's limit)"
        ) from None


def with_deviations(nominal: BrakeParameters, drawn: Mapping[str, float]) -> BrakeParameters:
    """``nominal`` with deviations ``drawn`` (per key of its brake's scatter table,
    :func:`scatter_table`, in each scatter's unit; a missing key: none), and each
    :data:`FOLLOWERS` parameter scaled as its leader. Raises ParameterError (the core's
    checks) for an invalid result or a key its brake's table has not."""
    by_key = {s.key: s for s in scatter_table(nominal.brake)}
    values: dict[str, float] = {}
    for key, deviation in drawn.items():
        s = by_key.get(key)
        if s is None:
            raise ParameterError(
                f"scatter {key!r}: not scattered on the {nominal.brake} brake (allowed"
                f" {sorted(by_key)})"
            )
        values[key] = s.apply(_field(nominal, key), deviation)
        for follower, leader in FOLLOWERS.items():
            if leader == key:
                ratio = values[key] / _field(nominal, key)
                values[follower] = _field(nominal, follower) * ratio
    return _with_values(nominal, values)


def _sensor_scatter(channel: SensorChannel) -> Iterator[tuple[str, Scatter]]:
    """(field, scatter) of each field of ``channel`` that scatters between units."""
    if channel.transducer == IDEAL or channel.transducer.name == "ideal":
        return
    for name, by_kind in SENSOR_SCATTER.items():
        scatter = by_kind.get(channel.kind)
        if scatter is None:
            continue
        if name == "resonance_hz" and channel.transducer.resonance_hz is None:
            continue
        yield name, scatter


def sensor_deviations(sensors: SensorSet, unit_id: str, seed: int) -> dict[str, float]:
    """Per ``sensor.<channel>.<field>``, the unit's deviation (relative) of each channel
    field that scatters (all 0 for :data:`NOMINAL_UNIT`)."""
    _check(unit_id, seed)
    out = {}
    for channel in sensors.channels:
        for name, scatter in _sensor_scatter(channel):
            key = f"sensor.{channel.name}.{name}"
            out[key] = (
                0.0 if unit_id == NOMINAL_UNIT else scatter.draw(_uniform(unit_id, seed, key))
            )
    return out


def _sensor_value(channel: SensorChannel, name: str) -> float:
    source = channel.transducer if name == "resonance_hz" else channel
    return getattr(source, name)


def unit_sensors(nominal: SensorSet, unit_id: str, seed: int) -> SensorSet:
    """The sensors of unit ``unit_id`` (seed ``seed``): each channel of ``nominal`` with a
    real transducer gets its drawn sensitivity and, where it has one, mounted resonance;
    ``nominal`` itself for :data:`NOMINAL_UNIT`."""
    drawn = sensor_deviations(nominal, unit_id, seed)
    if unit_id == NOMINAL_UNIT:
        return nominal
    channels = []
    for channel in nominal.channels:
        for name, scatter in _sensor_scatter(channel):
            value = scatter.apply(
                _sensor_value(channel, name), drawn[f"sensor.{channel.name}.{name}"]
            )
            if name == "resonance_hz":
                channel = replace(
                    channel, transducer=replace(channel.transducer, resonance_hz=value)
                )
            else:
                channel = replace(channel, **{name: value})
        channels.append(channel)
    return replace(nominal, channels=tuple(channels))


@dataclass(frozen=True)
class UnitValue:
    """One scattered value of a unit against the drawing.

    Attributes:
        key: the parameter's key (``friction.coefficient``, ``sensor.<channel>.<field>``).
        unit: its SI unit ("1": dimensionless).
        nominal: the scenario's value.
        value: the unit's value.
        scatter: its distribution.
    """

    key: str
    unit: str
    nominal: float
    value: float
    scatter: Scatter

    @property
    def change(self) -> float:
        """``value - nominal`` in ``unit``."""
        return self.value - self.nominal

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: key, unit, nominal, value (the ground truth's form)."""
        return {"key": self.key, "unit": self.unit, "nominal": self.nominal, "value": self.value}


def unit_values(
    nominal: BrakeParameters,
    unit: BrakeParameters,
    nominal_sensors: SensorSet,
    unit_sensor_set: SensorSet,
) -> list[UnitValue]:
    """Every scattered value of a unit against its drawing, in table order: the brake's
    (the scatter table of its brake, :func:`scatter_table`, then :data:`FOLLOWERS`), then
    each sensor channel's."""
    table = scatter_table(nominal.brake)
    out = [
        UnitValue(s.key, parameter_unit(s.key), _field(nominal, s.key), _field(unit, s.key), s)
        for s in table
    ]
    by_key = {s.key: s for s in table}
    for key, leader in FOLLOWERS.items():
        s = by_key[leader]
        out.append(UnitValue(key, parameter_unit(key), _field(nominal, key), _field(unit, key), s))
    drawn = {c.name: c for c in unit_sensor_set.channels}
    for channel in nominal_sensors.channels:
        for name, scatter in _sensor_scatter(channel):
            out.append(
                UnitValue(
                    f"sensor.{channel.name}.{name}",
                    SENSOR_UNITS[name],
                    _sensor_value(channel, name),
                    _sensor_value(drawn[channel.name], name),
                    scatter,
                )
            )
    return out
