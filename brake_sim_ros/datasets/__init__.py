"""Tables of runs for analysis and learning: Parquet files of samples and sensor channels,
campaign sweeps and their datasets.

``brake_sim_ros.datasets.open(DIR)`` opens a sweep's output directory
(:func:`.reader.open_dataset`); pyarrow is imported only then.
"""

from __future__ import annotations

from typing import Any


def __getattr__(name: str) -> Any:
    if name in ("open", "open_dataset"):
        from brake_sim_ros.datasets.reader import open_dataset

        return open_dataset
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
