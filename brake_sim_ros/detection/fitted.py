"""Parts of a saved detector file (:mod:`.saved`) beside the built-ins' own codecs: the
``fitted_at`` record (the rate, the brake and the channels with their units a detector
was fitted on), and the state of a user's detector (:meth:`Detector.saved_state` /
:meth:`Detector.load_state`).

A user's detector is saved as data like the built-ins: ``parameters`` is ``{}`` and
``state`` is what its ``saved_state`` gave, numpy arrays written as the file's arrays
(``{"dtype", "shape", "base64"}``, bit for bit). The file names the detector by its
``name`` only, never by code to import: loading needs the class named on the command line
(``--detector path/to/file.py:Class``), so a file can never make the monitor run code.
"""

from __future__ import annotations

import base64
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from brake_sim_ros.detection.detector import Detector
from brake_sim_ros.model.parameters import BRAKES

# The saved file's version (:mod:`.saved`). 3: ``fitted_at`` records the brake. A version 2
# file is refused rather than read as the study brake's: the service brake came after
# version 2, so either brake may have fitted it.
SCHEMA_VERSION = 3
_OLD_VERSIONS = {1: "version 1 did not record the rate", 2: "version 2 did not record the brake"}
DTYPES = {"float64": "<f8", "int64": "<i8"}
ARRAY_KEYS = ("dtype", "shape", "base64")
MAX_STATE_DEPTH = 16  # nesting of a user's state: objects and lists within each other


def array_json(a: np.ndarray, dtype: str) -> dict[str, Any]:
    """``a`` as a file's array: its little-endian bytes of ``dtype``, base64-encoded."""
    data = np.ascontiguousarray(a, dtype=DTYPES[dtype])
    return {
        "dtype": dtype,
        "shape": list(data.shape),
        "base64": base64.b64encode(data.tobytes()).decode("ascii"),
    }


def fitted_at_json(detector: Detector) -> dict[str, Any]:
    """The ``fitted_at`` object of ``detector``."""
    return {
        "sample_rate_hz": detector.fitted_rate_hz,
        "brake": detector.fitted_brake,
        "channels": dict(detector.fitted_channels),
    }


def read_schema_version(value: object, c: Any) -> None:
    """Refuse a ``schema_version`` other than :data:`SCHEMA_VERSION`, saying what an old
    one lacks; ``c`` is the file's checker."""
    if value == SCHEMA_VERSION and type(value) is int:
        return
    old = _OLD_VERSIONS.get(value) if type(value) is int else None
    allowed = f"allowed {SCHEMA_VERSION}" + (f" ({old}: fit it again)" if old else "")
    raise c.fail("schema_version", f"not one this version reads; {allowed}")


def read_fitted_at(value: object, c: Any) -> tuple[float | None, str | None, dict[str, str]]:
    """``fitted_at``: the rate (None: not recorded), the brake (None: not recorded) and
    each channel's unit; ``c`` is the file's checker (its refusals name the key)."""
    at = c.obj(value, "fitted_at", ("sample_rate_hz", "brake", "channels"))
    rate = at["sample_rate_hz"]
    rate = None if rate is None else c.positive(rate, "fitted_at.sample_rate_hz", 1e7)
    brake = None if at["brake"] is None else c.string(at["brake"], "fitted_at.brake", BRAKES)
    channels = at["channels"]
    if not (isinstance(channels, dict) and len(channels) <= 64):
        raise c.fail("fitted_at.channels", "allowed an object of at most 64 channel: unit")
    for name, unit in channels.items():
        c.channel(name, "fitted_at.channels")
        if not (isinstance(unit, str) and len(unit) <= 32 and unit.isprintable()):
            raise c.fail("fitted_at.channels", "allowed units of at most 32 printable characters")
    return rate, brake, dict(channels)


def has_saved_form(detector: Detector) -> bool:
    """A user's detector that overrides both :meth:`Detector.saved_state` and
    :meth:`Detector.load_state`."""
    cls = type(detector)
    return cls.saved_state is not Detector.saved_state and cls.load_state is not Detector.load_state


def _encode(value: Any, key: str, depth: int) -> Any:
    if depth > MAX_STATE_DEPTH:
        raise ValueError(f"{key}: nested more than {MAX_STATE_DEPTH} deep")
    if isinstance(value, np.ndarray):
        if value.dtype.kind == "f":
            return array_json(value, "float64")
        if value.dtype.kind in "iub":
            return array_json(value, "int64")
        raise ValueError(f"{key}: an array of {value.dtype}; allowed float or integer arrays")
    if isinstance(value, Mapping):
        if not all(isinstance(k, str) for k in value):
            raise ValueError(f"{key}: a key that is not a string")
        if set(value) == set(ARRAY_KEYS):
            raise ValueError(f"{key}: an object with exactly an array's keys {ARRAY_KEYS}")
        return {k: _encode(v, f"{key}.{k}", depth + 1) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_encode(v, f"{key}[{i}]", depth + 1) for i, v in enumerate(value)]
    if isinstance(value, bool | str) or value is None:
        return value
    if isinstance(value, int | float | np.integer | np.floating):
        if isinstance(value, float | np.floating) and not math.isfinite(value):
            raise ValueError(f"{key}: {value}; allowed finite numbers")
        return value.item() if isinstance(value, np.generic) else value
    raise ValueError(f"{key}: a {type(value).__name__}; allowed JSON values and numpy arrays")


def state_json(detector: Detector) -> dict[str, Any]:
    """A user's detector's ``state`` for the file.

    Raises:
        ValueError: not fitted (``saved_state`` gave None) or a value JSON cannot hold.
    """
    state = detector.saved_state()
    if state is None:
        raise ValueError(f"detector {detector.name} is not fitted: nothing to save")
    if not isinstance(state, Mapping):
        raise ValueError(f"detector {detector.name}: saved_state gave no mapping")
    return _encode(state, "state", 0)


def _decode(value: Any, key: str, c: Any) -> Any:
    if isinstance(value, dict):
        if set(value) == set(ARRAY_KEYS):
            shape = value["shape"]
            ndim = len(shape) if isinstance(shape, list) else 1
            dtype = value["dtype"] if value["dtype"] in DTYPES else "float64"
            return c.array(value, key, dtype, ndim)
        return {k: _decode(v, f"{key}.{k}", c) for k, v in value.items()}
    if isinstance(value, list):
        return [_decode(v, f"{key}[{i}]", c) for i, v in enumerate(value)]
    return value


def load_state(detector: Detector, parameters: object, state: object, c: Any) -> Detector:
    """``detector`` (a user's, built without arguments) given the file's ``state``."""
    if parameters != {}:
        raise c.fail("parameters", "allowed {} for a user's detector (its state holds all)")
    if not isinstance(state, dict):
        raise c.fail("state", "allowed an object (the detector's saved_state)")
    try:
        detector.load_state(_decode(state, "state", c))
    except ValueError as exc:
        raise c.fail("state", " ".join(str(exc).split())[:300]) from None
    return detector


def facts_text(detector: Detector) -> str:
    """What ``detector`` was fitted on, for what the CLI prints: its rate and its brake,
    e.g. ``at 5120 Hz on the study brake`` (``not recorded`` where the file says nothing),
    and the training windows a dropout left without a sample, counted."""
    rate = detector.fitted_rate_hz
    brake = detector.fitted_brake
    unjudged = getattr(detector, "unjudged_windows", 0)
    return (
        f"at {'a rate not recorded' if rate is None else f'{rate:g} Hz'} on"
        f" {'a brake not recorded' if brake is None else f'the {brake} brake'}"
        + (f"; {unjudged} healthy windows without a finite sample left out" if unjudged else "")
    )
