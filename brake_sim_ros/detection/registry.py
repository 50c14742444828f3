"""The built-in detectors: one entry each, and everything else reads it.

An entry names the detector, says in one line what it judges (the CLI's help for
``score``, ``fit`` and ``monitor`` is generated from these lines), builds it, says whether
it learns (a detector that learns cannot run unfitted: ``monitor`` asks for ``--fit`` or
``--model``) and whether it has a saved form (``brake-sim fit``: :mod:`.saved` holds the
codec of each class, and ``tests/detection/test_registry.py`` checks every entry against it).

Adding a built-in detector: its class, its entry here, its codec in :mod:`.saved`; the
completeness test fails on an entry that lacks a part.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # each detector's module is imported when it is made: the help is light
    from brake_sim_ros.detection.detector import Detector

USER_FORMS = "module:Class or path/to/file.py:Class"


@dataclass(frozen=True)
class DetectorEntry:
    """One built-in detector.

    Attributes:
        name: its name on the command line and in saved files.
        summary: what it judges, one line.
        make: builds it unfitted, with its default parameters.
        learns: it must be fitted (or loaded fitted) before it can assess.
        saved: it has a saved form (``brake-sim fit``).
    """

    name: str
    summary: str
    make: Callable[[], Detector]
    learns: bool = True
    saved: bool = True


def _statistic(name: str) -> Callable[[], Detector]:
    def make() -> Detector:
        from brake_sim_ros.detection.baselines import VibrationThreshold

        return VibrationThreshold(name)

    return make


def _orders() -> Detector:
    from brake_sim_ros.detection.order_analysis import OrderAnalysis

    return OrderAnalysis()


def _impact() -> Detector:
    from brake_sim_ros.detection.impact import ImpactDetector

    return ImpactDetector()


def _learned() -> Detector:
    from brake_sim_ros.detection.learned import LearnedClassifier

    return LearnedClassifier()


ENTRIES: tuple[DetectorEntry, ...] = (
    DetectorEntry("rms", "rms of the backing plate's y acceleration", _statistic("rms")),
    DetectorEntry("kurtosis", "its kurtosis", _statistic("kurtosis")),
    DetectorEntry("crest", "its crest factor", _statistic("crest")),
    DetectorEntry("orders", "the tone ring's orders, for an out-of-round drum", _orders),
    DetectorEntry("impact", "each stop's first impacts, for shoes and actuation", _impact),
    DetectorEntry("learned", "a random forest on the window features", _learned),
)
REGISTRY: dict[str, DetectorEntry] = {e.name: e for e in ENTRIES}


def names(*, saved_only: bool = False) -> tuple[str, ...]:
    """The built-in names, in the registry's order."""
    return tuple(e.name for e in ENTRIES if e.saved or not saved_only)


def help_text(*, saved_only: bool = False, user: bool = True) -> str:
    """The detectors a command takes, for its ``--help``: each built-in with its summary,
    and (``user``) the forms of a user's detector."""
    entries = [e for e in ENTRIES if e.saved or not saved_only]
    text = "; ".join(f"{e.name}: {e.summary}" for e in entries)
    return f"{text}; or your Detector as {USER_FORMS}" if user else text


# name -> factory
BUILTIN: dict[str, Callable[[], Detector]] = {n: e.make for n, e in REGISTRY.items()}


def make_detector(name: str) -> Detector:
    """A built-in detector by name (:data:`REGISTRY`), or a user's as ``module:Class`` or
    ``path/to/file.py:Class`` (a :class:`Detector` subclass built without arguments:
    :mod:`.user_class`).

    Raises:
        ValueError: one line (an unknown name, a class that cannot be loaded).
    """
    if name in REGISTRY:
        return REGISTRY[name].make()
    if ":" not in name:
        raise ValueError(f"detector {name!r}: allowed {', '.join(REGISTRY)}, {USER_FORMS}")
    from brake_sim_ros.detection.user_class import load_class
    from brake_sim_ros.detection.user_code import user_code

    cls = load_class(name)
    with user_code(cls, "__init__"):
        return cls()
