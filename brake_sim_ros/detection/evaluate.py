"""A detector over a dataset (``brake-sim sweep``): fitted on one split, run and scored on
another, offline, through the same streaming contract as live.

Each run's measured channels are fed in chunks (``chunk_s``, default 0.1 s: what the
node's ``~/measured`` delivers); the truth at each assessment is the run's label columns
(``defect:<kind>:<location> [<unit>]``) at the assessment's sample. A run is defective
from the first sample at which any label is non-zero (its onset) to its end.

The score (:func:`score`, written as JSON by ``brake-sim score``; :data:`SCHEMA_VERSION`):

``detector``, ``split``, ``hold_s``, ``runs``, ``windows``
``detection``: ``defective_runs``, ``detected``, ``missed``, ``delays_s`` (one per
    detected run, from its onset to the first held alarm), ``median_delay_s``;
    ``per_class``: the same counts and ``median_delay_s`` per class of run (``kind:location``
    of its first defect active at its end)
``false_alarms``: ``count`` and ``healthy_hours`` over the healthy samples of every run,
    ``per_hour``
``health_index``: ``auroc``, ``auprc`` over all windows (defective at the window's last
    sample = positive); null where undefined; ``roc``: ``fpr`` and ``tpr``, the ROC curve's
    corners (empty where undefined); ``per_class``: per class of defective window
    (``kind:location`` of its first active defect), ``windows`` and ``auroc`` of that class's
    windows against the healthy ones (null where undefined)
``isolation``: ``classes`` and ``matrix`` (rows true, columns diagnosed; ``none``: no
    diagnosis) over the windows of defective runs after onset, when the detector diagnoses;
    null otherwise
``severity``: when the detector estimates severities, over the windows of defective runs
    after onset whose diagnosis names a defect active there (a wrong diagnosis is the
    isolation matrix's error, not a severity error): ``windows`` and ``rmse`` over all of
    them (in mixed units: each estimate in its kind's unit); ``per_class``: per diagnosed
    ``kind:location``, ``unit``, ``windows``, ``rmse`` and ``mean_error`` (estimate minus
    true, the kind's unit) and ``rmse_of_service_limit`` (the rmse over the size of the
    kind's service limit, ``brake-sim defects``: comparable across kinds); null when the
    detector gives no finite severity (new in version 3: ``windows`` and ``per_class``;
    version 2 compared a wrong diagnosis's severity against 0)
``forecast``: when the detector forecasts the remaining useful life (``Assessment.rul_s``),
    over the windows of runs with a ``rul [s]`` label where both the forecast and the label
    are finite (a censored run's windows are not scored): ``windows``, ``rmse_s``,
    ``mean_error_s`` (forecast minus true: negative is early) and ``rul_score`` (the
    asymmetric C-MAPSS score, :func:`~.metrics.rul_score`, with its scales read in s: a late
    forecast costs more than an early one by as much); null when it gives no finite
    forecast there (new in version 4)
``per_run``: one object per run: ``run_id``, ``unit_id``, ``defects`` (kind:location
    labels active at the end), ``onset_s``, ``delay_s``, ``false_alarms``, ``healthy_s``
    (s of healthy operation; new in version 5)
``held_out``: one object per held-out rule of the dataset (``[[split.held_out]]``):
    ``rule`` (``column``, ``values``, ``minimum``, ``maximum``), and ``held_out`` and
    ``rest``, the figures over the runs it matches and over the split's other runs:
    ``runs``, ``windows``, ``detection`` (``defective_runs``, ``detected``, ``missed``,
    ``median_delay_s``), ``false_alarms`` (``count``, ``healthy_hours``, ``per_hour``),
    ``health_index`` (``auroc``, ``auprc``) (new in version 5; :mod:`.windows`)
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from brake_sim_ros.datasets.life import RUL_COLUMN
from brake_sim_ros.datasets.reader import DatasetError, SweepDataset
from brake_sim_ros.datasets.run_brake import recorded_brake
from brake_sim_ros.detection import metrics
from brake_sim_ros.detection.detector import Assessment, Detector, SampleChunk, TrainingWindow
from brake_sim_ros.detection.user_code import user_code
from brake_sim_ros.detection.windows import headline_figures, held_out_figures, window_rows
from brake_sim_ros.model.catalogue import KIND_BY_NAME, KINDS, label_column

SCHEMA_VERSION = 5
HEALTHY = "healthy"  # the class of a healthy window or run in the per-class figures
MEASURED_PREFIX = "measured:"
# label column -> "kind:location", the catalogue's (``brake-sim defects``)
LABELS = {label_column(k, loc): f"{k.name}:{loc}" for k in KINDS for loc in k.locations}


@dataclass(frozen=True)
class RunSamples:
    """One run's measured channels (by channel name) and its truth."""

    run_id: str
    unit_id: str
    sample_rate_hz: float
    time_s: np.ndarray
    channels: dict[str, np.ndarray]
    label_names: tuple[str, ...]  # "kind:location"
    labels: np.ndarray  # (n, len(label_names)) severities, 0 where absent
    rul_s: np.ndarray | None = None  # (n,) the ``rul [s]`` label (NaN: censored); None: none
    units: dict[str, str] = field(default_factory=dict)  # channel name -> its unit
    brake: str = ""  # "study" or "service" (datasets.run_brake); "": not known
    where: str = ""  # the run and its file, for messages

    def active(self, row: int) -> tuple[tuple[str, str], ...]:
        """``(kind, location)`` of the defects active at sample ``row``."""
        return tuple(
            tuple(name.split(":", 1))  # type: ignore[misc]
            for name, v in zip(self.label_names, self.labels[row], strict=True)
            if v != 0.0
        )

    def severities(self, row: int) -> tuple[float, ...]:
        """The severities at sample ``row`` of the defects :meth:`active` lists, in order."""
        return tuple(float(v) for v in self.labels[row] if v != 0.0)

    @property
    def onset_index(self) -> int | None:
        rows = np.flatnonzero(np.any(self.labels != 0.0, axis=1))
        return int(rows[0]) if rows.size else None


def _channel_name(column: str) -> str:
    """``measured:<name> [<unit>]`` -> ``<name>``."""
    return column[len(MEASURED_PREFIX) :].rsplit(" [", 1)[0]


def _channel_unit(column: str) -> str:
    """``measured:<name> [<unit>]`` -> ``<unit>`` ("" without one)."""
    _head, sep, unit = column.rpartition(" [")
    return unit[:-1] if sep and unit.endswith("]") else ""


def read_run(dataset: SweepDataset, run_id: str) -> RunSamples:
    """One finished run of ``dataset``, its brake read from its file's metadata.

    Raises:
        DatasetError: the run's file damaged, or its brake not recorded (one line).
    """
    table = dataset.run_table(run_id)
    where = dataset.run_where(run_id)
    brake = recorded_brake(table, where)
    names = table.column_names
    time_s = table["time_s"].to_numpy()
    if time_s.size < 2:
        raise ValueError(f"run {run_id}: {time_s.size} samples; a detector needs 2 or more")
    channels = {
        _channel_name(c): table[c].to_numpy(zero_copy_only=False).astype(np.float64)
        for c in names
        if c.startswith(MEASURED_PREFIX) and not c.endswith("_edge_time [s]")
    }
    units = {
        _channel_name(c): _channel_unit(c)
        for c in names
        if c.startswith(MEASURED_PREFIX) and not c.endswith("_edge_time [s]")
    }
    label_cols = [c for c in names if c in LABELS]
    labels = (
        np.column_stack([table[c].to_numpy() for c in label_cols])
        if label_cols
        else np.zeros((time_s.size, 0))
    )
    unit = dataset.manifest.filter(dataset.manifest["run_id"].to_numpy() == run_id)
    rul = table[RUL_COLUMN].to_numpy().astype(np.float64) if RUL_COLUMN in names else None
    return RunSamples(
        run_id=run_id,
        unit_id=str(unit["unit_id"][0]) if unit.num_rows else "",
        sample_rate_hz=1.0 / float(time_s[1] - time_s[0]),
        time_s=time_s,
        channels=channels,
        label_names=tuple(LABELS[c] for c in label_cols),
        labels=labels,
        rul_s=rul,
        units=units,
        brake=brake,
        where=where,
    )


def _severity_figures(severities: dict[str, list[tuple[float, float]]]) -> dict:
    """The score's ``severity`` object (module docstring) from (estimate, true) per class."""
    every = np.array([pair for pairs in severities.values() for pair in pairs])
    per_class = {}
    for label, pairs in sorted(severities.items()):
        kind = KIND_BY_NAME[label.split(":", 1)[0]]
        est, true = np.array(pairs).T
        rmse = metrics.rmse(est, true)
        per_class[label] = {
            "unit": kind.unit,
            "windows": len(pairs),
            "rmse": rmse,
            "mean_error": float(np.mean(est - true)),
            "rmse_of_service_limit": rmse / abs(kind.service_limit),
        }
    return {
        "windows": int(every.shape[0]),
        "rmse": metrics.rmse(every[:, 0], every[:, 1]),
        "per_class": per_class,
    }


def _forecast_figures(pairs: list[tuple[float, float]]) -> dict:
    """The score's ``forecast`` object (module docstring) from (forecast, true) RUL, s."""
    est, true = np.array(pairs).T
    return {
        "windows": len(pairs),
        "rmse_s": metrics.rmse(est, true),
        "mean_error_s": float(np.mean(est - true)),
        "rul_score": metrics.rul_score(est, true),
    }


def _median(values: list[float]) -> float | None:
    return float(np.median(values)) if values else None


def chunks(run: RunSamples, chunk_s: float) -> Iterator[SampleChunk]:
    """The run's measured channels as consecutive chunks of about ``chunk_s``."""
    n = max(1, round(chunk_s * run.sample_rate_hz))
    for start in range(0, run.time_s.size, n):
        yield SampleChunk(
            start,
            run.sample_rate_hz,
            {name: values[start : start + n] for name, values in run.channels.items()},
        )


class SplitRateError(DatasetError):
    """A split's runs are at several sample rates: no detector is fitted on them."""


class SplitBrakeError(DatasetError):
    """A split's runs come from both brakes: no detector is fitted on them."""


class SplitChannelError(DatasetError):
    """A run of a split lacks a channel the detector reads: no detector is fitted on it."""


class SplitWindows:
    """The training windows of a split, read from the dataset run by run each time it is
    iterated: a detector's fit holds one run's channels at a time, not the split's (a
    detector that iterates twice reads the runs twice and sees the same windows). Counts
    the windows of a whole pass and collects the runs' sample rate, brake and channel
    units."""

    def __init__(self, detector: Detector, dataset: SweepDataset, split: str) -> None:
        self.detector, self.dataset, self.split = detector, dataset, split
        self.windows = 0  # of the last whole pass
        self.longest = 0  # samples of the longest run read
        self.rates: set[float] = set()
        self.brakes: set[str] = set()
        self.units: dict[str, str] = {}

    def __iter__(self) -> Iterator[TrainingWindow]:
        count = 0
        for run_id in self.dataset.runs(self.split):
            run = read_run(self.dataset, run_id)
            self.rates.add(run.sample_rate_hz)
            self.units.update(run.units)
            if len(self.rates) > 1:
                shown = ", ".join(f"{r:g}" for r in sorted(self.rates))
                raise SplitRateError(
                    f"split {self.split}: runs at {shown} Hz; allowed one sample rate to fit"
                    " a detector on"
                )
            missing = [c for c in self.detector.channels if c not in run.channels]
            if missing:
                raise SplitChannelError(
                    f"split {self.split}: {run.where} has no channel {missing[0]!r}; detector"
                    f" {self.detector.name} reads {list(self.detector.channels)}"
                )
            self.brakes.add(run.brake)
            if len(self.brakes) > 1:
                raise SplitBrakeError(
                    f"split {self.split}: runs from the {' and the '.join(sorted(self.brakes))}"
                    f" brake ({run.where} is from the {run.brake} brake); allowed one brake's"
                    " runs to fit a detector on"
                )
            n = window_samples(self.detector, run.sample_rate_hz)
            self.longest = max(self.longest, run.time_s.size)
            for start in range(0, run.time_s.size - n + 1, n):
                count += 1
                yield TrainingWindow(
                    {c: v[start : start + n] for c, v in run.channels.items()},
                    run.sample_rate_hz,
                    run.active(start + n - 1),
                    run_id=run.run_id,
                    last_sample_index=start + n - 1,
                    severities=run.severities(start + n - 1),
                    unit_id=run.unit_id,
                )
        self.windows = count


def fit(detector: Detector, dataset: SweepDataset, split: str = "train") -> int:
    """Fit ``detector`` on the windows of ``split`` (its window length), streamed run by
    run (:class:`SplitWindows`); the number of windows it saw. Records on the detector the
    sample rate, the brake and the units of the channels it read
    (:attr:`Detector.fitted_rate_hz`, :attr:`Detector.fitted_brake`,
    :attr:`Detector.fitted_channels`).

    Raises:
        SplitRateError: the split's runs are at several sample rates (one line).
        SplitBrakeError: the split's runs come from both brakes (one line).
        SplitChannelError: a run of the split lacks a channel the detector reads (one line).
    """
    windows = SplitWindows(detector, dataset, split)
    if next(iter(windows), None) is None:  # reads runs up to the first window only
        _no_window(detector, dataset, split, windows.longest)
    passthrough = (SplitRateError, SplitBrakeError, SplitChannelError)
    with user_code(detector, "fit", passthrough=passthrough):
        detector.fit(windows)
    if windows.rates:
        detector.fitted_rate_hz = windows.rates.pop()
        detector.fitted_brake = windows.brakes.pop()
        units = windows.units
        detector.fitted_channels = {c: units[c] for c in detector.channels if c in units}
    return windows.windows


def window_samples(detector: Detector, sample_rate_hz: float) -> int:
    """The detector's window length at ``sample_rate_hz``, samples (a user's code: checked).

    Raises:
        DetectorCodeError: it raised, or gave no whole number >= 1.
    """
    with user_code(detector, "window_samples"):
        n = detector.window_samples(sample_rate_hz)
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
            raise ValueError(f"{n!r}: allowed a whole number of samples >= 1")
    return int(n)


def _no_window(detector: Detector, dataset: SweepDataset, split: str, longest: int) -> None:
    """Refuse a fit or score over no window: nothing would be measured."""
    if not dataset.runs(split):
        raise DatasetError(f"split {split}: no finished run: no window to fit or score on")
    raise DatasetError(
        f"detector {detector.name}: its window (window_s {detector.window_s!r}) is longer"
        f" than every run of {split} (the longest: {longest} samples): no window"
    )


def unit_refusal(detector: Detector, run: RunSamples) -> str | None:
    """Why ``run``'s channels cannot be judged by ``detector``: a channel in another unit
    than it was fitted on (one line); None when they match or nothing was recorded."""
    for name, unit in detector.fitted_channels.items():
        if name in run.units and run.units[name] != unit:
            return (
                f"detector {detector.name} was fitted on {name} in [{unit}]; run {run.run_id}"
                f" gives it in [{run.units[name]}]: allowed [{unit}]"
            )
    return None


def assess_run(detector: Detector, run: RunSamples, chunk_s: float) -> list[Assessment]:
    """The detector's assessments over ``run`` fed in chunks of ``chunk_s``.

    Raises:
        ValueError: the run's rate, brake or a channel's unit is not what the detector was
            fitted on (one line; :class:`~.detector.RateMismatchError` for the rate).
        DetectorCodeError: the detector's code raised.
    """
    refusal = (
        detector.rate_refusal(run.sample_rate_hz)
        or detector.brake_refusal(run.brake, run.where or f"run {run.run_id}")
        or unit_refusal(detector, run)
    )
    if refusal is not None:
        raise ValueError(refusal)
    with user_code(detector, "feed"):
        detector.reset()
        return [a for c in chunks(run, chunk_s) for a in detector.feed(c)]


@dataclass
class _Tally:
    """What :func:`score` gathers over a split's runs, in run order."""

    per_run: list[dict] = field(default_factory=list)  # the score's per_run entries
    rows: list[dict] = field(default_factory=list)  # every window (windows.window_rows)
    run_class: dict[str, list[float | None]] = field(default_factory=dict)  # class -> delays
    true_class: list[str] = field(default_factory=list)  # per defective window after onset
    diagnosed: list[str] = field(default_factory=list)  # its diagnosis ("none": none)
    severities: dict[str, list[tuple[float, float]]] = field(default_factory=dict)
    forecasts: list[tuple[float, float]] = field(default_factory=list)  # (forecast, true), s
    longest: int = 0  # samples of the longest run


def score(
    detector: Detector,
    dataset: SweepDataset,
    split: str = "test",
    *,
    hold_s: float = 0.2,
    chunk_s: float = 0.1,
    windows: list[dict] | None = None,
) -> dict:
    """Run ``detector`` (fitted) over ``split`` and score it (module docstring);
    ``windows``, when given, receives every assessed window's row
    (:func:`~.windows.window_rows`)."""
    tally = _Tally()
    for run_id in dataset.runs(split):
        _score_run(detector, read_run(dataset, run_id), tally, hold_s=hold_s, chunk_s=chunk_s)
    if not tally.rows:
        _no_window(detector, dataset, split, tally.longest)
    if windows is not None:
        windows.extend(tally.rows)
    manifest = {r["run_id"]: r for r in dataset.manifest.to_pylist()}
    return {
        "schema_version": SCHEMA_VERSION,
        "detector": detector.name,
        "split": split,
        "hold_s": hold_s,
        **_split_figures(tally),
        "isolation": _isolation_figures(tally.true_class, tally.diagnosed),
        "severity": _severity_figures(tally.severities) if tally.severities else None,
        "forecast": _forecast_figures(tally.forecasts) if tally.forecasts else None,
        "per_run": tally.per_run,
        "held_out": held_out_figures(dataset.held_out, manifest, tally.per_run, tally.rows),
    }


def _score_run(
    detector: Detector, run: RunSamples, tally: _Tally, *, hold_s: float, chunk_s: float
) -> None:
    """Assess ``run`` and add its windows, its per-run entry and its figures to ``tally``."""
    tally.longest = max(tally.longest, run.time_s.size)
    window_samples(detector, run.sample_rate_hz)  # checked before any sample is fed
    found = assess_run(detector, run, chunk_s)
    rows = np.array([a.sample_index for a in found], dtype=np.int64)
    times = run.time_s[rows] if rows.size else np.zeros(0)
    alarm = np.array([a.alarm for a in found], dtype=bool)
    defective = np.any(run.labels[rows] != 0.0, axis=1) if rows.size else np.zeros(0, bool)
    classes = [
        ":".join(run.active(int(row))[0]) if bad else HEALTHY
        for row, bad in zip(rows, defective, strict=True)
    ]
    actives = [[":".join(x) for x in run.active(int(row))] for row in rows]
    tally.rows.extend(window_rows(run.run_id, run.unit_id, found, times, actives, classes))
    if run.rul_s is not None:
        for a, row in zip(found, rows, strict=True):
            if math.isfinite(a.rul_s) and math.isfinite(run.rul_s[row]):
                tally.forecasts.append((float(a.rul_s), float(run.rul_s[row])))
    onset = run.onset_index
    onset_s = None if onset is None else float(run.time_s[onset])
    delay = None
    count, hours = 0, 0.0
    if rows.size:
        count, hours = metrics.false_alarms_per_hour(alarm, times, ~defective, hold_s)
    if onset_s is not None:
        delay = metrics.detection_delay(alarm, times, onset_s, hold_s) if rows.size else None
        final = run.active(run.time_s.size - 1)
        tally.run_class.setdefault(":".join(final[0]) if final else HEALTHY, []).append(delay)
        bad = [(a, int(row)) for a, row, d in zip(found, rows, defective, strict=True) if d]
        _tally_diagnoses(run, bad, tally)
    tally.per_run.append(
        {
            "run_id": run.run_id,
            "unit_id": run.unit_id,
            "defects": [":".join(x) for x in run.active(run.time_s.size - 1)],
            "onset_s": onset_s,
            "delay_s": delay,
            "false_alarms": count,
            "healthy_s": hours * 3600.0,
        }
    )


def _tally_diagnoses(run: RunSamples, bad: list[tuple[Assessment, int]], tally: _Tally) -> None:
    """Each defective window's (assessment, sample row) true class against its diagnosis,
    and the severity estimate of a diagnosis that names a defect active there."""
    for a, row in bad:
        active = run.active(row)
        tally.true_class.append(":".join(active[0]))
        d = a.diagnosis
        label = "none" if d is None else f"{d.kind}:{d.location}"
        tally.diagnosed.append(label)
        if d is not None and math.isfinite(d.severity) and label in map(":".join, active):
            true = float(run.labels[row, run.label_names.index(label)])
            tally.severities.setdefault(label, []).append((d.severity, true))


def _split_figures(tally: _Tally) -> dict:
    """``runs``, ``windows``, ``detection``, ``false_alarms`` and ``health_index`` over the
    whole split: the headline figures (:func:`~.windows.headline_figures`, as for a
    held-out rule's runs) with the split's own detail (delays, ROC, per class)."""
    head = headline_figures(tally.per_run, tally.rows)
    detection = head["detection"]
    y = np.array([r["defective"] for r in tally.rows], dtype=bool)
    h = np.array([r["health_index"] for r in tally.rows], dtype=np.float64)
    cls = np.array([r["class"] for r in tally.rows], dtype=object)
    fpr, tpr = metrics.roc_points(y, h) if y.size else ([], [])
    return {
        "runs": head["runs"],
        "windows": head["windows"],
        "detection": {
            "defective_runs": detection["defective_runs"],
            "detected": detection["detected"],
            "missed": detection["missed"],
            "delays_s": [r["delay_s"] for r in tally.per_run if r["delay_s"] is not None],
            "median_delay_s": detection["median_delay_s"],
            "per_class": {
                c: {
                    "defective_runs": len(found_delays),
                    "detected": sum(x is not None for x in found_delays),
                    "median_delay_s": _median([x for x in found_delays if x is not None]),
                }
                for c, found_delays in sorted(tally.run_class.items())
            },
        },
        "false_alarms": head["false_alarms"],
        "health_index": {
            **head["health_index"],
            "roc": {"fpr": fpr, "tpr": tpr},
            "per_class": {
                c: {
                    "windows": int(np.count_nonzero(cls == c)),
                    "auroc": metrics.auroc(
                        (cls == c)[(cls == c) | (cls == HEALTHY)],
                        h[(cls == c) | (cls == HEALTHY)],
                    ),
                }
                for c in sorted(set(cls.tolist()) - {HEALTHY})
            },
        },
    }


def _isolation_figures(true_class: list[str], diagnosed: list[str]) -> dict | None:
    """The score's ``isolation`` object, None when the detector never diagnoses."""
    if not any(d != "none" for d in diagnosed):
        return None
    classes = sorted(set(true_class) | set(diagnosed))
    return {
        "classes": classes,
        "matrix": metrics.confusion(true_class, diagnosed, classes).tolist(),
    }
