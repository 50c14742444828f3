"""How each defect kind enters the kernels' packed parameter vector (layout ``S_*``,
``LN_*``, ``P_DRUM_WAVE_*``, ``P_FLAT_*``): one function per kind, named by the kind's
catalogue entry (:attr:`.catalogue.DefectKind.packing`). :func:`.assembly.pack` writes the
healthy brake's own slots, then calls every kind's packing at each of its locations, in
catalogue order (the shoes before the drum); each writes its slots for any severity, 0
included (a healthy severity packs the healthy value).

A packing checks what its own numbers allow (a drum's slope); the checks that need the
assembled brake (a shoe clear of the drum at rest, self-locking, the drum's runout against
the rest gap) are the assembly's.

Pure logic: no files.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model import adjuster, growth
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.actuation import RETURN_SPRING_PRELOAD_N
from brake_sim_ros.model.contact import MAX_DRUM_SLOPE
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.placement import place_shoe, worn_lining_radius


@dataclass(frozen=True)
class PackSite:
    """One location of the brake being packed: what a kind's packing reads and where it
    writes.

    Attributes:
        params: the brake's parameters.
        location: ``left``, ``right``, ``drum`` or ``line``.
        defect: that location's defects, a :class:`.defects.ShoeDefect`,
            :class:`.defects.DrumDefect` or :class:`.defects.LineDefect` (not imported:
            that module imports the catalogue, which names these functions).
        p: the packed parameter vector being written (layout ``N_PARAMS``).
    """

    params: BrakeParameters
    location: str
    defect: Any
    p: np.ndarray

    @property
    def shoe_base(self) -> int:
        """Index of the shoe's block in ``p`` (layout ``P_SHOE_BASE``)."""
        return L.P_SHOE_BASE + L.SIDES.index(self.location) * L.SHOE_STRIDE

    @property
    def lining_base(self) -> int:
        """Index of the shoe's lining block in ``p`` (layout ``P_LINING_BASE``)."""
        return L.P_LINING_BASE + L.SIDES.index(self.location) * L.LINING_STRIDE


def pack_nothing(site: PackSite) -> None:
    """A kind with no slot of its own: it acts through the state at t = 0 (a shoe's
    starting angle, :func:`.assembly.initial_state`)."""


def pack_pivot(site: PackSite) -> None:
    """A pin moved radially: the shoe's placement (pin, lining centre and middle, mass
    centre, inertia about the pin, tip), :func:`.placement.place_shoe`."""
    s = place_shoe(site.params, site.location, site.defect)
    growth.write_placement.py_func(
        site.p,
        site.shoe_base,
        *s.pivot_xy_m,
        *s.lining_centre_xy_m,
        s.lining_mid_rad,
        *s.mass_centre_xy_m,
        s.inertia_about_pivot_kg_m2,
        *s.tip_xy_m,
    )


def _pack_gain(site: PackSite) -> None:
    # the force multiplier is the product of the share and the gain change: each of the
    # two kinds writes it whole
    site.p[site.shoe_base + L.S_ACTUATION_GAIN] = site.defect.actuation_gain


def pack_share(site: PackSite) -> None:
    """The shoe's share of the total actuation force, and the force multiplier."""
    site.p[site.shoe_base + L.S_SHARE] = site.defect.actuation_share
    _pack_gain(site)


def pack_gain_change(site: PackSite) -> None:
    """The wheel cylinder's pressure factor ``1 + pct/100``, and the force multiplier."""
    site.p[site.shoe_base + L.S_PRESSURE_FACTOR] = (
        1.0 + site.defect.actuation_gain_change_pct / 100.0
    )
    _pack_gain(site)


def pack_friction(site: PackSite) -> None:
    """The lining's friction coefficient ``mu (1 + pct/100)``."""
    site.p[site.shoe_base + L.S_FRICTION_COEFFICIENT] = growth.lining_friction.py_func(
        site.params.friction.coefficient, site.defect.friction_change_pct
    )


def pack_delay(site: PackSite) -> None:
    """The actuation's dead time, s."""
    site.p[site.shoe_base + L.S_ACTUATION_DELAY] = site.defect.actuation_delay_ms * 1e-3


def pack_lag(site: PackSite) -> None:
    """The actuation's first-order lag time constant, s."""
    site.p[site.shoe_base + L.S_ACTUATION_LAG] = site.defect.actuation_lag_ms * 1e-3


def pack_pulsation(site: PackSite) -> None:
    """The actuation's pulsation: amplitude (a fraction of the force) and frequency, Hz."""
    b = site.shoe_base
    site.p[b + L.S_PULSATION_AMPLITUDE] = site.defect.actuation_pulsation_pct / 100.0
    site.p[b + L.S_PULSATION_FREQUENCY] = site.defect.actuation_pulsation_hz


def pack_spring_release(site: PackSite) -> None:
    """The return spring's lost preload, N at the tip, for the study brake's net-force
    shortcut; the service brake's spring carries its weakening itself
    (:func:`.assembly._pack_service`)."""
    if site.params.service is not None:
        return
    site.p[site.shoe_base + L.S_SPRING_RELEASE] = (
        site.defect.return_spring_weakening_pct / 100.0 * RETURN_SPRING_PRELOAD_N
    )


def pack_lining_wear(site: PackSite) -> None:
    """A worn lining: its radius (:func:`.placement.worn_lining_radius`) and its wear, m
    (from which a wear that grows starts)."""
    wear_mm = site.defect.lining_wear_mm
    site.p[site.shoe_base + L.S_LINING_RADIUS] = worn_lining_radius(site.params, wear_mm)
    site.p[site.lining_base + L.LN_WEAR] = wear_mm * 1e-3


def pack_adjuster_seized(site: PackSite) -> None:
    """A seized self-adjuster: refused on the study brake (it has none); on the service
    brake the adjuster is packed with the shoe's wear at the start of the run
    (:func:`.adjuster.pack_adjuster`, called by :func:`.assembly.pack`: it reads the
    wear's growth)."""
    if site.params.service is None:
        adjuster.refuse_on_study(site.location, site.defect.adjuster_seized_mm)


def pack_harmonics(site: PackSite) -> None:
    """The drum's radius harmonics (layout ``P_DRUM_WAVE_*``) after checking their slope;
    a round drum (no harmonic of non-zero amplitude) packs none, so the kernels take
    exactly the round drum's arithmetic. The runout against the rest gap needs the
    assembled shoes: :func:`.assembly.pack` checks it."""
    drum = site.defect
    waves = [h for h in drum.harmonics if h.amplitude_um > 0.0]
    if not waves:
        return
    slope = drum.slope(site.params.shoe.drum_radius_m)
    if slope > MAX_DRUM_SLOPE:
        raise ParameterError(
            f"drum harmonics slope sum_k k a_k / R0 = {slope:.4f}: allowed at most"
            f" {MAX_DRUM_SLOPE} (the contact geometry tilts the normal by a small slope)"
        )
    site.p[L.P_DRUM_WAVE_COUNT] = float(len(waves))
    for j, h in enumerate(waves):
        b = L.P_DRUM_WAVE_BASE + j * L.DRUM_WAVE_STRIDE
        site.p[b + L.W_ORDER] = float(h.order)
        site.p[b + L.W_AMPLITUDE] = h.amplitude_um * 1e-6
        site.p[b + L.W_PHASE] = math.radians(h.phase_deg)


def pack_flat(site: PackSite) -> None:
    """The drum's flat (layout ``P_FLAT_*``) after checking its slope against the drum's
    radius; none (depth 0) leaves the round drum's arithmetic."""
    drum = site.defect
    if drum.flat_depth_um <= 0.0:
        return
    slope = drum.flat_slope(site.params.shoe.drum_radius_m)
    if slope > MAX_DRUM_SLOPE:
        raise ParameterError(
            f"drum flat of {drum.flat_depth_um:g} um over {drum.flat_width_deg:g} deg: slope"
            f" pi d / (2 w R0) = {slope:.4f}, allowed at most {MAX_DRUM_SLOPE} (the contact"
            " geometry tilts the normal by a small slope): make it wider or shallower"
        )
    site.p[L.P_FLAT_DEPTH] = drum.flat_depth_um * 1e-6
    site.p[L.P_FLAT_CENTRE] = math.radians(drum.flat_centre_deg)
    site.p[L.P_FLAT_HALF_WIDTH] = math.radians(0.5 * drum.flat_width_deg)


def pack_line_air(site: PackSite) -> None:
    """The line's air, m^3 at atmospheric pressure (:func:`.service.air_compliance`)."""
    site.p[L.P_LINE_AIR_VOLUME] = site.defect.air_in_line_ml * 1e-6


def pack_line_leak(site: PackSite) -> None:
    """A leak's conductance to the reservoir, m^3/(s Pa): ``G = s / ((1 - s) R)`` for the
    held pressure's shortfall ``s`` (a fraction) through the line's resistance ``R``, so
    that a held source ``p_s`` holds ``p_s / (1 + G R) = (1 - s) p_s``."""
    shortfall = site.defect.line_leak_pct / 100.0
    resistance = site.params.service.line_resistance_pa_s_per_m3
    site.p[L.P_LINE_LEAK_CONDUCTANCE] = shortfall / ((1.0 - shortfall) * resistance)
