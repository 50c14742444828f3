"""A study brake (no springs, the study's clearance) whose shoe sits by the tip abutment:
the service brake's shoe and contact at the 3.5 mm clearance, which is the study brake as
it was calibrated before issue 28 gave it the heel in an eye. The tests of the tip
abutment's response (monotone, antisymmetric in the pin) run on it."""

from __future__ import annotations

import dataclasses

from brake_sim_ros.model.parameters import SERVICE_CONTACT, SERVICE_SHOE, BrakeParameters

TIP_STUDY = BrakeParameters(
    shoe=dataclasses.replace(SERVICE_SHOE, running_clearance_m=0.0035), contact=SERVICE_CONTACT
)
