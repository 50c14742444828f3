"""One run as a Parquet table (``brake-sim simulate --out run.parquet``), with pyarrow.

One row per sample of the scenario's rate. Columns, units in the names:

* ``sample_index`` (int64);
* every column of the run's history as the core names it (``model/layout.py``:
  ``time_s``, ``drum_speed_rad_s``, ``left_pivot_fx_n``, ...), float64;
* per measured series of the scenario's sensors (``scenario.sensors``, run by
  :func:`~brake_sim_ros.stream.build.sensor_bank_for` as the node's ``~/measured`` does,
  the same bits): ``measured:<name> [<unit>]`` (float64; NaN where a dropout silenced
  the sensor; null on rows a slower channel does not sample) and ``fault:<name>``
  (uint8, OR of ``faults.FAULT_BIT``; 0 = no sensor fault; null likewise). None
  when the scenario's fidelity plan builds no sensors (``[needs]`` without
  ``measured_signals``; ``simulate`` then records ``"sensors": false`` in the metadata).

* per wheel-speed channel (a tone ring), ``measured:<name>_edge_time [s]`` (float64): the
  simulated time of the tone ring's rising edge that occurred in (previous sample's time,
  this sample's time], NaN on rows without one (:func:`edge_time_column`). The model
  reports at most one edge per sample interval (it assumes much less than a tooth pitch
  per sample: 48 teeth at 25.6 kHz allow up to 3350 rad/s); two on one row are refused.
  Speed from consecutive edges: ``(2 pi / teeth) / diff(edge times)`` rad/s.

* per kind of the defect catalogue (``model/catalogue.py``, ``brake-sim defects``) and
  location, ``defect:<kind>:<location> [<unit>]`` (float64): the defect's severity at that
  sample's time, 0 where it is absent or before its onset (the growth law evaluated by
  ``catalogue.severity_at``, the function the compiled model sets the physics with; a
  defect present from the start gives a constant column).

* ``rul [s]`` (float64): the remaining useful life at each sample, s of simulated time,
  until the first defect reaches its kind's service limit (:mod:`.life`: from the labels,
  or from a growth law beyond the run's end); 0 from then on; NaN when unknown (a healthy
  brake, defects below their limits: right-censored).
* with a drive cycle (``[cycle]``, ``model/cycle.py``), the label column ``phase``
  (dictionary-encoded string): the cycle's segment at that sample, ``"<index>:<kind>"``
  (kinds ``accelerate``, ``cruise``, ``brake``, ``hold``, ``release``, ``drag``;
  ``"<n>:end"`` after the last segment), from the history's ``cycle_segment``; the
  metadata's ``cycle`` lists the segment kinds in order.

Each measured column's field metadata gives ``unit``, ``rate_hz`` and ``decimation``; an
edge-time column's gives ``unit`` and ``tone_ring_teeth``.
The file's key-value metadata ``brake_sim`` holds JSON: the run parameters the caller gives
(scenario, method, seed, rates, ...; ``brake``: ``"study"`` or ``"service"``, the brake the
samples come from, which :mod:`.run_brake` reads for a detector), ``fault_bits``,
``defects`` (the ground truth: one object per defect of the run with kind, location, final
severity, unit, onset_s, growth and growth_rate, as the DefectState message), ``unit_id``
(the scenario's brake unit, "nominal" for the drawing's brake) and ``unit_parameters`` (the
unit's ground truth: a list of ``{key, unit, nominal, value}``, every scattered parameter as
the scenario gives it and as the unit has it, :mod:`brake_sim_ros.fleet.scatter`) and
``conditions`` (the run's operating conditions drawn from the scenario's ranges: per name
``{value, unit, range}``, :mod:`brake_sim_ros.fleet.conditions`; ``{}`` without them) and
``life`` (the failure the ``rul`` column counts down to: ``time_s``, ``kind``, ``location``,
``service_limit``, ``unit``, ``source`` "run", "law" or "censored"; :class:`.life.Failure`).
"""

from __future__ import annotations

import json
import os
from collections.abc import Collection, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from brake_sim_ros.datasets import life
from brake_sim_ros.datasets.run_brake import BRAKE_KEY, METADATA_KEY
from brake_sim_ros.fleet.scatter import UnitValue
from brake_sim_ros.model.cycle import Cycle
from brake_sim_ros.model.defects import Defects
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.sensing.faults import FAULT_BIT
from brake_sim_ros.sensing.sensors import SensorBank
from brake_sim_ros.stream.ground_truth import recorded_wear

if TYPE_CHECKING:
    from brake_sim_ros.scenarios.types import Scenario
    from brake_sim_ros.stream.run import RunResult


def measured_column(name: str, unit: str) -> str:
    return f"measured:{name} [{unit}]"


def fault_column(name: str) -> str:
    return f"fault:{name}"


def edge_time_column(name: str) -> str:
    """The column of a wheel-speed channel's edge times (``name``: the channel's)."""
    return measured_column(f"{name}_edge_time", "s")


def edges_on_rows(time_s: np.ndarray, edges_s: np.ndarray) -> np.ndarray:
    """Sample-aligned edge times: row k holds the edge in (time_s[k-1], time_s[k]], NaN
    where there is none (row 0: an edge at time_s[0]).

    Args:
        time_s: sample times, s, ascending, shape (n,).
        edges_s: edge times, s, ascending, within [time_s[0], time_s[-1]].

    Raises:
        ValueError: two edges fall on one row (more than one tooth per sample).
    """
    out = np.full(time_s.shape[0], np.nan)
    rows = np.searchsorted(time_s, edges_s, side="left")
    if rows.size and (np.any(np.diff(rows) == 0) or rows[-1] >= time_s.shape[0]):
        raise ValueError(
            "tone-ring edges: more than one edge in a sample interval, or one after the last"
            " sample; a sample-aligned column holds one per sample"
        )
    out[rows] = edges_s
    return out


def history_table(
    samples: SampleBlock,
    sensors: SensorBank | None,
    defects: Defects,
    metadata: Mapping[str, Any],
    *,
    unit_id: str,
    unit_values: Sequence[UnitValue],
    conditions: Mapping[str, Any],
    cycle: Cycle | None = None,
    sample_columns: Collection[str] | None = None,
) -> pa.Table:
    """The table of ``samples``, with ``sensors`` (a fresh bank, fed the whole run here)
    what they measured, and the ground truth of ``defects`` (the brake's defects in force
    over the run), of the unit (``unit_id``, ``unit_values``: its scattered parameters,
    ``Scenario.unit_values()``) and of the run's ``conditions``
    (``Scenario.conditions_record()``); with the run's drive ``cycle``, the label column
    ``phase`` (from the samples' ``cycle_segment``); ``metadata`` goes into the
    ``brake_sim`` key as JSON. ``sample_columns``: the samples' columns to write besides
    ``time_s`` (default every one; a sweep that keeps a few does not build the rest)."""
    n = len(samples)
    index = samples.first_index + np.arange(n, dtype=np.int64)
    history = samples.as_dict()
    if "time_s" not in history:
        history = {"time_s": np.asarray(samples.time_s), **history}
    columns: dict[str, pa.Array] = {"sample_index": pa.array(index)}
    fields = [pa.field("sample_index", pa.int64())]
    for name, values in history.items():
        if sample_columns is not None and name != "time_s" and name not in sample_columns:
            continue
        columns[name] = pa.array(np.asarray(values, dtype=np.float64))
        fields.append(pa.field(name, pa.float64()))
    if sensors is not None:
        frame = sensors.advance(samples)
        decimation = sensors.output_decimation
        for name, series in frame.series.items():
            step = decimation[name]
            rows = np.flatnonzero(index % step == 0)
            sampled = np.zeros(n, dtype=bool)
            sampled[rows] = True
            values = np.zeros(n)
            values[rows] = series.values
            labels = np.zeros(n, dtype=np.uint8)
            labels[rows] = series.fault_label
            info = {
                b"unit": series.unit.encode(),
                b"rate_hz": repr(sensors.sample_rate_hz / step).encode(),
                b"decimation": str(step).encode(),
            }
            value_name = measured_column(name, series.unit)
            columns[value_name] = pa.array(values, mask=~sampled)
            fields.append(pa.field(value_name, pa.float64(), metadata=info))
            columns[fault_column(name)] = pa.array(labels, mask=~sampled)
            fields.append(pa.field(fault_column(name), pa.uint8(), metadata=info))
        teeth = {c.name: c.tone_ring_teeth for c in sensors.sensors.channels}
        for name, edges in frame.edges_s.items():
            edge_name = edge_time_column(name)
            columns[edge_name] = pa.array(edges_on_rows(np.asarray(samples.time_s), edges))
            info = {b"unit": b"s", b"tone_ring_teeth": str(teeth[name]).encode()}
            fields.append(pa.field(edge_name, pa.float64(), metadata=info))
    times = np.asarray(history["time_s"])
    wear = recorded_wear(samples)  # a lining wearing with its friction work: the model's
    labels = defects.label_series(times, wear)
    for name, severity in labels.items():
        columns[name] = pa.array(severity)
        fields.append(pa.field(name, pa.float64()))
    fail = life.failure(defects, times, labels)
    columns[life.RUL_COLUMN] = pa.array(life.rul_series(times, fail))
    fields.append(pa.field(life.RUL_COLUMN, pa.float64()))
    if cycle is not None and "cycle_segment" in history:
        phase = pa.array(cycle.phase_names(history["cycle_segment"])).dictionary_encode()
        columns["phase"] = phase
        fields.append(pa.field("phase", phase.type))
    meta = {
        **metadata,
        "cycle": None if cycle is None else list(cycle.kinds),
        "fault_bits": FAULT_BIT,
        "defects": [d.as_dict() for d in defects.active()],
        "unit_id": unit_id,
        "unit_parameters": [v.as_dict() for v in unit_values],
        "conditions": dict(conditions),
        "life": fail.as_dict(),
    }
    schema = pa.schema(fields, metadata={METADATA_KEY: json.dumps(meta).encode()})
    return pa.Table.from_arrays([columns[f.name] for f in fields], schema=schema)


def run_table(
    scenario: Scenario,
    result: RunResult,
    duration_s: float,
    extra: Mapping[str, Any] | None = None,
    sample_columns: Collection[str] | None = None,
) -> pa.Table:
    """The table of a finished run of ``scenario`` (``simulate --out``, each run of a
    sweep): :func:`history_table` with the scenario's sensors, defects, unit and drawn
    conditions, and the run's parameters and the full scenario text (``scenario_toml``)
    in the metadata, plus ``extra`` (a sweep's run id and split); ``sample_columns`` as
    :func:`history_table`'s."""
    from brake_sim_ros import __version__
    from brake_sim_ros.stream.build import sensor_bank_for

    meta = {
        "scenario": scenario.name,
        "source": scenario.source,
        BRAKE_KEY: scenario.setup.params.brake,
        "method": result.method,
        "stop_time_s": result.stop_time_s,
        "version": __version__,
        "sample_period_s": result.samples.sample_period_s,
        "sample_rate_hz": scenario.sample_rate_hz,
        "preset": scenario.solver.preset,
        "step": result.step_note,
        "scenario_toml": scenario.text,
        "seed": scenario.seed,
        "duration_s": duration_s,
        "fidelity_level": result.plan.level.name,
        "sensors": result.plan.sensors,  # no measured columns without them
        **(extra or {}),
        "columns": "units in names",
    }
    return history_table(
        result.samples,
        sensor_bank_for(scenario),
        scenario.setup.defects,
        meta,
        unit_id=scenario.unit_id,
        unit_values=scenario.unit_values(),
        conditions=scenario.conditions_record(),
        cycle=scenario.setup.cycle,
        sample_columns=sample_columns,
    )


def history_arrays(table: pa.Table) -> dict[str, np.ndarray]:
    """The columns of a :func:`history_table` as numpy arrays, for an NPZ file: the same
    names; a null (a row a slower channel does not sample) becomes NaN in a measured column
    and 0 in a fault column (a dropout, also NaN, carries its fault bit)."""
    out = {}
    for name in table.column_names:
        column = table[name]
        if pa.types.is_floating(column.type):
            out[name] = column.to_numpy(zero_copy_only=False)  # null -> NaN
        else:
            out[name] = column.fill_null(0).to_numpy()
    return out


def write_history(path: str | os.PathLike[str], table: pa.Table) -> None:
    """Write ``table`` to ``path`` (zstd-compressed Parquet)."""
    pq.write_table(table, path, compression="zstd")
