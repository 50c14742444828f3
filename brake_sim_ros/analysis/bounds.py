"""Physical upper bounds that a correct run must respect, derived from the model's equations.

Indentation under a constant actuation force. Take one shoe, linearised about its first
contact: rotation ``phi`` past the onset angle, indentation ``eps = d phi``, moment arms
``d`` (normal force), ``h`` (friction) and ``q`` (actuation) about the pivot. The
actuation moment is ``M = Fe q``. In contact the normal force ``Fn = k eps + c eps'``
resists with ``Fn d`` and friction assists the leading shoe with at most ``mu Fn h``,
so the net resisting moment is at least ``(d - mu h) Fn`` (the trailing shoe, whose
friction resists, is held back more). With

    W = I phi'^2 / 2 - M phi + k_eff max(phi, 0)^2 / 2,    k_eff = k d (d - mu h)

``dW/dt <= 0`` whenever ``M`` is constant (the damping part of ``Fn`` and the
coupling to the drum only dissipate, a contact never pulls), so from rest at ``phi0 =
-phi_gap`` the rotation past onset never exceeds the positive root of
``k_eff phi^2 / 2 - M phi = M phi_gap``:

    eps_max = d (M + sqrt(M^2 + 2 k_eff M phi_gap)) / k_eff.

The arms change a little as the shoe turns; :data:`ARM_VARIATION` allows for that.
"""

from __future__ import annotations

import math

from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import contact_arms, pack
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.model.run_setup import BrakeSetup

# Relative allowance for the change of the moment arms between first contact and the
# deepest indentation. For the nominal geometry and pivot shifts of +-3 %, d and h change
# by at most 1.4 % over the first 0.03 rad past onset (4.5 mm of indentation); the
# -3 % shift's d grows, which only stiffens the contact.
ARM_VARIATION = 0.02


def indentation_bound_m(setup: BrakeSetup, actuation_n: float) -> tuple[float, float]:
    """Largest indentation (left, right), m, each shoe can reach from rest under a constant
    actuation force ``actuation_n`` (before the actuation-share gain), per the module
    docstring. ``inf`` when the linearised shoe self-locks (``mu h >= d``)."""
    p = pack(setup.params, setup.defects, setup.options)
    k = p[L.P_CONTACT_STIFFNESS]
    out = []
    for i, side in enumerate(SIDES):
        base = L.P_SHOE_BASE + i * L.SHOE_STRIDE
        mu = p[base + L.S_FRICTION_COEFFICIENT]
        start = math.radians(getattr(setup.defects, side).initial_angle_deg)
        arms = contact_arms(p, base, start)
        if arms is None:
            out.append(0.0)  # never reaches the drum
            continue
        # each arm taken at the end of its allowance that loosens the bound
        d_lo = arms.normal_arm_m * (1.0 - ARM_VARIATION)
        d_hi = arms.normal_arm_m * (1.0 + ARM_VARIATION)
        h_hi = arms.friction_arm_m * (1.0 + ARM_VARIATION)
        q = arms.actuation_arm_m * (1.0 + ARM_VARIATION)
        margin = d_lo - mu * h_hi
        if margin <= 0.0:
            out.append(math.inf)
            continue
        k_eff = k * d_lo * margin
        moment = actuation_n * p[base + L.S_ACTUATION_GAIN] * q
        gap = max(arms.onset_angle_rad - start, 0.0)
        phi = (moment + math.sqrt(moment * moment + 2.0 * k_eff * moment * gap)) / k_eff
        out.append(float(d_hi * phi))
    return out[0], out[1]
