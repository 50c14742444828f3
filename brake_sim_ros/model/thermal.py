"""The brake's temperature: a lumped thermal state heated by friction, cooled by the air,
and the fade law by which it acts on the linings' friction (compiled parts and parameters).

A scenario with a ``[thermal]`` table carries one more state, the temperature ``T`` of the
brake (drum and shoes as one lumped body, deg C), integrated with the motion::

    C dT/dt = P_f - (h_0 + h_v |v|) (T - T_air)

* ``P_f``: the friction power of both shoes, W (the ``friction_work_j`` quadrature's
  rate), all of it into the brake; the kinetic energy the drum's lock removes at a stick
  instant (``lock_loss_j``) heats it too, at that instant. The contact's damping loss
  (Kelvin-Voigt, ``contact_loss_j``) is not counted: it is the lining's hysteresis, under
  a thousandth of the friction work in a stop.
* ``C``: the brake's heat capacity, J/K (default 3680 J/K: an 8 kg cast-iron drum at
  460 J/(kg K); the shoes' steel and linings are left out, which a lumped body of the
  drum's capacity makes a little too quick to heat).
* ``h_0 + h_v |v|``: the convective conductance to the air, W/K, at the vehicle speed
  ``v`` (m/s; the drum's speed times the wheel radius). Defaults 1.5 W/K at rest and
  0.3 W/K per m/s: a drum's outer surface of about 0.15 m^2 with a natural-convection
  coefficient of 10 W/(m^2 K) at rest and about 65 W/(m^2 K) at 100 km/h, the order of
  Limpert (*Brake Design and Safety*, ch. 3) for drums; at 100 km/h the time constant
  ``C / h`` is 6 minutes, at rest 41 minutes. Radiation is left out (some 10 % of the
  cooling at 300 deg C). These are order-of-magnitude values, stated as assumptions.

The temperature acts on both linings' friction coefficient through the fade law
:data:`FADE`, at the start of every physics step, from the state then (the coefficient is
held over the step, as the defects' growth holds its parameters). A lining's coefficient
when cool (its friction change included) is kept apart, so that fade and a friction
defect compose: ``mu = mu_cool x fade(T)``.

:data:`FADE` is a generic organic lining's, stated as an assumption. A real lining's curve
is its own (the SAE J866 edge code rates its "hot" friction over 204-343 deg C, 400-650
deg F); this one keeps the friction up to 250 deg C and falls linearly to half at
350 deg C (organic binders start to decompose near 290-340 deg C, 550-650 deg F, in fleet
brake-temperature guides), half above. The rule is :func:`fade_ratio`, written once: the
compiled step and the per-run conditions (fleet/conditions.py) both use it.

Pure: no files, no transport.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.compiled import JIT
from brake_sim_ros.model.vehicle import DEFAULT_WHEEL_RADIUS_M

# The fade law's assumption (module doc): onset, full fade, deg C; the ratio at full fade.
FADE_ONSET_C = 250.0
FADE_FULL_C = 350.0
FADE_FULL_RATIO = 0.5
# A brake without a thermal state is recorded at this temperature unless the run's
# conditions give one (deg C; the ISA sea-level air is 15 deg C, a workshop's 20).
DEFAULT_TEMPERATURE_C = 20.0


@njit(inline="always", **JIT)
def fade_ratio(temperature_c, onset_c, full_c, full_ratio):
    """A lining's friction at ``temperature_c`` over its friction when cool: 1 up to
    ``onset_c``, linear to ``full_ratio`` at ``full_c``, held above (deg C); the rule."""
    if temperature_c <= onset_c:
        return 1.0
    if temperature_c >= full_c:
        return full_ratio
    w = (temperature_c - onset_c) / (full_c - onset_c)
    return 1.0 - w * (1.0 - full_ratio)


@dataclass(frozen=True)
class FadeLaw:
    """A lining's friction against its temperature (:func:`fade_ratio`'s arguments)."""

    onset_c: float
    full_c: float
    full_ratio: float

    def ratio(self, temperature_c: float) -> float:
        """Friction at ``temperature_c`` (deg C) over the friction when cool."""
        return fade_ratio.py_func(temperature_c, self.onset_c, self.full_c, self.full_ratio)


FADE = FadeLaw(onset_c=FADE_ONSET_C, full_c=FADE_FULL_C, full_ratio=FADE_FULL_RATIO)


@dataclass(frozen=True)
class Thermal:
    """The brake's lumped thermal state (scenario table ``[thermal]``; module doc).

    Attributes:
        heat_capacity_j_k: the brake's heat capacity, J/K (3680: 8 kg of cast iron).
        cooling_w_k: convective conductance to the air at rest, W/K.
        cooling_w_k_per_m_s: its growth with the vehicle speed, W/K per m/s.
        ambient_c: the air's temperature, deg C.
        initial_c: the brake's temperature at the start, deg C (None: the ambient's).
    """

    heat_capacity_j_k: float = 3680.0
    cooling_w_k: float = 1.5
    cooling_w_k_per_m_s: float = 0.3
    ambient_c: float = DEFAULT_TEMPERATURE_C
    initial_c: float | None = None

    def __post_init__(self) -> None:
        for name, lo, hi in LIMITS:
            value = getattr(self, name)
            if value is None and name == "initial_c":
                continue
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ParameterError(f"thermal {name} {value!r}: allowed a number")
            if not (math.isfinite(value) and lo <= value <= hi) or (
                name == "heat_capacity_j_k" and value == 0.0
            ):
                low = f"> {lo:g}" if name == "heat_capacity_j_k" else f">= {lo:g}"
                raise ParameterError(f"thermal {name} {value!r}: allowed {low} and <= {hi:g}")

    @property
    def start_c(self) -> float:
        """The brake's temperature at the start, deg C."""
        return self.ambient_c if self.initial_c is None else float(self.initial_c)


# (field, low, high): the model's limits (deg C from -40 to 800: a drum glows red near 600)
LIMITS: tuple[tuple[str, float, float], ...] = (
    ("heat_capacity_j_k", 0.0, 1.0e6),
    ("cooling_w_k", 0.0, 1.0e4),
    ("cooling_w_k_per_m_s", 0.0, 1.0e3),
    ("ambient_c", -40.0, 60.0),
    ("initial_c", -40.0, 800.0),
)


def pack_fade(p: np.ndarray) -> None:
    """Write the fade law, the linings' friction coefficients when cool (as ``p`` has them
    now) and the default recorded temperature into the packed vector ``p``
    (:func:`~brake_sim_ros.model.assembly.pack` calls it last)."""
    p[L.P_HELD_TEMPERATURE] = DEFAULT_TEMPERATURE_C
    p[L.P_FADE_ONSET] = FADE_ONSET_C
    p[L.P_FADE_FULL] = FADE_FULL_C
    p[L.P_FADE_FULL_RATIO] = FADE_FULL_RATIO
    for i in range(2):
        p[L.P_COOL_FRICTION + i] = p[L.P_SHOE_BASE + i * L.SHOE_STRIDE + L.S_FRICTION_COEFFICIENT]


def pack_thermal(p: np.ndarray, setup) -> None:
    """Write ``setup``'s temperature (``BrakeSetup.thermal``, ``.held_temperature_c``) into
    the packed vector ``p`` (a :func:`pack_fade` one): the thermal state's parameters, or
    without one the temperature the run is held at. The vehicle's wheel radius (the
    published one without a vehicle) turns the drum's speed into the vehicle's."""
    p[L.P_HELD_TEMPERATURE] = setup.held_temperature_c
    thermal = setup.thermal
    if thermal is None:
        return
    radius = DEFAULT_WHEEL_RADIUS_M if setup.vehicle is None else setup.vehicle.wheel_radius_m
    p[L.P_THERMAL] = 1.0
    p[L.P_HELD_TEMPERATURE] = thermal.start_c
    p[L.P_HEAT_CAPACITY] = thermal.heat_capacity_j_k
    p[L.P_COOLING] = thermal.cooling_w_k
    p[L.P_COOLING_PER_SPEED] = thermal.cooling_w_k_per_m_s * radius
    p[L.P_AMBIENT] = thermal.ambient_c


@njit(inline="always", **JIT)
def heating_rate(p, friction_power, drum_speed, temperature):
    """``dT/dt`` of the brake, K/s, for the friction power ``friction_power`` (W) at
    ``drum_speed`` (rad/s) and ``temperature`` (deg C) (module doc)."""
    conductance = p[L.P_COOLING] + p[L.P_COOLING_PER_SPEED] * abs(drum_speed)
    return (friction_power - conductance * (temperature - p[L.P_AMBIENT])) / p[L.P_HEAT_CAPACITY]


@njit(**JIT)
def fade_linings(p, pw, temperature):
    """Write both linings' friction coefficient at ``temperature`` (deg C) into ``pw``:
    each one's coefficient when cool (``pw``'s layout.P_COOL_FRICTION, which a growing
    friction change updates) times :func:`fade_ratio`."""
    ratio = fade_ratio(temperature, p[L.P_FADE_ONSET], p[L.P_FADE_FULL], p[L.P_FADE_FULL_RATIO])
    for i in range(2):
        pw[L.P_SHOE_BASE + i * L.SHOE_STRIDE + L.S_FRICTION_COEFFICIENT] = (
            pw[L.P_COOL_FRICTION + i] * ratio
        )
