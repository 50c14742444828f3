"""The backing plate and knuckle as a small linear modal structure loaded by the pivots.

Frame ``brake_backing_plate`` (x right, y up). The pivot columns of a sample block are the
force the pin exerts on the shoe; the backing plate receives the opposite, and that is the
load applied here. Each in-plane mode ``k`` (direction x or y) obeys

    m_k (q_k'' + 2 zeta_k w_k q_k' + w_k^2 q_k)
        = phi_k(left pin) F_left,d + phi_k(right pin) F_right,d

with ``q_k`` the modal coordinate (m, the displacement of the mode where its shape is 1),
``m_k`` the modal mass for that normalisation, and ``phi_k(point)`` the mode-shape value
at a point (dimensionless). At a named mount point the acceleration along the mode's
direction is ``sum_k phi_k(mount) q_k''`` (m/s^2) and the displacement ``sum_k phi_k(mount)
q_k`` (m). Every mode is integrated exactly per sample (:mod:`.lti`, first-order hold).

**Defaults, to be identified on a real brake.** Two modes per in-plane direction, inside
the drum-brake noise band 0.85-4.6 kHz (TESTBED.md, "Signals measured in practice"): a first
mode near 1.2 kHz (x) / 1.45 kHz (y), in which the plate with the anchor moves as one
(both pins in phase), and a second near 3.4 kHz (x) / 3.8 kHz (y), a bending mode with the
pins in antiphase. Damping ratios 2 % and 1.5 %: lightly damped bolted steel. Modal masses
5 kg (plate, anchor and the knuckle's share) and 1.5 kg (the plate bending): the order of a
pressed-steel backing plate bolted to a knuckle. No measured backing-plate modes of this
brake exist; these values put the structure's resonances where drum-brake noise is
reported, and nothing more. The x and y frequencies differ so that the two directions can be
told apart in a spectrum.

**One-way coupling.** The structure's motion does not feed back into the contact model.
The plate deflects by micrometres: a static 2 kN on the default first mode (5 kg at
1.2 kHz) gives 7 um, and the published event peaks at 23 um at the backing plate during the
first impacts (:class:`Structure` reports the displacements), against a running clearance
of 3.6 mm and indentations up to 0.14 mm. What would feed back is the pin's motion relative
to the drum's axis, and the drum turns on a hub carried by the same knuckle, so less than
that. The neglect is small in steady contact; in the first impacts the plate's absolute
motion reaches a sixth of the peak indentation, an upper bound on what is left out. A
two-way coupling is the step to take if the plate's modes are to change the impacts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.sensing.lti import LtiState, SampledLti, foh_discretise

AXES = ("x", "y")
# the load, in input order: the pivot forces (frame brake_backing_plate), sign-flipped
FORCE_COLUMNS: tuple[str, ...] = tuple(f"{s}_pivot_f{a}_n" for s in SIDES for a in AXES)
DEFAULT_MOUNTS: tuple[str, ...] = ("backing_plate", "knuckle")


def acceleration_output(mount: str, axis: str) -> str:
    """The name of the structure's output that is the acceleration at ``mount`` along
    ``axis`` (frame brake_backing_plate), m/s^2: what an accelerometer there reads."""
    return f"{mount}_accel_{axis}_m_s2"


def _require(condition: bool, what: str, value: object, allowed: str) -> None:
    if not condition:
        raise ParameterError(f"structure: {what} = {value!r} is invalid: allowed {allowed}")


@dataclass(frozen=True)
class Mode:
    """One in-plane mode of the backing plate and knuckle.

    Attributes:
        direction: "x" or "y" (frame brake_backing_plate): the direction it moves and is
            loaded in.
        frequency_hz: undamped natural frequency, Hz.
        damping_ratio: modal damping ratio zeta (dimensionless, 0 < zeta < 1).
        modal_mass_kg: modal mass for the shape normalisation below, kg.
        left_pin: mode-shape value at the left (leading) pivot pin: its participation in the
            left pivot force (dimensionless).
        right_pin: the same at the right (trailing) pin.
        at_mounts: mode-shape value at each mount point, in the order of
            :attr:`StructureParameters.mounts`.
    """

    direction: str
    frequency_hz: float
    damping_ratio: float
    modal_mass_kg: float
    left_pin: float
    right_pin: float
    at_mounts: tuple[float, ...]

    def __post_init__(self) -> None:
        _require(self.direction in AXES, "mode direction", self.direction, f"one of {AXES}")
        _require(
            math.isfinite(self.frequency_hz) and 1.0 <= self.frequency_hz <= 1e5,
            "mode frequency_hz",
            self.frequency_hz,
            "1 to 1e5 Hz",
        )
        _require(
            math.isfinite(self.damping_ratio) and 0.0 < self.damping_ratio < 1.0,
            "mode damping_ratio",
            self.damping_ratio,
            "> 0 and < 1",
        )
        _require(
            math.isfinite(self.modal_mass_kg) and self.modal_mass_kg > 0.0,
            "mode modal_mass_kg",
            self.modal_mass_kg,
            "> 0 kg",
        )
        for name in ("left_pin", "right_pin"):
            value = getattr(self, name)
            _require(math.isfinite(value), f"mode {name}", value, "a finite number")
        _require(
            all(math.isfinite(v) for v in self.at_mounts),
            "mode at_mounts",
            self.at_mounts,
            "finite numbers",
        )

    @property
    def omega_rad_s(self) -> float:
        return 2.0 * math.pi * self.frequency_hz

    @property
    def stiffness_n_m(self) -> float:
        """Modal stiffness m w^2, N/m."""
        return self.modal_mass_kg * self.omega_rad_s**2


def _default_modes() -> tuple[Mode, ...]:
    # (frequency, damping, modal mass, left pin, right pin, backing plate, knuckle)
    first = (0.02, 5.0, 1.0, 1.0, 0.8, 0.4)  # plate and anchor in phase
    second = (0.015, 1.5, 0.9, -0.9, 1.0, 0.1)  # bending, pins in antiphase
    return (
        Mode("x", 1200.0, *first[:4], first[4:]),
        Mode("x", 3400.0, *second[:4], second[4:]),
        Mode("y", 1450.0, *first[:4], first[4:]),
        Mode("y", 3800.0, *second[:4], second[4:]),
    )


@dataclass(frozen=True)
class StructureParameters:
    """The modal structure: named mount points and the modes (defaults: module docstring).

    Attributes:
        mounts: names of the points where sensors can be mounted.
        modes: the in-plane modes; each gives its shape value at every mount.
    """

    mounts: tuple[str, ...] = DEFAULT_MOUNTS
    modes: tuple[Mode, ...] = field(default_factory=_default_modes)

    def __post_init__(self) -> None:
        _require(
            len(self.mounts) > 0 and len(set(self.mounts)) == len(self.mounts),
            "mounts",
            self.mounts,
            "a non-empty list of distinct names",
        )
        _require(len(self.modes) > 0, "modes", self.modes, "at least one mode")
        for i, mode in enumerate(self.modes):
            _require(
                len(mode.at_mounts) == len(self.mounts),
                f"modes[{i}].at_mounts",
                mode.at_mounts,
                f"one value per mount {list(self.mounts)}",
            )

    def output_names(self) -> tuple[str, ...]:
        """Output channels of :class:`Structure`, in order: acceleration (m/s^2) then
        displacement (m) at each mount along x and y."""
        acc = tuple(acceleration_output(m, a) for m in self.mounts for a in AXES)
        disp = tuple(f"{m}_disp_{a}_m" for m in self.mounts for a in AXES)
        return acc + disp

    def continuous(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, C, D)``: state ``[q_0, q_0', q_1, q_1', ...]``, inputs the pivot
        forces in :data:`FORCE_COLUMNS` order (N; ``B`` applies their opposite to the
        plate), outputs :meth:`output_names`."""
        n_modes, n_mounts = len(self.modes), len(self.mounts)
        a = np.zeros((2 * n_modes, 2 * n_modes))
        b = np.zeros((2 * n_modes, len(FORCE_COLUMNS)))
        c = np.zeros((4 * n_mounts, 2 * n_modes))
        d = np.zeros((4 * n_mounts, len(FORCE_COLUMNS)))
        for k, mode in enumerate(self.modes):
            w, z, mass = mode.omega_rad_s, mode.damping_ratio, mode.modal_mass_kg
            axis = AXES.index(mode.direction)
            load = np.zeros(len(FORCE_COLUMNS))  # generalised force per unit input, / m
            for s, pin in enumerate((mode.left_pin, mode.right_pin)):
                load[FORCE_COLUMNS.index(f"{SIDES[s]}_pivot_f{mode.direction}_n")] = pin / mass
            a[2 * k, 2 * k + 1] = 1.0
            a[2 * k + 1, 2 * k] = -(w**2)
            a[2 * k + 1, 2 * k + 1] = -2.0 * z * w
            b[2 * k + 1] = -load  # the plate receives the opposite of the pin's force
            for j, shape in enumerate(mode.at_mounts):
                acc_row = 2 * j + axis
                disp_row = 2 * n_mounts + 2 * j + axis
                c[acc_row, 2 * k : 2 * k + 2] += shape * a[2 * k + 1, 2 * k : 2 * k + 2]
                d[acc_row] += shape * b[2 * k + 1]
                c[disp_row, 2 * k] += shape
        return a, b, c, d

    def sampled(self, sample_period_s: float) -> SampledLti:
        """The exact per-sample recursion at ``sample_period_s``."""
        _require(
            math.isfinite(sample_period_s) and sample_period_s > 0.0,
            "sample period",
            sample_period_s,
            "> 0 s",
        )
        return foh_discretise(*self.continuous(), sample_period_s)


class Structure:
    """The structure driven by a stream of sample blocks; the modal state is carried from
    block to block, so a stream in blocks equals one long run bit for bit.

    ``outputs`` names the outputs computed (:meth:`StructureParameters.output_names`, in
    the order wanted; default all of them): a sensor set reads only its accelerometers'."""

    def __init__(
        self,
        params: StructureParameters,
        sample_period_s: float,
        outputs: tuple[str, ...] | None = None,
    ) -> None:
        self.params = params
        every = params.output_names()
        self.names = every if outputs is None else tuple(outputs)
        unknown = [n for n in self.names if n not in every]
        _require(not unknown, "outputs", unknown, f"names among {list(every)}")
        self.system = params.sampled(sample_period_s)
        self._state = LtiState(self.system, tuple(every.index(n) for n in self.names))

    def forces(self, block: SampleBlock) -> np.ndarray:
        """The pivot-force columns of ``block`` (n, 4), N, in :data:`FORCE_COLUMNS` order."""
        return np.column_stack([block[c] for c in FORCE_COLUMNS])

    def advance(self, block: SampleBlock) -> np.ndarray:
        """The outputs (n, len(names)) for the next block: accelerations, m/s^2, and
        displacements, m."""
        return self.advance_forces(self.forces(block))

    def advance_forces(self, pivot_forces_n: np.ndarray) -> np.ndarray:
        """The same from the pivot forces themselves, shape (n, 4), N."""
        return self._state.advance(pivot_forces_n)
