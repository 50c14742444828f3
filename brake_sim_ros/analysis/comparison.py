"""Errors of a run's event metrics against a reference run: one definition for every study.

The work-precision study (``brake-sim bench accuracy``), the fidelity study (``brake-sim
bench fidelity``) and the presets' error bounds (``solvers/presets.py``, checked by
``tests/solvers/test_presets.py``) all compare metrics this way:

* relative error: ``|value / reference - 1|``, a fraction; NaN where either is missing
  (None or not finite);
* the worse shoe: the largest of the shoes' relative errors; NaN if any shoe's is NaN (a
  missing impact or period is not a small error);
* impact count difference: impacts missed or added, **summed** over the shoes,
  ``sum |n - n_reference|``. A sum, not the worse shoe: one impact missed on each shoe
  counts 2, so the figure is the number of impacts the run gets wrong.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from brake_sim_ros.analysis.impacts import EventMetrics
from brake_sim_ros.model.assembly import SIDES


def relative_error(value: float | None, reference: float | None) -> float:
    """``|value / reference - 1|``; NaN where either is None or not finite."""
    if value is None or reference is None:
        return math.nan
    if not (math.isfinite(value) and math.isfinite(reference)):
        return math.nan
    return abs(value / reference - 1.0)


def worse(errors: list[float]) -> float:
    """The largest of ``errors``; NaN if any is NaN or there is none."""
    if not errors or any(math.isnan(e) for e in errors):
        return math.nan
    return max(errors)


def impact_count_diff(
    metrics: EventMetrics, reference: EventMetrics, sides: tuple[str, ...] = SIDES
) -> int:
    """Impacts missed or added, summed over ``sides``: ``sum |n - n_reference|``."""
    return sum(abs(metrics.shoe(s).n_impacts - reference.shoe(s).n_impacts) for s in sides)


@dataclass(frozen=True)
class MetricErrors:
    """Errors of one run against a reference; relative errors are fractions, the worse shoe.

    Attributes:
        stop_time: stopping time.
        first_peak: first-impact peak pivot force.
        period: first impact period.
        contact_force: contact-regime mean pivot force.
        impact_count_diff: impacts missed or added, summed over the shoes.
    """

    stop_time: float
    first_peak: float
    period: float
    contact_force: float
    impact_count_diff: int


def metric_errors(
    metrics: EventMetrics, reference: EventMetrics, sides: tuple[str, ...] = SIDES
) -> MetricErrors:
    """Errors of ``metrics`` against ``reference`` over the shoes ``sides``."""

    def shoes(name: str) -> float:
        return worse(
            [
                relative_error(getattr(metrics.shoe(s), name), getattr(reference.shoe(s), name))
                for s in sides
            ]
        )

    return MetricErrors(
        stop_time=relative_error(metrics.stop_time_s, reference.stop_time_s),
        first_peak=shoes("first_impact_peak_n"),
        period=shoes("period_s"),
        contact_force=shoes("contact_regime_force_n"),
        impact_count_diff=impact_count_diff(metrics, reference, sides),
    )
