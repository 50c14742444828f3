"""Energy bookkeeping of a recorded run: what the model stores, spends and is supplied.

The state carries four energy quadratures integrated with the motion (layout.Y_*):
friction work, coupling-damper loss, contact loss (Kelvin-Voigt, the strain a wearing
lining's worn layer takes away, ``contact.wear_loss``, and what a defect growing with a
law of time moves at each step of the geometry, model/growth_energy.py) and actuator
work; the stepper
adds the kinetic energy removed when the brake locks (``lock_loss_j``). Between any two
samples of one run

    stored(first) + actuator work = stored(last) + friction + damper + contact + lock losses

where ``stored`` is the kinetic energy of flywheel, drum and shoes (about their pivots)
plus the elastic energy of the coupling spring and of the contacts (``k_c eps^2 / 2``
while the lining penetrates). The residual of that identity is the integration error of
the whole event; it can fail, since the quadratures and the motion are independent sums.
A run whose drive cycle changes the vehicle's load (model/cycle.py) stores the flywheel's
kinetic energy with the inertia in force at each sample (``flywheel_inertia_kg_m2``) and
is supplied the kinetic energy its load changes brought (``load_change_work_j``).
With ``packed`` (the run's packed parameters), each end's stored energy is read with the
parameters in force at its time (:func:`parameters_at`: growing defects as they were).
The service brake (model/service.py) also stores energy in its return springs and rest
stops (from the shoe angles and the packed parameters, which place them for the run's
defects) and in its hydraulic circuit's compliance, ``C p^2 / 2`` (the line pressure
``p`` read from the pistons' recorded forces, :func:`line_pressure_pa`); its stops'
dampers and its line's resistance lose theirs into ``contact_loss_j``, and its actuator
work is the source's (``p_s`` times the flow into the line) and the pistons' own. Its
flywheel and drum are coupled by its tyre (model/tyre.py), not by the coupling spring:
``coupling_damper_loss_j`` is the tyre's work, what the rotors gave it (its tread's stored
energy, at most 42 J on a dry road, and its losses), and no coupling spring is stored.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from brake_sim_ros.model import growth, lining, service
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import SIDES
from brake_sim_ros.model.growth_law import LAW_FRICTION_WORK
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.run_setup import SampleBlock

_LOSSES = ("friction_work_j", "coupling_damper_loss_j", "contact_loss_j", "lock_loss_j")
# a vehicle's (model/vehicle.py): the drive's work in, the road load's out; read when kept
_VEHICLE_WORK = ("drive_work_j", "road_load_work_j")
# the flywheel inertia in force and the load changes' work; read when kept (else the
# parameters' inertia, which is the column's value for a run whose load never changes)
_LOAD_COLUMNS = ("flywheel_inertia_kg_m2", "load_change_work_j")
# every column the books read (a run restricted to some outputs may not keep them all)
ENERGY_COLUMNS: tuple[str, ...] = (
    "flywheel_angle_rad",
    "drum_angle_rad",
    "flywheel_speed_rad_s",
    "drum_speed_rad_s",
    *(f"{s}_{name}" for s in SIDES for name in ("speed_rad_s", "indentation_m")),
    "actuation_work_j",
    *_LOSSES,
)


@dataclass(frozen=True)
class EnergyBalance:
    """Energy books between the first and the last sample of a block, J.

    Attributes:
        stored_start_j: kinetic + elastic energy at the first sample.
        stored_end_j: kinetic + elastic energy at the last sample.
        supplied_j: actuator work (and a vehicle's drive work) done between them.
        spent_j: friction, coupling-damper, contact and lock losses (and a vehicle's
            road-load work) between them.
        residual_j: ``stored_start + supplied - stored_end - spent`` (0 for exact books).
    """

    stored_start_j: float
    stored_end_j: float
    supplied_j: float
    spent_j: float
    residual_j: float

    @property
    def turnover_j(self) -> float:
        """Energy that entered the books: what was stored at the start plus what was supplied."""
        return self.stored_start_j + abs(self.supplied_j)

    @property
    def relative_residual(self) -> float:
        """``|residual| / stored_start``: for a run from t = 0, the residual as a fraction of
        the initial kinetic energy (the figure the work-precision and fidelity studies
        report)."""
        return abs(self.residual_j) / self.stored_start_j


def parameters_at(packed: np.ndarray, block: SampleBlock, row: int) -> np.ndarray:
    """The packed parameters in force at row ``row`` of ``block``: ``packed`` (a run's,
    whose defects are at their final severity) with its growing defects at the row's
    time (:func:`.growth.apply`; a lining that wears with its friction work at the row's
    recorded wear). A self-adjuster's take-up within the run is not in them: it moves a
    lining only while it is clear of the drum (model/ratchet.py), which stores nothing."""
    if packed[L.P_GROWTH_COUNT] <= 0.0:
        return packed
    pw = growth.working_copy(packed)
    y = np.zeros(L.N_STATE_SERVICE)
    entries = range(int(packed[L.P_GROWTH_COUNT]))
    laws = {int(packed[L.P_GROWTH_BASE + j * L.GROWTH_STRIDE + L.G_LAW]) for j in entries}
    if LAW_FRICTION_WORK in laws:  # the wear state it reads
        for i, side in enumerate(SIDES):
            y[L.Y_LEFT_WEAR + i] = block[f"{side}_lining_wear_m"][row]
    growth.apply(packed, pw, float(block["time_s"][row]), y, growth.ALL_ENTRIES)
    return pw


def stored_energy_j(
    block: SampleBlock,
    params: BrakeParameters,
    row: int,
    *,
    point_contact: bool = True,
    packed: np.ndarray | None = None,
) -> float:
    """Kinetic plus elastic energy at row ``row`` of ``block`` (columns read by name), J;
    without the point contacts' ``k_c eps^2 / 2`` if not ``point_contact`` (a lining over
    its arc stores :func:`lining_energy_j` instead). The shoes' inertias about their
    pivots are ``packed``'s (the parameters in force at the row, :func:`parameters_at`:
    a pivot out of place changes them), else the nominal shoe's."""
    d = params.driveline
    if packed is None:
        i_l = i_r = params.shoe.inertia_about_pivot_kg_m2
    else:
        i_l = packed[L.P_SHOE_BASE + L.S_INERTIA]
        i_r = packed[L.P_SHOE_BASE + L.SHOE_STRIDE + L.S_INERTIA]

    def at(name: str) -> float:  # a numpy float64, as the arithmetic below expects
        return block[name][row]

    i_f = at("flywheel_inertia_kg_m2") if block.has(*_LOAD_COLUMNS) else d.flywheel_inertia_kg_m2
    kinetic = (
        0.5 * i_f * at("flywheel_speed_rad_s") ** 2
        + 0.5 * d.drum_inertia_kg_m2 * at("drum_speed_rad_s") ** 2
        + 0.5 * i_l * at("left_speed_rad_s") ** 2
        + 0.5 * i_r * at("right_speed_rad_s") ** 2
    )
    twist = at("flywheel_angle_rad") - at("drum_angle_rad")
    # the service brake's tyre replaces the coupling spring (its work is booked whole)
    k_s = d.coupling_stiffness_n_m_per_rad if params.service is None else 0.0
    k_c = params.contact_stiffness_n_per_m if point_contact else 0.0
    elastic = 0.5 * k_s * twist**2 + sum(
        0.5 * k_c * max(float(at(f"{s}_indentation_m")), 0.0) ** 2 for s in SIDES
    )
    return float(kinetic + elastic)


def spring_energy_j(block: SampleBlock, packed: np.ndarray, rows: list[int]) -> list[float]:
    """Elastic energy of the service brake's return springs and rest stops (J) at ``rows``
    of ``block``, for the run's packed parameters ``packed`` (its stepper's
    ``packed_parameters``)."""
    left = np.array([block["left_angle_rad"][r] for r in rows], dtype=float)
    right = np.array([block["right_angle_rad"][r] for r in rows], dtype=float)
    return [float(e) for e in service.stored_energy_rows(packed, left, right)]


def lining_energy_j(block: SampleBlock, packed: np.ndarray, rows: list[int]) -> list[float]:
    """Elastic energy of the service brake's linings over their arcs (model/lining.py),
    J, at ``rows`` of ``block``."""
    left, right, drum = (
        np.array([block[name][r] for r in rows], dtype=float)
        for name in ("left_angle_rad", "right_angle_rad", "drum_angle_rad")
    )
    return [float(e) for e in lining.stored_energy_rows(packed, left, right, drum)]


def line_pressure_pa(
    block: SampleBlock, packed: np.ndarray, rows: list[int] | None = None
) -> np.ndarray:
    """The service brake's line pressure at every row of ``block`` (or at ``rows``), Pa:
    the pistons' mean recorded force over the piston area (model/service.py: each piston
    pushes ``A p`` plus its own commanded force's departure from the pistons' mean, so
    their mean is ``A p``), exact while neither piston sits at its residual force."""
    left, right = block["left_actuation_force_n"], block["right_actuation_force_n"]
    if rows is not None:
        left, right = left[rows], right[rows]
    return 0.5 * (left + right) / packed[L.P_PISTON_AREA]


def line_energy_j(block: SampleBlock, packed: np.ndarray, rows: list[int]) -> list[float]:
    """Energy the service brake's hydraulic circuit stores, ``C p^2 / 2`` and its air's
    (J, :func:`.service.line_energy`), at ``rows`` of ``block`` (:func:`line_pressure_pa`
    there only)."""
    pressure = line_pressure_pa(block, packed, rows)
    return [float(service.line_energy.py_func(packed, float(p))) for p in pressure]


def energy_balance(
    block: SampleBlock, params: BrakeParameters, *, packed: np.ndarray | None = None
) -> EnergyBalance:
    """Energy books of ``block`` (one run, samples in order) for the model ``params``;
    a service brake's also need the run's packed parameters ``packed`` (its springs).

    Raises:
        ValueError: for an empty block, or a service brake without ``packed``.
        KeyError: ``block`` lacks one of :data:`ENERGY_COLUMNS` (check with
            ``block.has(*ENERGY_COLUMNS)``).
    """
    if len(block) == 0:
        raise ValueError("energy_balance needs at least one sample")
    if params.service is not None and packed is None:
        raise ValueError(
            "energy_balance of a service brake needs packed= (the run's packed"
            " parameters: where its springs and stops sit for its defects)"
        )
    lined = packed is not None and packed[L.P_LINING_NODE_STIFFNESS] > 0.0

    def stored(row: int) -> float:
        at = None if packed is None else parameters_at(packed, block, row)
        energy = stored_energy_j(block, params, row, point_contact=not lined, packed=at)
        if params.service is not None:
            energy += spring_energy_j(block, at, [row])[0] + line_energy_j(block, at, [row])[0]
        if lined:
            energy += lining_energy_j(block, at, [row])[0]
        return energy

    start, end = stored(0), stored(len(block) - 1)
    work = block["actuation_work_j"]
    supplied = float(work[-1] - work[0])
    spent = float(sum(block[name][-1] - block[name][0] for name in _LOSSES))
    if block.has(*_VEHICLE_WORK):  # a vehicle's drive in and road load out (model/vehicle.py)
        drive, road = (block[name][-1] - block[name][0] for name in _VEHICLE_WORK)
        supplied = float(supplied + drive)
        spent = float(spent + road)
    if block.has(*_LOAD_COLUMNS):  # a cycle's load changes at standstill (model/cycle.py)
        load = block["load_change_work_j"]
        supplied = float(supplied + (load[-1] - load[0]))
    return EnergyBalance(
        stored_start_j=start,
        stored_end_j=end,
        supplied_j=supplied,
        spent_j=spent,
        residual_j=start + supplied - end - spent,
    )
