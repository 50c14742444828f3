"""Pieces of runs for tests: a run cut into the blocks a node would publish, or into the
training windows ``brake-sim score`` fits on; and the sensor set with every fault kind."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from brake_sim_ros.detection.detector import TrainingWindow
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.sensing.faults import SensorFault
from brake_sim_ros.sensing.kinds import SENSOR_KINDS
from brake_sim_ros.sensing.sensors import (
    SensorChannel,
    SensorSet,
    accelerometer,
    default_channels,
)


def cut(block: SampleBlock, sizes: list[int]) -> list[SampleBlock]:
    """``block`` cut into consecutive blocks of ``sizes`` (cycled), the last one shorter."""
    out, start, k = [], 0, 0
    while start < len(block):
        n = sizes[k % len(sizes)]
        rows = block.data[start : start + n]
        out.append(
            SampleBlock(rows, block.first_index + start, block.sample_period_s, block.columns)
        )
        start, k = start + n, k + 1
    return out


def scenario_table(scenario, run: SampleBlock):
    """The Parquet table of ``run`` (samples of ``scenario``), without sensors, with the
    scenario's defects, unit and conditions as ground truth."""
    from brake_sim_ros.datasets import parquet

    return parquet.history_table(
        run,
        None,
        scenario.setup.defects,
        {"scenario": scenario.name},
        unit_id=scenario.unit_id,
        unit_values=scenario.unit_values(),
        conditions=scenario.conditions_record(),
    )


def training_windows(
    channels: Mapping[str, np.ndarray],
    sample_rate_hz: float,
    *,
    run_id: str,
    unit_id: str = "",
    samples: int = 512,
) -> list[TrainingWindow]:
    """One healthy run's ``channels`` cut into consecutive whole training windows of
    ``samples``, as ``brake-sim score`` cuts a run to fit a detector."""
    n = len(next(iter(channels.values())))
    return [
        TrainingWindow(
            {c: v[s : s + samples] for c, v in channels.items()},
            sample_rate_hz,
            run_id=run_id,
            last_sample_index=s + samples - 1,
            unit_id=unit_id,
        )
        for s in range(0, n - samples + 1, samples)
    ]


def faulted_set() -> SensorSet:
    """The default channels with every fault kind, an IMU at 3.2 kHz and a load pin."""
    channels = default_channels()
    return SensorSet(
        channels=(
            channels[0].with_faults(SensorFault("loose_mount", 0.5, 0.3)),
            channels[1].with_faults(SensorFault("stuck", 0.3, duration_s=0.2)),
            channels[2].with_faults(SensorFault("dropout", 0.4, duration_s=0.1)),
            channels[3].with_faults(SensorFault("bias_drift", 0.25, 2.0)),
            accelerometer("imu_y", "knuckle", "y", "consumer_imu_class", rate_hz=3200.0),
            SensorChannel(
                "pin_left_x",
                "load_pin",
                "left",
                "x",
                SENSOR_KINDS["load_pin"].presets["strain_gauge_pin"],
                faults=(SensorFault("saturation", 0.21, 500.0),),
            ),
        )
    )
