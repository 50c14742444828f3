"""Blocks of recorded samples and the description of a whole braking model setup."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from brake_sim_ros.model import layout as L
from brake_sim_ros.model.actuation import Actuation
from brake_sim_ros.model.assembly import ModelOptions
from brake_sim_ros.model.cycle import Cycle
from brake_sim_ros.model.defects import Defects
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.thermal import DEFAULT_TEMPERATURE_C, Thermal
from brake_sim_ros.model.vehicle import Vehicle


@dataclass(frozen=True)
class BrakeSetup:
    """Everything that defines a braking event apart from the numerical method.

    ``vehicle``: road load and grade on the flywheel (model/vehicle.py); None: the
    published model, no external torque. ``cycle``: a drive cycle (model/cycle.py) that
    commands the drive torque and the brake force instead of ``actuation``; it needs a
    vehicle. ``thermal``: the brake's temperature as a state, heated by friction and acting
    on it through the fade law (model/thermal.py); None: the brake is held at
    ``held_temperature_c`` (deg C; the run's conditions set it, and with it the friction,
    fleet/conditions.py), which is recorded.
    """

    params: BrakeParameters = field(default_factory=BrakeParameters)
    defects: Defects = field(default_factory=Defects)
    actuation: Actuation = field(default_factory=Actuation.published_ramp)
    options: ModelOptions = field(default_factory=ModelOptions)
    vehicle: Vehicle | None = None
    cycle: Cycle | None = None
    thermal: Thermal | None = None
    held_temperature_c: float = DEFAULT_TEMPERATURE_C

    @property
    def driven(self) -> bool:
        """Whether a vehicle's road load (and a cycle's drive) act on the flywheel."""
        return self.vehicle is not None

    @property
    def start_temperature_c(self) -> float | None:
        """The thermal state's temperature at the start, deg C (None: no thermal state)."""
        return None if self.thermal is None else self.thermal.start_c

    @property
    def peak_force_n(self) -> float:
        """The largest actuation force per shoe commanded, N: the cycle's with a cycle,
        else the actuation profile's."""
        if self.cycle is not None:
            return self.cycle.peak_force_n
        return max(self.actuation.left.peak_n, self.actuation.right.peak_n)


@dataclass(frozen=True)
class SampleBlock:
    """Consecutive samples, one row per sample, one column per name in ``columns``.

    Attributes:
        data: float64 array, shape (n_samples, len(columns)). Units are in the column
            names; vectors are in the backing-plate frame.
        first_index: running index of the first row since the start of the event.
        sample_period_s: time between rows, s.
        columns: column names, ``layout.COLUMNS`` by default; a run restricted to what a
            scenario needs keeps a subset (``time_s`` always first).
    """

    data: np.ndarray
    first_index: int
    sample_period_s: float
    columns: tuple[str, ...] = L.COLUMNS

    def __len__(self) -> int:
        return int(self.data.shape[0])

    def __getitem__(self, name: str) -> np.ndarray:
        return self.data[:, self.index_of(name)]

    def index_of(self, name: str) -> int:
        """Position of column ``name`` along the second axis of ``data`` (for reading one
        row, ``data[row, index_of(name)]``, without a column view per value)."""
        try:
            return L.COL[name] if self.columns is L.COLUMNS else self.columns.index(name)
        except (KeyError, ValueError):
            raise KeyError(
                f"column {name!r} is not in this sample block: it holds {list(self.columns)}"
            ) from None

    def has(self, *names: str) -> bool:
        """Whether every column in ``names`` is recorded."""
        return all(n in self.columns for n in names)

    def select(self, columns: tuple[str, ...]) -> SampleBlock:
        """A block with only ``columns`` (each must be present), as a compact copy."""
        idx = [self.columns.index(c) for c in columns]
        return SampleBlock(
            np.ascontiguousarray(self.data[:, idx]), self.first_index, self.sample_period_s, columns
        )

    @property
    def time_s(self) -> np.ndarray:
        """Sample times, s (the ``time_s`` column)."""
        return self["time_s"]

    def pivot_force_magnitude(self, side: str) -> np.ndarray:
        """|F_pivot| of one shoe, N."""
        return np.hypot(self[f"{side}_pivot_fx_n"], self[f"{side}_pivot_fy_n"])

    @staticmethod
    def concatenate(blocks: list[SampleBlock]) -> SampleBlock:
        if not blocks:
            raise ValueError("no sample blocks to concatenate")
        return SampleBlock(
            np.concatenate([b.data for b in blocks]),
            blocks[0].first_index,
            blocks[0].sample_period_s,
            blocks[0].columns,
        )

    def as_dict(self) -> dict[str, np.ndarray]:
        return {name: self.data[:, i] for i, name in enumerate(self.columns)}
