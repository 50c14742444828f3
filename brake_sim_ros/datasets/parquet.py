"""One run as a Parquet table (``brake-sim simulate --out run.parquet``), with pyarrow.

One row per sample of the scenario's rate. Columns, units in the names:

* ``sample_index`` (int64);
* every column of the run's history as the core names it (``model/layout.py``:
  ``time_s``, ``drum_speed_rad_s``, ``left_pivot_fx_n``, ...), float64;
* per measured series of the scenario's sensors (``scenario.sensors``, run by
  :func:`~brake_sim_ros.stream.build.sensor_bank_for` as the node's ``~/measured`` does,
  the same bits): ``measured:<name> [<unit>]`` (float64; NaN where a dropout silenced
  the sensor; null on rows a slower channel does not sample) and ``fault:<name>``
  (uint8, OR of ``sensor_faults.FAULT_BIT``; 0 = no sensor fault; null likewise). None
  when the scenario's fidelity plan builds no sensors (``[needs]`` without
  ``measured_signals``; ``simulate`` then records ``"sensors": false`` in the metadata).

Each measured column's field metadata gives ``unit``, ``rate_hz`` and ``decimation``.
The file's key-value metadata ``brake_sim`` holds JSON: the run parameters the caller
gives (scenario, method, seed, rates, ...) and ``fault_bits``.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from brake_sim_ros.model.sensor_faults import FAULT_BIT
from brake_sim_ros.model.sensors import SensorBank
from brake_sim_ros.model.trajectory import SampleBlock

METADATA_KEY = b"brake_sim"


def measured_column(name: str, unit: str) -> str:
    return f"measured:{name} [{unit}]"


def fault_column(name: str) -> str:
    return f"fault:{name}"


def history_table(
    samples: SampleBlock, sensors: SensorBank | None, metadata: Mapping[str, Any]
) -> pa.Table:
    """The table of ``samples`` and, with ``sensors`` (a fresh bank, fed the whole run
    here), what they measured; ``metadata`` goes into the ``brake_sim`` key as JSON."""
    n = len(samples)
    index = samples.first_index + np.arange(n, dtype=np.int64)
    history = samples.as_dict()
    if "time_s" not in history:
        history = {"time_s": np.asarray(samples.time_s), **history}
    columns: dict[str, pa.Array] = {"sample_index": pa.array(index)}
    fields = [pa.field("sample_index", pa.int64())]
    for name, values in history.items():
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
    meta = {**metadata, "fault_bits": FAULT_BIT}
    schema = pa.schema(fields, metadata={METADATA_KEY: json.dumps(meta).encode()})
    return pa.Table.from_arrays([columns[f.name] for f in fields], schema=schema)


def write_history(path: str | os.PathLike[str], table: pa.Table) -> None:
    """Write ``table`` to ``path`` (zstd-compressed Parquet)."""
    pq.write_table(table, path, compression="zstd")
