"""A loaded campaign and the plan of runs it makes.

:class:`Campaign` is what the loader (:mod:`.loader`) reads from a campaign file;
:func:`plan_runs` resolves each of its runs (:class:`RunSpec`: the varied scenario as
TOML, read again by the scenario loader, its unit, seed and split), and
:meth:`Campaign.lock_text` the ``campaign.lock`` a sweep writes beside its runs.
"""

from __future__ import annotations

import copy
import hashlib
import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from brake_sim_ros import __version__
from brake_sim_ros.campaigns.axes import (
    DERIVED_COLUMNS,
    AnyAxis,
    Axis,
    DefectChoice,
    Value,
    condition_points,
    defects_table,
    point_columns,
)
from brake_sim_ros.campaigns.splits import HeldOut, assign_units
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.scenarios.toml_text import dumps

# samples of one run: the run's history is kept in memory to be written (about 40 float64
# columns: 2e6 samples is some 650 MB with the table's copy)
MAX_RUN_SAMPLES = 2_000_000


class CampaignError(BrakeSimError, ValueError):
    """A campaign file that cannot be loaded, in one line naming the file and the key."""


@dataclass(frozen=True)
class Outputs:
    """What every run writes.

    Attributes:
        duration_s: simulated time per run, s (None: the base scenario's).
        sample_rate_hz: output samples per second (None: the base scenario's).
        columns: the history columns kept (``sample_index``, ``time_s``, the label
            columns and ``rul [s]`` are always kept); empty: every column.
    """

    duration_s: float | None = None
    sample_rate_hz: float | None = None
    columns: tuple[str, ...] = ()


@dataclass(frozen=True)
class RunSpec:
    """One run of a campaign, resolved: everything a worker needs, and its manifest row.

    Attributes:
        run_id: ``run-NNNNN``, its index among the campaign's unit x condition pairs.
        unit_id: the brake unit it runs on.
        seed: the scenario seed (an axis's, or derived from the campaign seed and the
            run's identity with :class:`numpy.random.SeedSequence`).
        split: ``train``, ``validation`` or ``test``.
        columns: the varied values by manifest column.
        labels: the defect label columns (``defect:<kind>:<location> [<unit>]``) -> severity.
        scenario_text: the varied scenario as TOML (what the scenario loader read).
        duration_s: its simulated duration, s.
        keep: the history columns to keep (empty: all).
    """

    run_id: str
    unit_id: str
    seed: int
    split: str
    columns: dict[str, Value]
    labels: dict[str, float]
    scenario_text: str
    duration_s: float
    keep: tuple[str, ...] = ()


@dataclass(frozen=True)
class Campaign:
    """A loaded campaign file.

    Attributes (some):
        base: the base scenario as the file names it; ``base_text`` its TOML.
        brake: the brake the runs run on ("study" or "service"): the campaign's key
            ``brake``, set on the base scenario (``base_data``), or the base's own.
    """

    name: str
    description: str
    source: str
    text: str
    base: str
    base_text: str
    brake: str
    seed: int
    unit_ids: tuple[str, ...]
    outputs: Outputs
    axes: tuple[AnyAxis, ...]
    draw_method: str
    draw_count: int
    fractions: dict[str, float]
    held_out: tuple[HeldOut, ...]
    base_data: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)

    def runs(self) -> list[RunSpec]:
        """Every run, in run-id order (see :func:`plan_runs`)."""
        return plan_runs(self)

    def lock_text(self, runs: list[RunSpec]) -> str:
        """The ``campaign.lock``: the campaign and base scenario texts, the library version
        and every run resolved (JSON, keys sorted, so the same campaign gives the same
        bytes)."""
        body = {
            "campaign": self.name,
            "campaign_source": self.source,
            "campaign_sha256": hashlib.sha256(self.text.encode()).hexdigest(),
            "campaign_toml": self.text,
            "base_toml": self.base_text,
            "version": __version__,
            "held_out": [vars(h) for h in self.held_out],
            "runs": [
                {
                    "run_id": r.run_id,
                    "unit_id": r.unit_id,
                    "seed": r.seed,
                    "split": r.split,
                    "columns": r.columns,
                    "scenario_sha256": hashlib.sha256(r.scenario_text.encode()).hexdigest(),
                }
                for r in runs
            ],
        }
        return json.dumps(body, sort_keys=True, indent=1) + "\n"


# --- planning -------------------------------------------------------------------------------
# --- planning ------------------------------------------------------------------------------
def _set(data: dict[str, Any], key: str, value: Any, where: str) -> None:
    """Set the dotted ``key`` in the TOML data (tables made as needed)."""
    parts = key.split(".")
    table = data
    for part in parts[:-1]:
        table = table.setdefault(part, {})
        if not isinstance(table, dict):
            raise CampaignError(
                f"{where}: key '{key}': '{part}' is not a table in the base scenario"
            )
    table[parts[-1]] = value


def run_seed(campaign_seed: int, unit_id: str, columns: dict[str, Value]) -> int:
    """A run's seed from the campaign seed and the run's identity (its unit and varied
    values), through :class:`numpy.random.SeedSequence`: the same run, the same seed,
    whatever else the campaign holds; never Python's salted ``hash()``."""
    identity = json.dumps({"unit_id": unit_id, **columns}, sort_keys=True).encode()
    digest = hashlib.sha256(identity).digest()
    words = tuple(int.from_bytes(digest[i : i + 4], "little") for i in range(0, 32, 4))
    state = np.random.SeedSequence(campaign_seed, spawn_key=words).generate_state(2, np.uint64)
    return int(((int(state[0]) << 64) | int(state[1])) % 2**63)


def plan_runs(campaign: Campaign) -> list[RunSpec]:
    """Every run of ``campaign``: each unit x each condition point (units outer), a run id
    by that index; a condition with a held-out value runs on test units only (its index is
    skipped on the others). Each varied scenario is read by the scenario loader.

    Raises:
        CampaignError: a varied scenario the scenario loader refuses (naming the run).
    """
    base = campaign.base_data
    points = condition_points(
        campaign.axes, campaign.draw_method, campaign.draw_count, campaign.seed
    )
    split_of = assign_units(campaign.unit_ids, campaign.fractions, campaign.seed)
    axes = {a.name: a for a in campaign.axes}
    runs = []
    index = 0
    for unit in campaign.unit_ids:
        for point in points:
            run_id = f"run-{index:05d}"
            index += 1
            columns = point_columns(point)
            held = any(rule.matches(columns) for rule in campaign.held_out)
            split = split_of[unit]
            if held and split != "test":
                continue
            data = copy.deepcopy(base)
            where = f"{campaign.source} {run_id}"
            for name, value in point.items():
                if isinstance(value, DefectChoice):
                    data["defects"] = defects_table(value.defects())
                else:
                    _set(data, axes[name].key, value, where)
            if campaign.outputs.duration_s is not None:
                data["duration_s"] = campaign.outputs.duration_s
            if campaign.outputs.sample_rate_hz is not None:
                data["sample_rate_hz"] = campaign.outputs.sample_rate_hz
            seeded = any(isinstance(a, Axis) and a.key == "seed" for a in campaign.axes)
            identity = {
                k: v
                for k, v in columns.items()
                if k not in DERIVED_COLUMNS and not (k == "defect_repeat" and v == 0)
            }
            seed = data.get("seed", 0) if seeded else run_seed(campaign.seed, unit, identity)
            # the units are one fleet: each the same brake in all its runs (its scatter is
            # drawn from the unit id and the fleet seed), each run its own noise and draws
            data.setdefault("fleet_seed", campaign.seed)
            data.update(name=f"{campaign.name}.{run_id}", unit_id=unit, seed=seed)
            text = dumps(data)
            try:
                scenario = parse_scenario(text, where)
            except BrakeSimError as exc:
                raise CampaignError(f"{exc} (a varied scenario of the campaign)") from None
            samples = scenario.duration_s * scenario.sample_rate_hz
            if samples > MAX_RUN_SAMPLES:
                raise CampaignError(
                    f"{where}: {scenario.duration_s:g} s at {scenario.sample_rate_hz:g} Hz is"
                    f" {samples:.3g} samples: allowed at most {MAX_RUN_SAMPLES} per run (the run"
                    " is kept in memory to be written); shorten the runs or lower the rate"
                )
            defect = next((v for v in point.values() if isinstance(v, DefectChoice)), None)
            if defect is not None and scenario.setup.defects != defect.defects():
                raise CampaignError(f"{where}: the defect axis's defect did not reach the scenario")
            runs.append(
                RunSpec(
                    run_id=run_id,
                    unit_id=unit,
                    seed=seed,
                    split=split,
                    columns=columns,
                    labels=scenario.setup.defects.severities(),
                    scenario_text=text,
                    duration_s=scenario.duration_s,
                    keep=campaign.outputs.columns,
                )
            )
    return runs
