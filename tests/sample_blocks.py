"""Sample blocks for tests: a run cut into the pieces a node would publish."""

from __future__ import annotations

from brake_sim_ros.model.trajectory import SampleBlock


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
