"""Fidelity levels: which model a scenario needs, chosen from what it asks for.

A scenario states its needs (outputs from a fixed vocabulary, the shoes whose signals it
wants, an accuracy preset, optionally a forced level). :func:`plan` picks the cheapest
level that delivers every asked output, the shoes to keep in the model and the recorded
columns to keep. A forced level that cannot deliver an asked output is refused, naming the
output and the levels that can; nothing is silently approximated.

Levels, cheapest first (degrees of freedom in brackets):

* ``contact_regime_rigid`` (1): quasi-static shoes, flywheel and drum as one rigid body.
* ``contact_regime`` (2): quasi-static shoes, flywheel and drum on the torsional coupling.
* ``rigid`` (3): the impact model (dynamic shoes) with a rigid wheel-drum coupling.
* ``full`` (4): the 4-DoF impact model.

Why each level serves what it serves (the physics behind the capability table):

* Quasi-static shoes have no impacts: the contact-regime levels cannot deliver impacts,
  shoe motion or the force histories of the impacting regime. They deliver the forces of a
  shoe riding steadily on the drum exactly (the same balance the full model settles to), the
  braking torque (impact-averaged during the impacting regime) and the stopping time.
* The wheel-drum coupling matters only near standstill, where the smoothed friction law
  pins the drum and the twisted coupling unwinds through it before the brake locks (about
  1 % of the stopping time). Elsewhere the drum speed reaches the shoes only through a
  saturated friction law. So the rigid levels deliver impacts (the impacting regime ends
  while the drum still turns fast) and the contact-regime forces, but not the stopping
  time, the braking torque or any drum-side signal.
* One shoe affects the other only through the drum speed, which enters the friction law
  where it is saturated; so a shoe's impacts and contact-regime forces are the same with
  the other shoe removed, and a scenario that asks only these, for one shoe, gets a
  one-shoe model.
* ``measured_signals`` (the scenario's sensor channels) only from ``full``. The sensors read
  the pivot-force history with its impacts (accelerometers through the backing-plate
  structure, load pins), the actuation forces (line pressure) and the drum angle (the
  wheel-speed tone ring). The contact-regime levels have no impacts: their pivot forces
  are the steady ones, which leave the structure's modes unexcited and the accelerations
  near zero, so what they would measure is not what a vehicle's sensors see. The rigid
  levels have impacts but no drum-side signal: the tone ring would read the flywheel, and
  miss the coupling's twist and the lock at standstill. The structure sums both pivot
  forces, so measured signals never come from a one-shoe model. A plan without this
  output builds no sensor bank: no structure, no measured channels (the cost is saved).
* Defects: every level represents the shoe defects (pivot location, initial angle,
  actuation share: the geometry and the gains). An out-of-round drum (``drum_out_of_round``)
  needs the drum angle in the contact and the shoes' dynamics: its wave moves the shoe at
  ``k`` times the rotation frequency, it drives the contact damper and the drum works
  against the normal force. The contact-regime levels balance massless shoes without the
  drum angle and reuse a balance while the actuation holds, so they cannot represent it;
  the impact levels (``rigid``, ``full``) can (the rigid coupling changes the order-2 line
  of the leading shoe's pivot force by 3e-7 of it). A scenario with a drum defect gets the
  cheapest impact level that serves it; a forced contact-regime level is refused, naming
  the defect and the levels that represent it. Never a one-shoe model: the wave passes the
  shoe at ``k`` times the drum speed, which the other shoe's braking sets (one shoe alone
  stops the drum more slowly: the line of 50 um of ovality differs by 6 %). A drum flat
  (``drum_flat``) likewise: it passes the shoe once per revolution. A worn lining
  (``lining_wear``) is geometry, as a pivot's place: every level represents it.

Pure logic: no numerics, no files.
"""

from __future__ import annotations

from dataclasses import dataclass

from brake_sim_ros.errors import FidelityError
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.catalogue import DRUM_KIND, FLAT_KIND, KIND_BY_NAME, WEAR_KIND

SIDES = L.SIDES
# the solver presets by name (their schemes and steps: solvers/presets.py)
ACCURACY_PRESETS = ("fast", "balanced", "accurate")

# output name -> what it is (units) and what the contact-regime levels give for it
OUTPUTS: dict[str, str] = {
    "stop_time": "instant the brake locks at standstill, s",
    "braking_torque": (
        "friction torque on the drum, N m (contact-regime levels: its impact-averaged,"
        " quasi-static value during the impacting regime)"
    ),
    "contact_regime_forces": (
        "normal, friction and pivot forces of a shoe riding steadily on the drum, N"
        " (the contact-regime mean |F_pivot| over 1-6 s)"
    ),
    "friction_heat": "friction work into the linings, J",
    "torsional_vibration": "flywheel and drum angles and speeds (their twist), rad, rad/s",
    "impacts": "impact onsets, peaks and periods; indentation and regime histories",
    "pivot_forces": "pivot-force history including impacts, N",
    "contact_forces": "indentation, normal and friction force, contact point histories",
    "shoe_motion": "shoe angle and speed histories, rad, rad/s",
    "energy_balance": "every energy term of the balance (closes to rounding), J",
    "measured_signals": (
        "the scenario's sensor channels ([[sensors]]): accelerometers on the structure"
        " (m/s^2), load pins (N), line pressure (bar), wheel speed (pulse and index, 1)"
    ),
}
# defect kind (model/catalogue.py) -> levels that represent it (see module doc)
_ALL_LEVELS = frozenset({"contact_regime_rigid", "contact_regime", "rigid", "full"})
DEFECT_LEVELS: dict[str, frozenset[str]] = {
    "pivot_radius_change": _ALL_LEVELS,
    "initial_angle": _ALL_LEVELS,
    "actuation_share_change": _ALL_LEVELS,
    "friction_change": _ALL_LEVELS,  # a coefficient per lining: the same shoe balance
    "actuation_gain_change": _ALL_LEVELS,  # a gain, as the share's
    # a shaped actuation history: the contact-regime levels reuse a balance while the
    # actuation holds, and a delayed, lagging or pulsating force does not hold
    "actuation_delay": frozenset({"rigid", "full"}),
    "actuation_lag": frozenset({"rigid", "full"}),
    "actuation_pulsation": frozenset({"rigid", "full"}),
    # the spring acts on the force that reaches the shoe in the kernel: the contact-regime
    # levels take the commanded history
    "return_spring_weakening": frozenset({"rigid", "full"}),
    DRUM_KIND: frozenset({"rigid", "full"}),
    # a worn lining is geometry (the lining's radius), as a pivot's place: the same shoe
    # balance; wear that grows is a growth (GROWTH_LEVELS)
    WEAR_KIND: _ALL_LEVELS,
    # a flat passes the shoe once per revolution: the drum angle and the shoes' dynamics,
    # as the harmonics
    FLAT_KIND: frozenset({"rigid", "full"}),
}
# levels that represent a defect changing during the run (an onset after 0 s or a growth
# law): the impact levels step the compiled kernel, which sets each severity at every
# step (model/growth.py); the contact-regime levels reuse a shoe balance while the
# actuation holds, which a changing brake would make wrong
GROWTH_LEVELS = frozenset({"rigid", "full"})
# levels that represent a vehicle's road load and drive on the flywheel ([vehicle],
# [cycle]: model/vehicle.py, model/cycle.py): only the full model. The rigid levels have no
# flywheel apart from the drum (their standstill rule holds the whole rotor, so a grade
# would not reach the brake through the coupling), and the contact-regime levels reuse a
# shoe balance while the actuation holds and have no cycle controller.
DRIVEN_LEVELS = frozenset({"full"})
# outputs that belong to one shoe and do not depend on the other shoe (see module doc)
SHOE_LOCAL_OUTPUTS = frozenset({"impacts", "contact_regime_forces"})
# defects whose effect on a shoe follows the drum speed: no one-shoe model (see module doc)
SPEED_DEPENDENT_DEFECTS = frozenset({DRUM_KIND, FLAT_KIND})
# columns a plan keeps whatever it is asked when the defect changes during the run: a
# lining's wear may follow its friction work, and its labels are read from these
WEAR_COLUMNS: tuple[str, ...] = tuple(f"{s}_lining_wear_m" for s in SIDES)


@dataclass(frozen=True)
class Level:
    """One fidelity level.

    Attributes:
        name: level name used in scenario files and reports.
        dof: mechanical degrees of freedom with both shoes.
        rigid_coupling: flywheel and drum as one body.
        quasi_static_shoes: shoes in static equilibrium on the drum (no impact dynamics).
        outputs: the outputs this level delivers.
        description: one line for reports.
    """

    name: str
    dof: int
    rigid_coupling: bool
    quasi_static_shoes: bool
    outputs: frozenset[str]
    description: str


_CONTACT = frozenset({"stop_time", "braking_torque", "contact_regime_forces", "friction_heat"})
LEVELS: tuple[Level, ...] = (  # cheapest first: the planner takes the first that serves
    Level(
        "contact_regime_rigid",
        1,
        True,
        True,
        frozenset({"contact_regime_forces"}),
        "quasi-static shoes, flywheel and drum as one rigid body",
    ),
    Level(
        "contact_regime",
        2,
        False,
        True,
        _CONTACT,
        "quasi-static shoes, flywheel and drum on the torsional coupling",
    ),
    Level(
        "rigid",
        3,
        True,
        False,
        frozenset({"impacts", "contact_regime_forces"}),
        "impact model (dynamic shoes) with a rigid wheel-drum coupling",
    ),
    Level("full", 4, False, False, frozenset(OUTPUTS), "the full 4-DoF impact model"),
)
LEVEL_BY_NAME = {lv.name: lv for lv in LEVELS}


@dataclass(frozen=True)
class Needs:
    """What a scenario needs.

    Attributes:
        outputs: names from :data:`OUTPUTS`, at least one.
        shoes: shoes whose signals are wanted (a subset of ``("left", "right")``).
        accuracy: solver accuracy preset name (passed through to the solver), or None.
        level: a forced level name, or None to let the planner choose.
        defects: kinds of the scenario's defects (:data:`DEFECT_LEVELS` keys): the level
            must represent them (the scenario loader fills them in from ``[defects]``).
        growing: those of ``defects`` that change during the run: the level must be one
            of :data:`GROWTH_LEVELS`.
        driven: the scenario has a vehicle (road load, a drive cycle): the level must be
            one of :data:`DRIVEN_LEVELS` (the scenario loader sets it).
        thermal: the scenario has a thermal state ([thermal], model/thermal.py): the level
            must be one of :data:`DRIVEN_LEVELS` too (the full model's stepping carries it).
    """

    outputs: tuple[str, ...]
    shoes: tuple[str, ...] = SIDES
    accuracy: str | None = None
    level: str | None = None
    defects: tuple[str, ...] = ()
    growing: tuple[str, ...] = ()
    driven: bool = False
    thermal: bool = False

    def __post_init__(self) -> None:
        unknown = [o for o in self.outputs if o not in OUTPUTS]
        if not self.outputs or unknown or len(set(self.outputs)) != len(self.outputs):
            raise FidelityError(
                f"needs outputs {list(self.outputs)!r}: allowed a non-empty list of distinct"
                f" names from {list(OUTPUTS)}" + (f" (unknown: {unknown})" if unknown else "")
            )
        if (
            not self.shoes
            or len(set(self.shoes)) != len(self.shoes)
            or any(s not in SIDES for s in self.shoes)
        ):
            raise FidelityError(
                f"needs shoes {list(self.shoes)!r}: allowed a non-empty list of distinct names"
                f" from {list(SIDES)}"
            )
        if self.accuracy is not None and self.accuracy not in ACCURACY_PRESETS:
            raise FidelityError(
                f"needs accuracy {self.accuracy!r}: allowed one of {list(ACCURACY_PRESETS)}"
            )
        if self.level is not None and self.level not in LEVEL_BY_NAME:
            raise FidelityError(f"needs level {self.level!r}: allowed one of {list(LEVEL_BY_NAME)}")
        unknown = [d for d in self.defects if d not in DEFECT_LEVELS]
        if unknown:
            raise FidelityError(
                f"needs defects {list(self.defects)!r}: allowed names from"
                f" {list(DEFECT_LEVELS)} (unknown: {unknown})"
            )


@dataclass(frozen=True)
class Plan:
    """The model a scenario gets.

    Attributes:
        level: the chosen level.
        shoes: shoes kept in the model (the others are removed: held retracted, no forces).
        columns: recorded columns kept (names as in ``layout.COLUMNS`` plus
            :data:`DERIVED_COLUMNS`), ``time_s`` first; without needs, ``layout.COLUMNS``.
        accuracy: the accuracy preset passed through, or None.
        reason: one sentence saying why this level was chosen.
        sensors: the scenario's sensor bank is built (and with it the structure, when the
            set has an accelerometer): without needs, or when they ask ``measured_signals``.
    """

    level: Level
    shoes: tuple[str, ...]
    columns: tuple[str, ...]
    accuracy: str | None
    reason: str
    sensors: bool = True


# what a driven run keeps whatever its outputs: the vehicle's speed, its drive and road
# load, their work (the energy books), the cycle's segment (the phase label) and the
# vehicle's load in force with its changes' work (the books and the load label)
DRIVEN_COLUMNS: tuple[str, ...] = (
    "flywheel_speed_rad_s",
    "drive_torque_n_m",
    "road_load_torque_n_m",
    "drive_work_j",
    "road_load_work_j",
    "cycle_segment",
    "flywheel_inertia_kg_m2",
    "load_change_work_j",
)
# columns computed from the recorded ones, appended after layout.COLUMNS
DERIVED_COLUMNS: tuple[str, ...] = ("braking_torque_n_m",)

_SHOE_COLUMNS: dict[str, tuple[str, ...]] = {
    "contact_regime_forces": (
        "{s}_normal_force_n",
        "{s}_friction_force_n",
        "{s}_actuation_force_n",
        "{s}_pivot_fx_n",
        "{s}_pivot_fy_n",
        "{s}_regime",
    ),
    "impacts": (
        "{s}_indentation_m",
        "{s}_indentation_rate_m_s",
        "{s}_actuation_force_n",
        "{s}_pivot_fx_n",
        "{s}_pivot_fy_n",
        "{s}_regime",
    ),
    "pivot_forces": ("{s}_pivot_fx_n", "{s}_pivot_fy_n"),
    "contact_forces": (
        "{s}_indentation_m",
        "{s}_indentation_rate_m_s",
        "{s}_normal_force_n",
        "{s}_friction_force_n",
        "{s}_contact_x_m",
        "{s}_contact_y_m",
        "{s}_sliding_speed_m_s",
    ),
    "shoe_motion": ("{s}_angle_rad", "{s}_speed_rad_s"),
    "energy_balance": ("{s}_speed_rad_s", "{s}_indentation_m"),
}
_EVENT_COLUMNS: dict[str, tuple[str, ...]] = {
    "stop_time": ("regime",),
    "braking_torque": ("braking_torque_n_m",),
    "contact_regime_forces": ("regime",),
    "friction_heat": ("friction_work_j",),
    "torsional_vibration": (
        "flywheel_angle_rad",
        "drum_angle_rad",
        "flywheel_speed_rad_s",
        "drum_speed_rad_s",
    ),
    "impacts": ("regime",),
    # what the sensor bank reads (sensing/sensors.py): both pivot forces (the structure sums
    # them; load pins), both actuation forces (line pressure), the drum angle (tone ring)
    "measured_signals": (
        "drum_angle_rad",
        *(f"{s}_{c}" for s in SIDES for c in ("pivot_fx_n", "pivot_fy_n", "actuation_force_n")),
    ),
    "energy_balance": (
        "flywheel_angle_rad",
        "drum_angle_rad",
        "flywheel_speed_rad_s",
        "drum_speed_rad_s",
        "friction_work_j",
        "coupling_damper_loss_j",
        "contact_loss_j",
        "actuation_work_j",
        "lock_loss_j",
    ),
}


def columns_for(outputs: tuple[str, ...], shoes: tuple[str, ...]) -> tuple[str, ...]:
    """Recorded columns that ``outputs`` need for ``shoes``, ``time_s`` first, no repeats."""
    names = ["time_s"]
    for out in outputs:
        names.extend(_EVENT_COLUMNS.get(out, ()))
        for side in shoes:
            names.extend(c.format(s=side) for c in _SHOE_COLUMNS.get(out, ()))
    return tuple(dict.fromkeys(names))


def levels_serving(output: str) -> list[str]:
    """Names of the levels that deliver ``output``, cheapest first."""
    return [lv.name for lv in LEVELS if output in lv.outputs]


def levels_representing(defect: str) -> list[str]:
    """Names of the levels that represent the defect kind ``defect``, cheapest first."""
    return [lv.name for lv in LEVELS if lv.name in DEFECT_LEVELS[defect]]


def _represents(
    level: Level, defects: tuple[str, ...], growing: tuple[str, ...] = (), driven: bool = False
) -> bool:
    return (
        all(level.name in DEFECT_LEVELS[d] for d in defects)
        and (not growing or level.name in GROWTH_LEVELS)
        and (not driven or level.name in DRIVEN_LEVELS)
    )


def plan(needs: Needs | None, *, model_shoes: tuple[str, ...] = SIDES) -> Plan:
    """Choose the cheapest level serving ``needs`` (None: the full model, every signal).

    Args:
        needs: what the scenario asks for.
        model_shoes: shoes the scenario's own ``[model]`` has (a one-shoe brake); asking
            for a shoe the brake does not have is refused.
    """
    if needs is None:
        return Plan(
            LEVEL_BY_NAME["full"],
            model_shoes,
            L.COLUMNS,
            None,
            "the scenario states no [needs]: the full model, every signal",
            sensors=True,
        )
    missing = [s for s in needs.shoes if s not in model_shoes]
    if missing:
        raise FidelityError(
            f"needs shoes {list(needs.shoes)}: the scenario's brake has only {list(model_shoes)}"
            f" ([model] shoes), so {missing} cannot be delivered"
        )
    asked = set(needs.outputs)
    if needs.level is not None:
        level = LEVEL_BY_NAME[needs.level]
        lacking = [o for o in needs.outputs if o not in level.outputs]
        if lacking:
            out = lacking[0]
            raise FidelityError(
                f"needs level {level.name!r} cannot deliver the output {out!r} ({OUTPUTS[out]}):"
                f" allowed levels for it: {levels_serving(out)}"
            )
        for defect in needs.defects:
            if level.name not in DEFECT_LEVELS[defect]:
                raise FidelityError(
                    f"needs level {level.name!r} cannot represent the defect {defect!r}"
                    f" ({KIND_BY_NAME[defect].description}): allowed levels for it:"
                    f" {levels_representing(defect)}"
                )
        if needs.growing and level.name not in GROWTH_LEVELS:
            raise FidelityError(
                f"needs level {level.name!r} cannot represent the defect {needs.growing[0]!r}"
                " changing during the run (an onset after 0 s or a growth law): allowed"
                f" levels for it: {sorted(GROWTH_LEVELS, key=list(LEVEL_BY_NAME).index)}"
            )
        if needs.thermal and level.name not in DRIVEN_LEVELS:
            raise FidelityError(
                f"needs level {level.name!r} cannot carry the brake's thermal state"
                f" ([thermal]): allowed levels for it: {sorted(DRIVEN_LEVELS)}"
            )
        if needs.driven and level.name not in DRIVEN_LEVELS:
            raise FidelityError(
                f"needs level {level.name!r} cannot represent the vehicle's road load and"
                " drive on the flywheel ([vehicle], [cycle]): allowed levels for it:"
                f" {sorted(DRIVEN_LEVELS)}"
            )
        reason = f"level {level.name!r} forced by the scenario's [needs]"
    else:
        level = next(
            lv
            for lv in LEVELS
            if asked <= lv.outputs
            and _represents(lv, needs.defects, needs.growing, needs.driven or needs.thermal)
        )
        cheaper = [lv for lv in LEVELS if lv.dof < level.dof]
        if cheaper:

            def lack(lv: Level) -> str:
                if not asked <= lv.outputs:
                    return f"{lv.name} lacks {sorted(asked - lv.outputs)[0]}"
                defect = next((d for d in needs.defects if lv.name not in DEFECT_LEVELS[d]), None)
                if needs.driven and lv.name not in DRIVEN_LEVELS:
                    return f"{lv.name} cannot represent the vehicle ([vehicle], [cycle])"
                if needs.thermal and lv.name not in DRIVEN_LEVELS:
                    return f"{lv.name} cannot carry the brake's thermal state ([thermal])"
                if defect is None:
                    return f"{lv.name} cannot represent {needs.growing[0]} changing in time"
                return f"{lv.name} cannot represent {defect}"

            lacks = ", ".join(lack(lv) for lv in cheaper)
            reason = f"the cheapest level delivering {sorted(asked)} ({lacks})"
        else:
            reason = f"the cheapest level; it delivers {sorted(asked)}"
    shoes = model_shoes
    speed_bound = sorted(SPEED_DEPENDENT_DEFECTS.intersection(needs.defects))
    if len(needs.shoes) < len(model_shoes) and asked <= SHOE_LOCAL_OUTPUTS and speed_bound:
        reason += (
            f"; both shoes are modelled: the {speed_bound[0]} defect reaches a shoe at the"
            " drum speed, which the other shoe's braking sets"
        )
    elif len(needs.shoes) < len(model_shoes) and asked <= SHOE_LOCAL_OUTPUTS:
        shoes = needs.shoes
        reason += (
            f"; only the {'/'.join(shoes)} shoe is modelled: {sorted(asked)} of one shoe do not"
            " depend on the other"
        )
    sensors = "measured_signals" in asked
    columns = columns_for(needs.outputs, needs.shoes)
    if needs.driven:
        columns = (*columns, *(c for c in DRIVEN_COLUMNS if c not in columns))
    if needs.thermal and "brake_temperature_c" not in columns:
        columns = (*columns, "brake_temperature_c")
    if not sensors:
        reason += "; no sensors ([needs] do not ask measured_signals): no structure"
    if WEAR_KIND in needs.growing:
        columns = (*columns, *WEAR_COLUMNS)
    return Plan(
        level,
        shoes,
        columns,
        needs.accuracy,
        reason,
        sensors=sensors,
    )
