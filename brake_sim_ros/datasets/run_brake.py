"""Which brake a run's samples come from, read from its Parquet file's metadata.

A run's table (``simulate --out run.parquet``, each run of a sweep) records its brake,
``"study"`` or ``"service"`` (``model.parameters.BRAKES``), under ``brake`` in its
``brake_sim`` metadata (:mod:`.parquet`). A detector fitted on one brake's samples judges
nothing on the other's (springs, rest stops, hydraulics, tyre and clearance change every
signal), so what reads a run for a detector reads its brake here.

Files written before the field existed: their metadata holds the scenario's text
(``scenario_toml``, in every file since the first sweep), and a scenario's brake is its
top-level ``brake`` key, ``"study"`` without one (the scenario loader's default, and the
only brake before the service brake arrived): that text gives the brake exactly. A file
with neither is refused in one line.
"""

from __future__ import annotations

import json
import tomllib

import pyarrow as pa

from brake_sim_ros.datasets.checked import DatasetError
from brake_sim_ros.model.parameters import BRAKES, DEFAULT_BRAKE

# a run table's key-value metadata key (its JSON, :mod:`.parquet`), here rather than in the
# writer, which imports the physics, and within it the key of the brake
METADATA_KEY = b"brake_sim"
BRAKE_KEY = "brake"


def _from_scenario_text(text: object) -> object:
    """The brake a scenario's text gives: its top-level ``brake`` key, else the default."""
    if not isinstance(text, str):
        return None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        return None
    return data.get("brake", DEFAULT_BRAKE)


def recorded_brake(table: pa.Table, where: str) -> str:
    """The brake of the run in ``table``: its metadata's ``brake``, or for a file written
    before that field, its scenario text's (module docstring). ``where`` names the run in
    messages.

    Raises:
        DatasetError: no readable record of the brake, or a brake not in ``BRAKES`` (one
            line).
    """
    raw = (table.schema.metadata or {}).get(METADATA_KEY)
    try:
        meta = json.loads(raw) if raw is not None else None
    except (ValueError, UnicodeDecodeError):
        meta = None
    if not isinstance(meta, dict):
        raise DatasetError(
            f"{where}: no brake_sim metadata: which brake the samples come from is not known"
            " (allowed a run written by brake-sim simulate --out or brake-sim sweep)"
        )
    brake = meta[BRAKE_KEY] if BRAKE_KEY in meta else _from_scenario_text(meta.get("scenario_toml"))
    if brake is None:
        raise DatasetError(
            f"{where}: its metadata records neither the brake nor the scenario's text: which"
            " brake the samples come from is not known (run it again with this version)"
        )
    if brake not in BRAKES:
        shown = str(brake)[:40]
        raise DatasetError(f"{where}: brake {shown!r} in its metadata; allowed {list(BRAKES)}")
    return str(brake)
