"""Fitted detectors saved as JSON and loaded without refitting (``brake-sim fit``,
``score --model``, ``monitor --model``).

A saved detector is data, never code: no pickle (unpickling runs what the file names, and a
monitor must never execute a file). The loader is written for a hostile file: the file
must be a regular file of at most :data:`MAX_MODEL_BYTES`, strict JSON (no NaN, no
duplicate keys), and every key is checked for type, range and shape before anything is
built; a refusal is one line (:class:`ModelFileError`) naming the key and what is allowed,
and never shows the file's contents. The random forests of ``learned`` are stored as their
trees' arrays (:mod:`.forest` says why, and checks every index). :func:`dumps` gives a
file's text; the CLI writes it (whole, never through a link or over an input:
:mod:`brake_sim_ros.recording.output`, an adapter this layer does not import).

The file (:data:`SCHEMA_VERSION` 3), one JSON object::

    format          "brake-sim detector"
    schema_version  3 (version 1 did not record the rate, version 2 the brake: both are
                    refused, fit it again)
    detector        the detector's name: rms, kurtosis, crest, orders, impact, learned
    software        brake_sim_ros version that wrote it (informative)
    fitted_on       {"dataset": path, "split": name, "windows": count} (informative)
    fitted_at       {"sample_rate_hz": Hz or null (not recorded), "brake": "study" or
                    "service" or null (not recorded), "channels": {name: unit}}
                    what it was fitted on; samples at another rate or from the other
                    brake are refused
    parameters      the constructor's arguments (below)
    state           what fitting learned (below)

Arrays are ``{"dtype": "float64" | "int64", "shape": [...], "base64": ...}``: the values'
little-endian bytes, base64-encoded, so numbers come back bit for bit.

* ``rms``, ``kurtosis``, ``crest`` (:class:`~.baselines.VibrationThreshold`): parameters
  ``channel`` (a measured channel's name), ``window_s`` (s), ``k`` (standard deviations);
  state ``threshold`` (the statistic's alarm level, > 0, in the statistic's unit).
* ``orders`` (:class:`~.order_analysis.OrderAnalysis`): parameters ``history_s``,
  ``window_s`` (s), ``quantile``, ``gate_channel`` (a channel's name, or null: no gate);
  state ``gate`` (m/s^2 rms above which nothing is judged; null: no gate), ``mean`` and
  ``std`` (log10 rad, one per order of :data:`~.features.ORDERS`), ``threshold`` (> 0),
  ``healthy_index`` (the healthy training histories' health index, 1-D).
* ``learned`` (:class:`~.learned.LearnedClassifier`): parameters ``history_s``,
  ``window_s`` (s), ``channels`` (names); state ``classes`` (sorted: ``healthy`` and
  catalogue ``kind:location`` names), ``threshold`` (P(defective) at the alarm, 0.5 to 1),
  ``healthy_index`` (1-D), ``forest`` (the classifier: a forest, one leaf value per
  class) and ``severity`` (``{"kind:location": forest}``, each a regressor with one leaf
  value: the severity in the kind's unit). A forest is ``{"n_features": count,
  "node_counts", "left", "right", "feature": int64 arrays, "threshold": float64 array,
  "leaf_values": float64 array (leaves, outputs)}`` (:class:`~.forest.ForestArrays`).
* ``impact`` (:class:`~.impact.ImpactDetector`): parameters ``window_s`` (s); state
  ``sample_rate_hz`` (the rate it was fitted at, Hz), ``coef`` (2, F) (each feature's
  healthy value at rise rate 0 and its slope per bar/s), ``scale`` (F, > 0), ``location``
  (F), ``precision`` (F, F), ``rate_mean`` (bar/s), ``threshold`` (> 0),
  ``healthy_index`` (1-D), ``classes`` (sorted catalogue ``kind:location`` names, may be
  empty), ``centroids`` (classes, F), ``severity_slope`` (classes; null entries are no
  estimate), F = :data:`~.impact.N_FEATURES`.
"""

from __future__ import annotations

import base64
import binascii
import json
import math
import os
import re
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from brake_sim_ros import __version__, regular_file
from brake_sim_ros.detection import registry
from brake_sim_ros.detection.baselines import STATISTICS, VibrationThreshold
from brake_sim_ros.detection.detector import Detector
from brake_sim_ros.detection.features import ORDERS, feature_names
from brake_sim_ros.detection.fitted import (
    DTYPES,
    SCHEMA_VERSION,
    array_json,
    fitted_at_json,
    has_saved_form,
    load_state,
    read_fitted_at,
    read_schema_version,
    state_json,
)
from brake_sim_ros.detection.forest import ForestArrays
from brake_sim_ros.detection.impact import N_FEATURES, ImpactDetector
from brake_sim_ros.detection.learned import HEALTHY, LearnedClassifier
from brake_sim_ros.detection.order_analysis import OrderAnalysis
from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.model.catalogue import KINDS
from brake_sim_ros.regular_file import FileRefusedError, read_regular_file

FORMAT = "brake-sim detector"
# The largest file the loader reads: 256 MiB. The reference campaign's learned detector
# (100 trees on 14 040 windows, 18 severity forests) takes 61 MB: a campaign four times
# its size fits; a larger file is refused before it is read.
MAX_MODEL_BYTES = 256 * 1024**2
SAVED = registry.names(saved_only=True)  # the detectors that have a saved form
TOP_KEYS = (
    "format",
    "schema_version",
    "detector",
    "software",
    "fitted_on",
    "fitted_at",
    "parameters",
    "state",
)
DEFECTIVE_CLASSES = frozenset(f"{k.name}:{loc}" for k in KINDS for loc in k.locations)
CLASSES = DEFECTIVE_CLASSES | {HEALTHY}
_NAME = re.compile(r"[a-z][a-z0-9_]{0,63}")  # a measured channel's name
MAX_WINDOW_S = 60.0  # longest window or history a saved detector may ask for, s


class ModelFileError(BrakeSimError, ValueError):
    """A saved detector the loader refuses, or one that cannot be saved (one line)."""


# --- checking what a file holds ---------------------------------------------------------
def _type_name(value: object) -> str:
    return {dict: "an object", list: "a list", str: "a string", bool: "true/false"}.get(
        type(value), "null" if value is None else "a number"
    )


class _Checker:
    """Reads typed values out of the parsed JSON; each refusal names the key."""

    def __init__(self, where: str) -> None:
        self.where = where

    def fail(self, key: str, problem: str) -> ModelFileError:
        return ModelFileError(f"{self.where}: {key}: {problem}")

    def obj(self, value: object, key: str, keys: Sequence[str]) -> dict[str, Any]:
        if not isinstance(value, dict):
            raise self.fail(key, f"{_type_name(value)}; allowed an object")
        for k in keys:
            if k not in value:
                raise self.fail(key, f"no key {k!r}; allowed exactly {', '.join(keys)}")
        if len(value) != len(keys):
            raise self.fail(key, f"an unknown key; allowed exactly {', '.join(keys)}")
        return value

    def number(self, value: object, key: str, low: float, high: float) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(key, f"{_type_name(value)}; allowed a number {low:g} to {high:g}")
        if not low <= value <= high:
            raise self.fail(key, f"out of range; allowed {low:g} to {high:g}")
        try:
            return float(value)
        except OverflowError:  # an integer of hundreds of digits
            raise self.fail(key, f"too large; allowed {low:g} to {high:g}") from None

    def positive(self, value: object, key: str, high: float = math.inf) -> float:
        x = self.number(value, key, 0.0, high)
        if not (x > 0.0 and math.isfinite(x)):
            raise self.fail(key, f"allowed a finite number > 0 up to {high:g}")
        return x

    def integer(self, value: object, key: str, low: int, high: int) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            raise self.fail(key, f"allowed an integer {low} to {high}")
        return value

    def string(self, value: object, key: str, allowed: Sequence[str] | None = None) -> str:
        if not isinstance(value, str):
            raise self.fail(key, f"{_type_name(value)}; allowed a string")
        if allowed is not None and value not in allowed:
            raise self.fail(key, f"not one allowed here; allowed {', '.join(allowed)}")
        return value

    def channel(self, value: object, key: str) -> str:
        name = self.string(value, key)
        if not _NAME.fullmatch(name):
            raise self.fail(key, "allowed a channel name: lower case, digits, _ (1-64)")
        return name

    def array(self, value: object, key: str, dtype: str, ndim: int) -> np.ndarray:
        a = self.obj(value, key, ("dtype", "shape", "base64"))
        if a["dtype"] != dtype:
            raise self.fail(f"{key}.dtype", f"allowed {dtype!r}")
        shape = a["shape"]
        if not (isinstance(shape, list) and len(shape) == ndim):
            raise self.fail(f"{key}.shape", f"allowed a list of {ndim} sizes")
        dims = [self.integer(n, f"{key}.shape", 0, MAX_MODEL_BYTES) for n in shape]
        text = self.string(a["base64"], f"{key}.base64")
        try:
            raw = base64.b64decode(text.encode("ascii"), validate=True)
        except (UnicodeEncodeError, binascii.Error):
            raise self.fail(f"{key}.base64", "not base64; allowed the values' bytes") from None
        if len(raw) != math.prod(dims) * 8:
            raise self.fail(
                f"{key}.base64", f"{len(raw)} bytes; its shape {dims} needs {math.prod(dims) * 8}"
            )
        out = np.frombuffer(raw, dtype=DTYPES[dtype]).reshape(dims).astype(dtype, copy=False)
        if dtype == "float64" and not np.all(np.isfinite(out)):
            raise self.fail(key, "a NaN or infinite value; allowed finite numbers")
        return out

    def class_names(
        self, value: object, key: str, allowed: frozenset[str], low: int
    ) -> tuple[str, ...]:
        """A sorted list of ``low`` or more distinct class names out of ``allowed``."""
        if not (isinstance(value, list) and low <= len(value) <= len(allowed)):
            raise self.fail(key, f"allowed a list of {low} to {len(allowed)} class names")
        for x in value:
            if self.string(x, key) not in allowed:
                names = "healthy or kind:location" if HEALTHY in allowed else "kind:location"
                raise self.fail(key, f"an unknown class; allowed {names}")
        if value != sorted(set(value)):
            raise self.fail(key, "allowed distinct names, sorted")
        return tuple(value)

    def history(self, p: dict[str, Any]) -> tuple[float, float]:
        """``(window_s, history_s)`` of a history detector's parameters."""
        window_s = self.positive(p["window_s"], "parameters.window_s", MAX_WINDOW_S)
        history_s = self.positive(p["history_s"], "parameters.history_s", MAX_WINDOW_S)
        if history_s < window_s:
            raise self.fail("parameters.history_s", "allowed at least parameters.window_s")
        return window_s, history_s

    def forest(self, value: object, key: str, outputs: int) -> ForestArrays:
        f = self.obj(
            value,
            key,
            ("n_features", "node_counts", "left", "right", "feature", "threshold", "leaf_values"),
        )
        n_features = len(feature_names())
        if f["n_features"] != n_features or isinstance(f["n_features"], bool):
            raise self.fail(f"{key}.n_features", f"allowed {n_features} (the window features)")
        forest = ForestArrays(
            n_features=n_features,
            node_counts=self.array(f["node_counts"], f"{key}.node_counts", "int64", 1),
            left=self.array(f["left"], f"{key}.left", "int64", 1),
            right=self.array(f["right"], f"{key}.right", "int64", 1),
            feature=self.array(f["feature"], f"{key}.feature", "int64", 1),
            threshold=self.array(f["threshold"], f"{key}.threshold", "float64", 1),
            leaf_values=self.array(f["leaf_values"], f"{key}.leaf_values", "float64", 2),
        )
        problem = forest.check()
        if problem is not None:
            raise self.fail(key, problem)
        if forest.leaf_values.shape[1] != outputs:
            raise self.fail(f"{key}.leaf_values", f"allowed {outputs} values per leaf")
        return forest


def _forest(f: ForestArrays) -> dict[str, Any]:
    return {
        "n_features": f.n_features,
        "node_counts": array_json(f.node_counts, "int64"),
        "left": array_json(f.left, "int64"),
        "right": array_json(f.right, "int64"),
        "feature": array_json(f.feature, "int64"),
        "threshold": array_json(f.threshold, "float64"),
        "leaf_values": array_json(f.leaf_values, "float64"),
    }


def _as_arrays(model: Any) -> ForestArrays:
    return model if isinstance(model, ForestArrays) else ForestArrays.from_sklearn(model)


# --- each detector's parameters and state ----------------------------------------------
def _dump_threshold(d: VibrationThreshold) -> tuple[dict, dict]:
    assert d.threshold is not None
    return (
        {"channel": d.channels[0], "window_s": d.window_s, "k": d.k},
        {"threshold": d.threshold},
    )


def _load_threshold(name: str, p: dict, s: dict, c: _Checker) -> Detector:
    p = c.obj(p, "parameters", ("channel", "window_s", "k"))
    s = c.obj(s, "state", ("threshold",))
    d = VibrationThreshold(
        name,
        c.channel(p["channel"], "parameters.channel"),
        window_s=c.positive(p["window_s"], "parameters.window_s", MAX_WINDOW_S),
        k=c.positive(p["k"], "parameters.k", 1e3),
    )
    d.threshold = c.positive(s["threshold"], "state.threshold")
    return d


def _dump_orders(d: OrderAnalysis) -> tuple[dict, dict]:
    assert d.mean is not None and d.std is not None and d.threshold is not None
    return (
        {
            "history_s": d.history_s,
            "window_s": d.window_s,
            "quantile": d.quantile,
            "gate_channel": d.gate_channel,
        },
        {
            "gate": d.gate if math.isfinite(d.gate) else None,
            "mean": array_json(d.mean, "float64"),
            "std": array_json(d.std, "float64"),
            "threshold": d.threshold,
            "healthy_index": array_json(d.healthy_index, "float64"),
        },
    )


def _load_orders(name: str, p: dict, s: dict, c: _Checker) -> Detector:
    p = c.obj(p, "parameters", ("history_s", "window_s", "quantile", "gate_channel"))
    s = c.obj(s, "state", ("gate", "mean", "std", "threshold", "healthy_index"))
    window_s, history_s = c.history(p)
    gate = p["gate_channel"]
    d = OrderAnalysis(
        history_s=history_s,
        window_s=window_s,
        quantile=c.number(p["quantile"], "parameters.quantile", 0.5, 1.0),
        gate_channel=None if gate is None else c.channel(gate, "parameters.gate_channel"),
    )
    if (s["gate"] is None) != (gate is None):
        raise c.fail("state.gate", "allowed null exactly when parameters.gate_channel is null")
    d.gate = math.inf if s["gate"] is None else c.number(s["gate"], "state.gate", 0.0, 1e300)
    for key in ("mean", "std"):
        a = c.array(s[key], f"state.{key}", "float64", 1)
        if a.shape != (len(ORDERS),):
            raise c.fail(f"state.{key}", f"allowed one value per order ({len(ORDERS)})")
        setattr(d, key, a)
    if not np.all(d.std > 0.0):  # type: ignore[operator]
        raise c.fail("state.std", "allowed values > 0")
    d.threshold = c.positive(s["threshold"], "state.threshold")
    d.healthy_index = c.array(s["healthy_index"], "state.healthy_index", "float64", 1)
    return d


def _dump_learned(d: LearnedClassifier) -> tuple[dict, dict]:
    assert d.model is not None and d.threshold is not None
    return (
        {"history_s": d.history_s, "window_s": d.window_s, "channels": list(d.channels)},
        {
            "classes": list(d.classes),
            "threshold": d.threshold,
            "healthy_index": array_json(d.healthy_index, "float64"),
            "forest": _forest(_as_arrays(d.model)),
            "severity": {c: _forest(_as_arrays(m)) for c, m in d.severity_models.items()},
        },
    )


def _load_learned(name: str, p: dict, s: dict, c: _Checker) -> Detector:
    p = c.obj(p, "parameters", ("history_s", "window_s", "channels"))
    s = c.obj(s, "state", ("classes", "threshold", "healthy_index", "forest", "severity"))
    window_s, history_s = c.history(p)
    channels = p["channels"]
    if not (isinstance(channels, list) and 1 <= len(channels) <= 64):
        raise c.fail("parameters.channels", "allowed a list of 1 to 64 channel names")
    names = tuple(c.channel(x, "parameters.channels") for x in channels)
    if len(set(names)) != len(names):
        raise c.fail("parameters.channels", "a name twice; allowed distinct names")
    classes = c.class_names(s["classes"], "state.classes", CLASSES, 2)
    if HEALTHY not in classes:
        raise c.fail("state.classes", "allowed healthy among the classes")
    severity = s["severity"]
    if not isinstance(severity, dict):
        raise c.fail("state.severity", f"{_type_name(severity)}; allowed an object")
    if not set(severity) <= set(classes) - {HEALTHY}:
        raise c.fail("state.severity", "a key that is not a defective class of state.classes")
    d = LearnedClassifier(history_s=history_s, window_s=window_s, channels=names)
    d.classes = classes
    d.threshold = c.number(s["threshold"], "state.threshold", 0.5, 1.0)
    d.healthy_index = c.array(s["healthy_index"], "state.healthy_index", "float64", 1)
    d.model = c.forest(s["forest"], "state.forest", len(classes))
    d.severity_models = {
        k: c.forest(v, f"state.severity.{k}", 1) for k, v in sorted(severity.items())
    }
    return d


def _dump_impact(d: ImpactDetector) -> tuple[dict, dict]:
    assert d.threshold is not None and d.sample_rate_hz is not None
    return (
        {"window_s": d.window_s},
        {
            "sample_rate_hz": d.sample_rate_hz,
            "coef": array_json(d.coef, "float64"),
            "scale": array_json(d.scale, "float64"),
            "location": array_json(d.location, "float64"),
            "precision": array_json(d.precision, "float64"),
            "rate_mean": d.rate_mean,
            "threshold": d.threshold,
            "healthy_index": array_json(d.healthy_index, "float64"),
            "classes": list(d.classes),
            "centroids": array_json(d.centroids, "float64"),
            "severity_slope": [x if math.isfinite(x) else None for x in d.severity_slope],
        },
    )


def _load_impact(name: str, p: dict, s: dict, c: _Checker) -> Detector:
    p = c.obj(p, "parameters", ("window_s",))
    keys = (
        "sample_rate_hz", "coef", "scale", "location", "precision", "rate_mean", "threshold",
        "healthy_index", "classes", "centroids", "severity_slope",
    )  # fmt: skip
    s = c.obj(s, "state", keys)
    d = ImpactDetector(window_s=c.positive(p["window_s"], "parameters.window_s", MAX_WINDOW_S))
    d.sample_rate_hz = c.positive(s["sample_rate_hz"], "state.sample_rate_hz", 1e7)
    f = N_FEATURES
    shapes = {"coef": (2, f), "scale": (f,), "location": (f,), "precision": (f, f)}
    for key, shape in shapes.items():
        a = c.array(s[key], f"state.{key}", "float64", len(shape))
        if a.shape != shape:
            raise c.fail(f"state.{key}", f"allowed shape {list(shape)}")
        setattr(d, key, a)
    if not np.all(d.scale > 0.0):
        raise c.fail("state.scale", "allowed values > 0")
    d.rate_mean = c.number(s["rate_mean"], "state.rate_mean", -1e9, 1e9)
    d.threshold = c.positive(s["threshold"], "state.threshold")
    d.healthy_index = c.array(s["healthy_index"], "state.healthy_index", "float64", 1)
    classes = c.class_names(s["classes"], "state.classes", DEFECTIVE_CLASSES, 0)
    d.classes = classes
    centroids = c.array(s["centroids"], "state.centroids", "float64", 2)
    if centroids.shape != (len(classes), f):
        raise c.fail("state.centroids", f"allowed shape [{len(classes)}, {f}]")
    d.centroids = centroids
    slopes = s["severity_slope"]
    if not (isinstance(slopes, list) and len(slopes) == len(classes)):
        raise c.fail("state.severity_slope", "allowed a list of one number or null per class")
    d.severity_slope = np.array(
        [
            math.nan if x is None else c.number(x, "state.severity_slope", -1e12, 1e12)
            for x in slopes
        ]
    )
    return d


_Loader = Callable[[str, dict, dict, _Checker], Detector]
_CODECS: dict[type, tuple[Callable[[Any], tuple[dict, dict]], _Loader]] = {
    VibrationThreshold: (_dump_threshold, _load_threshold),
    OrderAnalysis: (_dump_orders, _load_orders),
    LearnedClassifier: (_dump_learned, _load_learned),
    ImpactDetector: (_dump_impact, _load_impact),
}
_LOADERS: dict[str, _Loader] = {
    **dict.fromkeys(STATISTICS, _load_threshold),
    "orders": _load_orders,
    "impact": _load_impact,
    "learned": _load_learned,
}


# --- the file ---------------------------------------------------------------------------
def check_savable(detector: Detector) -> None:
    """Refuse, in one line, a detector with no saved form (a user's without
    ``saved_state`` and ``load_state``).

    Raises:
        ModelFileError: the detector is not one of :data:`SAVED`.
    """
    builtin = type(detector) in _CODECS and detector.name in SAVED
    if not (builtin or (not isinstance(detector, tuple(_CODECS)) and has_saved_form(detector))):
        raise ModelFileError(
            f"detector {detector.name}: no saved form; allowed {', '.join(SAVED)}, or a"
            " Detector with saved_state and load_state"
        )


def document(detector: Detector, *, fitted_on: Mapping[str, Any]) -> dict[str, Any]:
    """The JSON object of a fitted detector (module docstring).

    Raises:
        ModelFileError: a detector with no saved form, or one not fitted.
    """
    check_savable(detector)
    if type(detector) not in _CODECS:  # a user's
        try:
            parameters, state = {}, state_json(detector)
        except ValueError as exc:
            raise ModelFileError(" ".join(str(exc).split())) from None
    elif getattr(detector, "threshold", None) is None:
        raise ModelFileError(f"detector {detector.name} is not fitted: nothing to save")
    else:
        parameters, state = _CODECS[type(detector)][0](detector)
    return {
        "format": FORMAT,
        "schema_version": SCHEMA_VERSION,
        "detector": detector.name,
        "software": f"brake_sim_ros {__version__}",
        "fitted_on": dict(fitted_on),
        "fitted_at": fitted_at_json(detector),
        "parameters": parameters,
        "state": state,
    }


def dumps(detector: Detector, *, fitted_on: Mapping[str, Any]) -> str:
    """The file's text for a fitted detector (:func:`document` as strict JSON). Writing it
    is the caller's (the CLI writes it whole, never through a link:
    :mod:`brake_sim_ros.recording.output`).

    Raises:
        ModelFileError: nothing to save (:func:`document`).
    """
    return json.dumps(document(detector, fitted_on=fitted_on), allow_nan=False, indent=1) + "\n"


def _refuse_constant(name: str) -> None:
    raise ValueError(f"{name} is not JSON")


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out = dict(pairs)
    if len(out) != len(pairs):
        raise ValueError("a key appears twice in one object")
    return out


def _refusal(where: str, exc: FileRefusedError) -> str:
    """The one-line message for a saved detector :func:`read_regular_file` refused."""
    if exc.reason in (regular_file.MISSING, regular_file.NOT_OPENED):
        return f"{where}: cannot open it ({exc.detail})"
    if exc.reason == regular_file.NOT_A_PATH:
        return f"{where}: cannot open it (not a valid path)"
    if exc.reason == regular_file.NOT_REGULAR:
        return f"{where}: not a regular file; allowed a saved detector"
    if exc.reason == regular_file.TOO_LARGE:
        return f"{where}: {exc.size} bytes; allowed at most {MAX_MODEL_BYTES}"
    if exc.reason == regular_file.GREW:
        return f"{where}: more than {MAX_MODEL_BYTES} bytes; allowed at most that"
    return f"{where}: cannot read it ({exc.detail})"


def read_document(path: str | os.PathLike[str], *, where: str = "saved detector") -> dict[str, Any]:
    """The parsed JSON of a saved detector file, after the file's checks (a regular file of
    at most :data:`MAX_MODEL_BYTES`, UTF-8, strict JSON, no duplicate keys).

    ``where`` names the file in messages (the CLI: the option and the path).

    Raises:
        ModelFileError: one line naming what is wrong.
    """
    try:
        raw = read_regular_file(path, MAX_MODEL_BYTES)
    except FileRefusedError as exc:
        raise ModelFileError(_refusal(where, exc)) from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ModelFileError(f"{where}: not UTF-8 text; allowed a saved detector (JSON)") from None
    try:
        doc = json.loads(text, parse_constant=_refuse_constant, object_pairs_hook=_unique_keys)
    except json.JSONDecodeError as exc:
        raise ModelFileError(
            f"{where}: not JSON (line {exc.lineno} column {exc.colno}: {exc.msg})"
        ) from None
    except RecursionError:
        raise ModelFileError(f"{where}: JSON nested too deep; allowed a saved detector") from None
    except ValueError as exc:  # NaN, Infinity, a duplicate key: fixed texts
        raise ModelFileError(f"{where}: {exc}; allowed strict JSON") from None
    return doc


def load(
    path: str | os.PathLike[str],
    name: str | None = None,
    *,
    where: str = "saved detector",
    user: Detector | None = None,
) -> Detector:
    """The fitted detector saved in ``path``, ready to feed; with ``name``, only if the
    file holds that detector. ``where`` names the file in messages. ``user``: a user's
    detector built without arguments (its class named on the command line, never by the
    file), given the file's state if the file holds a detector of its name.

    Raises:
        ModelFileError: one line naming the key and what is allowed (module docstring).
    """
    doc = read_document(path, where=where)
    c = _Checker(where)
    doc = c.obj(doc, "the file", TOP_KEYS)
    if doc["format"] != FORMAT:
        raise c.fail("format", f"not a saved detector; allowed {FORMAT!r}")
    read_schema_version(doc["schema_version"], c)
    kind = c.string(doc["detector"], "detector", SAVED if user is None else (user.name,))
    if name is not None and user is None and kind != name:
        raise c.fail("detector", f"the file holds a fitted {kind}; allowed the named one, {name}")
    c.string(doc["software"], "software")
    fitted = c.obj(doc["fitted_on"], "fitted_on", ("dataset", "split", "windows"))
    c.string(fitted["dataset"], "fitted_on.dataset")
    c.string(fitted["split"], "fitted_on.split")
    c.integer(fitted["windows"], "fitted_on.windows", 0, 2**62)
    rate, brake, channels = read_fitted_at(doc["fitted_at"], c)
    if user is None:
        loaded = _LOADERS[kind](kind, doc["parameters"], doc["state"], c)
    else:
        loaded = load_state(user, doc["parameters"], doc["state"], c)
    unread = sorted(set(channels) - set(loaded.channels))
    if unread:  # the units it was fitted with are of channels it reads (fit records them)
        raise c.fail(
            "fitted_at.channels",
            f"{unread[0]!r} is a channel the detector does not read; allowed channels of"
            f" {sorted(loaded.channels)}",
        )
    if rate is not None and user is None:  # a user's window_samples runs guarded, later
        try:
            loaded.window_samples(rate)
        except ValueError as exc:
            raise c.fail("parameters.window_s", str(exc)) from None
    loaded.fitted_rate_hz, loaded.fitted_brake, loaded.fitted_channels = rate, brake, channels
    return loaded
