"""The hydraulic line's defect kinds (catalogue location ``line``): air in the circuit and a
leak. They act on the service brake's circuit (:mod:`.service`), not on one shoe, so they
sit at the line; the study brake has no circuit (an ideal force source) and refuses them
(:func:`.catalogue.refuse_without_circuit`).

* ``air_in_line``: air left in the circuit (a poorly bled line, a boiled fluid's vapour
  once it has cooled back). Modelled as a volume ``V_a`` of air at atmospheric pressure,
  compressed isothermally with the line pressure: the compliance ``V_a p_a / (p_a + p)^2``
  beside the circuit's own (:func:`.service.air_compliance`). The pedal goes soft: the
  first bar takes far more fluid than the healthy circuit's 0.08 cm^3 per bar (1 ml of
  air takes 0.34 cm^3 per bar at the 0.7 bar residual pressure), so the pressure rises
  later, most of all at a light application, and the line is softer against the tips the
  drum pushes back, so an oval drum's pressure pulsation changes.
* ``line_leak``: fluid lost from the circuit to the outside or the reservoir (a weeping
  wheel-cylinder cup or fitting, a master-cylinder cup seal that bypasses): a laminar leak
  ``G p``. The source (the master cylinder behind the driver's force) makes the flow up
  through the line's resistance, so a held force holds the pressure ``p_s / (1 + G R)``
  short of the static one and the pressure settles faster, with ``R C / (1 + G R)``; a
  held pedal keeps sinking (the flow never stops). A leak rather than a gain on the
  source: a gain on the pistons' mean is already the sum of the shoes'
  ``actuation_gain_change`` (each piston's own departure, :mod:`.service`), while a leak
  has a cause of its own in the circuit with signatures of its own (the held droop, the
  faster settling, the lost fluid). The severity is the held pressure's shortfall in %,
  the number a pressure gauge at the wheel against the master cylinder reads; the packed
  conductance is ``G = s / ((1 - s) R)``.

Pure data and logic: no files.
"""

from __future__ import annotations

from brake_sim_ros.model import packing
from brake_sim_ros.model.defect_kind import DefectKind

LINE = "line"  # the location of a defect of the hydraulic circuit
AIR_KIND = "air_in_line"
LEAK_KIND = "line_leak"
# Most air a circuit can hold and still brake, ml at atmospheric pressure. Estimate: the
# master cylinder's displacement per circuit, 3.3 cm^2 (20.6 mm bore) over a 30 mm
# stroke, is 10 ml; more air than that and the pedal reaches the floor before the
# pressure builds.
MAX_AIR_ML = 10.0
# A clearly spongy pedal, ml. Estimate: compressing 1 ml of air to 35 bar takes 0.97 ml,
# 2.9 mm of a 20.6 mm master cylinder's stroke, 10 mm at the pedal (ratio 3.5): a third
# more than the healthy pedal's 30 mm for 35 bar (ServiceBrakeParameters).
SERVICE_AIR_ML = 1.0
# Largest leak, % of the held pressure lost: a line that still holds a tenth of it.
MAX_LEAK_PCT = 90.0
# A leak's sweep end, %. Estimate: any fluid leak fails an inspection; a fifth of the
# held pressure lost is the size of the graded efficiency loss the per-shoe gain's service
# limit uses (27 %), a little smaller.
SERVICE_LEAK_PCT = 20.0
# the circuit exists only on the service brake, which runs the full model (no [needs]:
# scenarios/tables.parse_brake)
CIRCUIT_LEVELS = frozenset({"full"})

LINE_KINDS: tuple[DefectKind, ...] = (
    DefectKind(
        name=AIR_KIND,
        locations=(LINE,),
        unit="ml",
        minimum=0.0,
        maximum=MAX_AIR_ML,
        limit=(
            "the master cylinder's displacement per circuit, about 10 ml: more and the pedal"
            " reaches the floor"
        ),
        description=(
            "volume of air in the hydraulic circuit at atmospheric pressure, ml, compressed"
            " isothermally with the line pressure: a spongy pedal, a later pressure rise"
            " (service brake only)"
        ),
        scenario_key="air_in_line_ml",
        service_limit=SERVICE_AIR_ML,
        levels=CIRCUIT_LEVELS,
        growth_id=None,
        packing=packing.pack_line_air,
        service_only=True,
    ),
    DefectKind(
        name=LEAK_KIND,
        locations=(LINE,),
        unit="%",
        minimum=0.0,
        maximum=MAX_LEAK_PCT,
        limit="a line that still holds a tenth of its pressure",
        description=(
            "a leak from the hydraulic circuit (a weeping cup or fitting, a bypassing"
            " master-cylinder seal): the held line pressure's shortfall from the static one,"
            " in %; the pressure also settles faster (service brake only)"
        ),
        scenario_key="line_leak_pct",
        service_limit=SERVICE_LEAK_PCT,
        levels=CIRCUIT_LEVELS,
        growth_id=None,
        packing=packing.pack_line_leak,
        service_only=True,
    ),
)
