"""``brake-sim score``, ``fit`` and ``plot``: detectors fitted on a sweep's dataset, scored
against its ground truth or saved, and one run drawn with a detector's health index."""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import TYPE_CHECKING

from brake_sim_ros.cli.common import DEBUG_HELP, Command, one_line
from brake_sim_ros.errors import BrakeSimError

if TYPE_CHECKING:
    from brake_sim_ros.datasets.reader import SweepDataset
    from brake_sim_ros.detection.detector import Detector


def _model_where(path: str) -> str:
    """How a --model file is named in messages."""
    from brake_sim_ros.recording.mcap_format import describe_path

    return f"--model {describe_path(path)}"


def load_model(path: str, name: str | None) -> Detector:
    """The detector saved in ``path`` (``--model``): a built-in, or a user's whose class
    ``name`` names (``module:Class`` or ``path/to/file.py:Class``; the file never does)."""
    from brake_sim_ros.detection import saved
    from brake_sim_ros.detection.registry import BUILTIN, make_detector

    user = make_detector(name) if name is not None and name not in BUILTIN else None
    return saved.load(path, None if user else name, where=_model_where(path), user=user)


def _dataset_inputs(directory: str) -> list[Path]:
    """The files of the dataset in ``directory`` that no output may replace."""
    from brake_sim_ros.datasets.sweep_output import LOCK_NAME, MANIFEST_NAME

    root = Path(directory)
    return [root / MANIFEST_NAME, root / LOCK_NAME]


def _outside_samples(directory: str, path: str, option: str, *, is_directory: bool = False) -> None:
    """Refuse an output ``path`` (``option``; a file, or with ``is_directory`` a directory
    for files) inside the dataset's samples, where a file would be read as one of them, in
    one line."""
    from brake_sim_ros.datasets.sweep_output import SAMPLES_DIR

    samples = os.path.realpath(Path(directory) / SAMPLES_DIR)
    place = os.path.realpath(Path(path) if is_directory else Path(path).parent)
    if os.path.commonpath([samples, place]) == samples:
        raise BrakeSimError(f"{option} {path}: inside the dataset's samples; allowed elsewhere")


def _score_inputs(args: argparse.Namespace) -> list[Path | str]:
    """What ``score`` reads and no output of it may replace: the dataset's files and the
    ``--model`` file."""
    return [*_dataset_inputs(args.directory), *([args.model] if args.model else [])]


# --- fit -----------------------------------------------------------------------------------
def cmd_fit(args: argparse.Namespace) -> int:
    """``brake-sim fit DIR --detector NAME --out MODEL.json``: fit a detector on one split
    and save it (``detection.saved``), for ``score --model`` and ``monitor --model``."""
    from brake_sim_ros.datasets.reader import open_dataset
    from brake_sim_ros.detection import evaluate, saved
    from brake_sim_ros.detection.fitted import facts_text
    from brake_sim_ros.detection.registry import make_detector
    from brake_sim_ros.recording.output import atomic_output, probe_output

    dataset = open_dataset(args.directory)
    inputs = _dataset_inputs(args.directory)
    _outside_samples(args.directory, args.out, "--out")
    probe_output(args.out, inputs=inputs, overwrite=args.overwrite, option="--out")
    try:
        detector = make_detector(args.detector)
        saved.check_savable(detector)  # before the work
        windows = evaluate.fit(detector, dataset, args.fit_split)
    except BrakeSimError:
        raise  # one line already (a user detector's keeps its traceback for --debug)
    except (ValueError, RuntimeError) as exc:
        raise BrakeSimError(one_line(exc)) from None
    fitted_on = {"dataset": str(args.directory), "split": args.fit_split, "windows": windows}
    text = saved.dumps(detector, fitted_on=fitted_on)
    with atomic_output(args.out, inputs=inputs, overwrite=args.overwrite, option="--out") as tmp:
        tmp.write_text(text, encoding="utf-8")
    print(
        f"detector {detector.name} fitted on {args.fit_split} ({windows} windows,"
        f" {facts_text(detector)}): {args.out}"
    )
    return 0


def fit_options(p: argparse.ArgumentParser) -> None:
    """``fit``'s description and options."""
    from brake_sim_ros.detection.registry import help_text, names

    p.description = (
        "Fit a detector on one split of a sweep's dataset and save it, fitted,"
        " as a JSON file (brake_sim_ros.detection.saved documents it) that score --model"
        " and monitor --model load instead of refitting. Saved forms: "
        + ", ".join(names(saved_only=True))
        + ", and your Detector's with saved_state and load_state."
    )
    p.add_argument("directory", help="a sweep's output directory")
    p.add_argument("--detector", required=True, help=help_text(saved_only=True))
    p.add_argument("--fit-split", default="train", help="split to fit on (default train)")
    p.add_argument("--out", required=True, metavar="MODEL.json", help="the file to write")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    p.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    p.set_defaults(func=cmd_fit)


# --- score ---------------------------------------------------------------------------------
def cmd_score(args: argparse.Namespace) -> int:
    """``brake-sim score DIR --detector NAME [--detector NAME ...]``: fit each detector on
    one split (or load it: ``--model``), score it on another, print the headline figures
    and write the JSON (``detection.evaluate``) and, with ``--report``, the report
    (``detection.report``)."""
    import json

    from brake_sim_ros.datasets.reader import open_dataset
    from brake_sim_ros.recording.output import replace_output

    dataset = open_dataset(args.directory)
    names = _checked_score_options(args)
    window_rows: list[dict] = []
    scores = []
    for name in names:
        score, fitted = _score_one(args, dataset, name, window_rows)
        scores.append(score)
        for line in score_lines(score, fitted, args.split):
            print(line)
    if args.out is not None:
        text = json.dumps(scores[0], indent=1, sort_keys=True)
        replace_output(args.out, lambda tmp: tmp.write_text(text + "\n"))
        print(f"JSON: {args.out}")
    if args.windows is not None:
        _write_windows(args.windows, window_rows)
    if args.report is not None:
        _write_report(args.report, scores, inputs=_score_inputs(args))
    return 0


def _checked_score_options(args: argparse.Namespace) -> list[str | None]:
    """The detectors ``score`` takes (None: the one the --model file holds), every option
    and output checked before the work."""
    from brake_sim_ros.recording.output import check_output, check_output_directory

    if not (args.hold_s >= 0.0 and args.hold_s <= 3600.0):
        raise BrakeSimError(f"--hold {args.hold_s!r}: allowed 0 to 3600 s")
    for name in args.detector or []:
        if not name.strip():
            raise BrakeSimError(f"--detector {name!r}: allowed a detector's name")
    if args.model is not None and not args.model.strip():
        raise BrakeSimError(f"--model {args.model!r}: allowed a saved detector's file")
    # without --detector: the saved detector the file holds, or rms
    names: list[str | None] = args.detector or ([None] if args.model else ["rms"])
    if args.out is not None and len(names) > 1:
        raise BrakeSimError("--out with several --detector: allowed one detector (or --report)")
    if args.windows is not None and len(names) > 1:
        raise BrakeSimError("--windows with several --detector: allowed one detector")
    if args.windows is not None and not args.windows.endswith(".parquet"):
        raise BrakeSimError(f"--windows {args.windows!r}: allowed a FILE.parquet path")
    if args.model and len(names) > 1:
        raise BrakeSimError("--model with several --detector: allowed one detector")
    if args.model and args.fit_split is not None:
        raise BrakeSimError("--fit-split with --model: the saved detector is fitted already")
    # before the work: no output replaces the dataset's files, the model or lands in samples
    inputs = _score_inputs(args)
    if args.out is not None:
        _outside_samples(args.directory, args.out, "--out")
        check_output(args.out, inputs=inputs, overwrite=True, option="--out")
    if args.windows is not None:
        _outside_samples(args.directory, args.windows, "--windows")
        check_output(args.windows, inputs=inputs, overwrite=True, option="--windows")
    if args.report is not None:  # made when the report is written
        check_output_directory(args.report, "--report")
        _outside_samples(args.directory, args.report, "--report", is_directory=True)
    return names


def _score_one(
    args: argparse.Namespace, dataset: SweepDataset, name: str | None, window_rows: list[dict]
) -> tuple[dict, str]:
    """One detector loaded (``--model``) or fitted, and scored on ``--split``: its score
    and how it was fitted, in words; its windows appended to ``window_rows``."""
    from brake_sim_ros.detection import evaluate
    from brake_sim_ros.detection.fitted import facts_text
    from brake_sim_ros.detection.registry import make_detector

    try:
        if args.model:
            detector = load_model(args.model, name)
            fitted = f"loaded from {args.model} (fitted {facts_text(detector)})"
        else:
            detector = make_detector(name or "rms")
            fit_split = args.fit_split or "train"
            windows = evaluate.fit(detector, dataset, fit_split)
            fitted = f"fitted on {fit_split} ({windows} windows, {facts_text(detector)})"
        score = evaluate.score(
            detector, dataset, args.split, hold_s=args.hold_s, windows=window_rows
        )
    except BrakeSimError:
        raise
    except (ValueError, RuntimeError) as exc:  # the detector's, or the dataset's, one line
        raise BrakeSimError(one_line(exc)) from None
    return score, fitted


def _figure(value: float | None) -> str:
    return "undefined" if value is None else f"{value:.3f}"


def score_lines(score: dict, fitted: str, split: str) -> list[str]:
    """What ``score`` prints of one detector's score (``detection.evaluate``'s JSON): the
    headline, then the severity per class and the remaining useful life where it has them."""
    d, fa, hi = score["detection"], score["false_alarms"], score["health_index"]
    median = d["median_delay_s"]
    delay = "" if median is None else f" (median delay {median:.3f} s)"
    sev = score["severity"]
    severity = "" if sev is None else f"; severity rmse {sev['rmse']:.4g} (mixed units)"
    lines = [
        f"detector {score['detector']} {fitted},"
        f" scored on {split}: {score['runs']} runs; detected {d['detected']} of"
        f" {d['defective_runs']} defective runs{delay};"
        f" {fa['count']} false alarms in {fa['healthy_hours'] * 3600:.1f} s of healthy"
        f" operation; AUROC {_figure(hi['auroc'])}, AUPRC {_figure(hi['auprc'])}{severity}"
    ]
    for label, figures in ({} if sev is None else sev["per_class"]).items():
        lines.append(
            f"  severity {label}: rmse {figures['rmse']:.4g} {figures['unit']}"
            f" ({100 * figures['rmse_of_service_limit']:.0f} % of the service limit),"
            f" mean error {figures['mean_error']:+.4g} over {figures['windows']} windows"
        )
    forecast = score["forecast"]
    if forecast is not None:
        lines.append(
            f"  remaining useful life: rmse {forecast['rmse_s']:.4g} s, mean error"
            f" {forecast['mean_error_s']:+.4g} s, asymmetric score"
            f" {forecast['rul_score']:.4g} over {forecast['windows']} windows"
        )
    return lines


def _write_windows(path: str, rows: list[dict]) -> None:
    """``score --windows``: every assessed window as Parquet, written whole."""
    import pyarrow.parquet as pq

    from brake_sim_ros.detection.windows import windows_table
    from brake_sim_ros.recording.output import replace_output

    table = windows_table(rows)
    replace_output(path, lambda tmp: pq.write_table(table, tmp), option="--windows")
    print(f"windows: {table.num_rows} in {path}")


def _write_report(directory: str, scores: list[dict], *, inputs: list[Path | str]) -> None:
    """``score --report DIR``: each detector's JSON and the figures, every file's rules
    checked before the first is written."""
    from brake_sim_ros.detection.report import report_files
    from brake_sim_ros.recording.output import check_output, replace_output

    files = report_files(scores)
    for name in files:
        check_output(Path(directory) / name, inputs=inputs, overwrite=True, option="--report")
    for name, content in files.items():
        replace_output(
            Path(directory) / name,
            lambda tmp, c=content: tmp.write_bytes(c),
            option="--report",
        )
    print(f"report: {', '.join(files)} in {directory}")


def score_options(p: argparse.ArgumentParser) -> None:
    """``score``'s description and options."""
    from brake_sim_ros.detection.registry import help_text

    p.description = (
        "Fit a detector on one split of a sweep's dataset and score it on"
        " another: detection delay, false alarms per healthy hour, AUROC/AUPRC of its"
        " health index (brake_sim_ros.detection.evaluate documents the JSON)."
    )
    p.add_argument("directory", help="a sweep's output directory")
    p.add_argument(
        "--detector",
        action="append",
        help=help_text() + " (default rms); repeat it to score several",
    )
    p.add_argument("--split", default="test", help="split to score (default test)")
    p.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    p.add_argument("--fit-split", help="split to fit on (default train; not with --model)")
    p.add_argument(
        "--hold", dest="hold_s", type=float, default=0.2, help="alarm hold, s (default 0.2)"
    )
    p.add_argument("--out", help="write the score as JSON here (one detector)")
    p.add_argument(
        "--windows",
        metavar="FILE.parquet",
        help="write every assessed window (run, time, health index, alarm, diagnosis, truth,"
        " class) here, to compute any metric (one detector)",
    )
    p.add_argument(
        "--model",
        metavar="MODEL.json",
        help="load the fitted detector from this file (brake-sim fit) instead of fitting it;"
        " --detector, if given, must name the file's",
    )
    p.add_argument(
        "--report",
        metavar="DIR",
        help="write each detector's JSON and the figures (ROC, delays, isolation) here",
    )
    p.set_defaults(func=cmd_score)


# --- plot ----------------------------------------------------------------------------------
def cmd_plot(args: argparse.Namespace) -> int:
    """``brake-sim plot SOURCE --out FILE.png``: one run drawn headless
    (:mod:`brake_sim_ros.detection.plot`)."""
    from brake_sim_ros.detection import plot
    from brake_sim_ros.recording.output import atomic_output, probe_output

    if not args.out.endswith(".png"):
        raise BrakeSimError(f"--out {args.out!r}: allowed a FILE.png path")
    probe_output(args.out, inputs=[args.source], overwrite=args.overwrite, option="--out")
    try:
        columns, name = plot.read_run(args.source, args.run)
        windows = (
            None
            if args.windows is None
            else plot.read_windows(args.windows, name, columns.get("time_s"))
        )
        with atomic_output(args.out, overwrite=args.overwrite, option="--out") as tmp:
            plot.draw(columns, tmp, title=name, windows=windows)
    except ValueError as exc:
        raise BrakeSimError(one_line(exc)) from None
    print(f"plot: {args.out}")
    return 0


def plot_options(p: argparse.ArgumentParser) -> None:
    """``plot``'s options."""
    p.add_argument("source", help="a simulate --out file (.parquet, .npz) or a dataset directory")
    p.add_argument("--run", metavar="RUN_ID", help="the dataset's run to draw")
    p.add_argument(
        "--windows", metavar="FILE.parquet", help="a score --windows file: draw its health index"
    )
    p.add_argument("--out", required=True, metavar="FILE.png", help="the PNG to write")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    p.set_defaults(func=cmd_plot)


SCORE = Command(
    "score", "fit a detector on a dataset's train split and score it on test", score_options
)
FIT = Command("fit", "fit a detector on a dataset's train split and save it as JSON", fit_options)
PLOT = Command(
    "plot",
    "draw one run to a PNG: measured channels with defect labels and drive phases,"
    " a spectrogram, the tone ring's orders, a detector's health index",
    plot_options,
)
