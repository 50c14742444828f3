"""``brake-sim plot``: one run drawn to a PNG, headless, to look before reading numbers.

The run is a ``simulate --out`` file (``.parquet`` or ``.npz``) or a dataset's run by id.
Four panels, one above the other:

1. the measured channels over time (``measured:<name> [<unit>]``, each in its unit,
   scaled to its own range and offset so that none hides another), with the drive phases
   shaded (a cycle's ``phase`` column; otherwise the brake applied, where the actuation
   force is above zero) and the defect labels (``defect:<kind>:<location> [<unit>]``)
   named with their severity at the end and a line at each one's onset;
2. a spectrogram of the first accelerometer (its power, dB);
3. the order spectrum on the tone ring: the drum's angle fluctuation at orders 1-20, rad
   (:func:`~.features.angle_fluctuation_orders`, over the whole run);
4. with a windows file (``brake-sim score --windows``): the detector's health index over
   the run, its alarms marked, 1 the alarm threshold.

Drawn with matplotlib's Agg backend: no display needed.
"""

from __future__ import annotations

import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from brake_sim_ros.detection.features import ORDERS, angle_fluctuation_orders

MEASURED = "measured:"
LABEL = "defect:"


def _channels(columns: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    return {
        c: np.asarray(v, dtype=np.float64)
        for c, v in columns.items()
        if c.startswith(MEASURED) and not c.endswith("_edge_time [s]")
    }


def _applied(columns: Mapping[str, np.ndarray]) -> list[tuple[str, np.ndarray]]:
    """(name, mask) of each drive phase to shade."""
    if "phase" in columns:
        phase = np.asarray(columns["phase"]).astype(str)
        return [(p, phase == p) for p in dict.fromkeys(phase) if p not in ("", "None")]
    force = [c for c in ("left_actuation_force_n", "right_actuation_force_n") if c in columns]
    if force:
        on = np.any([np.asarray(columns[c], dtype=np.float64) > 0.0 for c in force], axis=0)
        return [("brake applied", on)]
    return []


def _shade(ax: Any, t: np.ndarray, phases: list[tuple[str, np.ndarray]]) -> None:
    colours = ("tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink")
    for i, (name, mask) in enumerate(phases):
        edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
        for k, (a, b) in enumerate(zip(edges[::2], edges[1::2], strict=True)):
            ax.axvspan(
                t[a], t[b - 1], color=colours[i % len(colours)], alpha=0.15,
                label=name if k == 0 else None,
            )  # fmt: skip


def draw(
    columns: Mapping[str, np.ndarray],
    out: str | Path,
    *,
    title: str,
    windows: Mapping[str, np.ndarray] | None = None,
) -> None:
    """Draw one run's ``columns`` (name -> values, one per sample; ``time_s`` among them)
    to the PNG ``out``; ``windows``: the run's rows of a windows file (``time_s``,
    ``health_index``, ``alarm``), or None.

    Raises:
        ValueError: a run without ``time_s`` or measured channels (one line).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if "time_s" not in columns:
        raise ValueError(f"{title}: no time_s column; allowed a run's samples")
    channels = _channels(columns)
    if not channels:
        raise ValueError(
            f"{title}: no measured channels (measured:<name> [<unit>]); allowed a run with"
            " the scenario's sensors (simulate --out FILE.parquet writes them)"
        )
    t = np.asarray(columns["time_s"], dtype=np.float64)
    rate = 1.0 / float(np.median(np.diff(t)))
    panels = 4 if windows is not None else 3
    fig, axes = plt.subplots(panels, 1, figsize=(11, 3.0 * panels), constrained_layout=True)
    ax = axes[0]
    _shade(ax, t, _applied(columns))
    for k, (name, v) in enumerate(channels.items()):
        finite = v[np.isfinite(v)]
        span = float(np.ptp(finite)) if finite.size else 1.0
        centre = float(np.mean(finite)) if finite.size else 0.0
        ax.plot(t, (v - centre) / (span or 1.0) - 1.2 * k, lw=0.6, label=name[len(MEASURED) :])
    labels = [c for c in columns if c.startswith(LABEL)]
    named = []
    for c in labels:
        s = np.asarray(columns[c], dtype=np.float64)
        active = np.flatnonzero(s != 0.0)
        if active.size:
            ax.axvline(t[active[0]], color="red", lw=0.8, ls="--")
            named.append(f"{c[len(LABEL) :]} = {s[-1]:g}")
    ax.set_title(f"{title}: " + ("; ".join(named) if named else "healthy"), fontsize=9)
    ax.set_ylabel("each channel over its range")
    ax.set_yticks([])
    ax.legend(loc="upper right", fontsize=7)
    accel = next((c for c in channels if "accel" in c), next(iter(channels)))
    x = np.nan_to_num(channels[accel])
    axes[1].specgram(x, NFFT=256, Fs=rate, noverlap=192, cmap="viridis")
    axes[1].set_ylabel("Hz")
    axes[1].set_title(f"spectrogram of {accel[len(MEASURED) :]}", fontsize=9)
    pulse = next((c for c in channels if c.startswith(f"{MEASURED}wheel_speed ")), None)
    amplitudes = (
        angle_fluctuation_orders(np.nan_to_num(channels[pulse]), rate)
        if pulse
        else np.zeros(len(ORDERS))
    )
    axes[2].bar(ORDERS, amplitudes)
    axes[2].set_xlabel("order (per drum revolution)")
    axes[2].set_ylabel("rad")
    axes[2].set_title("drum angle fluctuation on the tone ring, by order", fontsize=9)
    if windows is not None:
        ax = axes[3]
        wt, h = np.asarray(windows["time_s"]), np.asarray(windows["health_index"])
        alarm = np.asarray(windows["alarm"], dtype=bool)
        ax.step(wt, h, where="post", lw=1.0, label="health index")
        ax.plot(wt[alarm], h[alarm], "rv", ms=4, label="alarm")
        ax.axhline(1.0, color="red", lw=0.8, ls=":")
        ax.set_xlim(t[0], t[-1])
        ax.set_xlabel("time, s")
        ax.legend(loc="upper right", fontsize=7)
    else:
        axes[0].set_xlabel("time, s")
    fig.savefig(out, format="png", dpi=100)
    plt.close(fig)


def _from_table(table: Any) -> dict[str, np.ndarray]:
    out = {}
    for name in table.column_names:
        column = table.column(name)
        if name == "phase":
            out[name] = np.array([str(x) for x in column.to_pylist()])
        else:
            out[name] = column.to_numpy(zero_copy_only=False)
    return out


def read_run(source: str, run_id: str | None) -> tuple[dict[str, np.ndarray], str]:
    """One run's columns and its name: a dataset directory with ``run_id``, or a
    ``simulate --out`` file (``.parquet``, ``.npz``) without.

    Raises:
        ValueError: a source or run that cannot be read (one line).
    """
    path = Path(source)
    if path.is_dir():
        from brake_sim_ros.datasets.reader import open_dataset

        if run_id is None:
            raise ValueError(f"{source}: a dataset; allowed with --run RUN_ID (its manifest)")
        dataset = open_dataset(path)
        if run_id not in dataset.runs():
            raise ValueError(f"--run {run_id!r}: not a run of {source}; allowed its run ids")
        return _from_table(dataset.run_table(run_id)), run_id
    if run_id is not None:
        raise ValueError(f"--run with {source}: allowed only with a dataset directory")
    if path.suffix == ".parquet":
        import pyarrow.parquet as pq

        try:
            return _from_table(pq.read_table(path)), path.name
        except (OSError, ValueError) as exc:
            raise ValueError(f"{source}: not a readable Parquet file ({exc})") from None
    if path.suffix == ".npz":
        try:
            with np.load(path, allow_pickle=False) as data:
                return {k: data[k] for k in data.files}, path.name
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
            # the kind of failure only: a damaged archive's own text may quote its bytes
            raise ValueError(f"{source}: not a readable .npz file ({type(exc).__name__})") from None
    raise ValueError(f"{source}: allowed a dataset directory, a .parquet or a .npz run file")


def read_windows(path: str, run_id: str, time_s: Any = None) -> dict[str, np.ndarray]:
    """The rows of ``run_id`` in a windows file (``brake-sim score --windows``); with the
    run's sample times ``time_s`` (s), each window's last sample must be one of them, at
    its index: a file of another dataset's run of that id is refused.

    Raises:
        ValueError: unreadable, no window of that run, or windows not at the run's samples
            (one line).
    """
    import pyarrow.parquet as pq

    try:
        table = pq.read_table(
            path, columns=["run_id", "sample_index", "time_s", "health_index", "alarm"]
        )
    except (OSError, ValueError, KeyError) as exc:
        raise ValueError(f"--windows {path}: not a windows file ({exc})") from None
    rows = table.to_pydict()
    keep = np.array(rows["run_id"]) == run_id
    if not keep.any():
        raise ValueError(f"--windows {path}: no window of run {run_id}")
    out = {k: np.asarray(v)[keep] for k, v in rows.items() if k != "run_id"}
    if time_s is not None:
        time_s = np.asarray(time_s, dtype=np.float64)
        index = out["sample_index"].astype(np.int64)
        inside = (index >= 0) & (index < time_s.size)
        same = inside & (time_s[np.clip(index, 0, time_s.size - 1)] == out["time_s"])
        if not same.all():
            i = int(np.flatnonzero(~same)[0])
            raise ValueError(
                f"--windows {path}: its window {i} of run {run_id} ends at sample"
                f" {int(index[i])}, {out['time_s'][i]:g} s, not a sample of this run there:"
                " allowed the windows score wrote for this run"
            )
    return out
