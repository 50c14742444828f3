"""Remaining useful life: the label a forecast is scored against.

A brake has failed once the first of its defects reaches its kind's service limit
(:attr:`~brake_sim_ros.model.catalogue.DefectKind.service_limit`, in the kind's unit; a
signed limit is reached by a severity of that sign and at least that size). The failure
time is found in the run's per-sample severity labels; when no defect reaches its limit
within the run but one is bound to by the growth law its ground truth states (a step,
linear or exponential law toward a final severity at or beyond the limit), it is that
law's time (:meth:`~brake_sim_ros.model.catalogue.Growth.reached_s`), so that a run cut
short still has its true remaining life, as the test units of NASA's C-MAPSS do. When
neither says (a healthy brake, defects that stay below their limits, or a growth the
labels do not reach and no law predicts), the remaining life is unknown: NaN, the run
right-censored.

``rul_s(t) = max(0, t_fail - t)``, s of simulated time.

Pure: arrays in, arrays out.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass

import numpy as np

from brake_sim_ros.model.catalogue import KIND_BY_NAME, label_column
from brake_sim_ros.model.defects import Defects

RUL_COLUMN = "rul [s]"


@dataclass(frozen=True)
class Failure:
    """When and why the brake reaches the end of its life, as far as the run tells.

    Attributes:
        time_s: simulated time of failure, s; NaN when unknown (censored).
        kind, location: the defect that reaches its limit first ("" when unknown).
        service_limit: that kind's service limit, in ``unit``.
        unit: the kind's unit.
        source: ``"run"`` (the labels reach the limit within the run), ``"law"`` (its
            growth law reaches it after the run's end), or ``"censored"``.
    """

    time_s: float
    kind: str = ""
    location: str = ""
    service_limit: float = math.nan
    unit: str = ""
    source: str = "censored"

    def as_dict(self) -> dict[str, object]:
        """JSON-ready (NaN as None)."""
        return {
            k: (None if isinstance(v, float) and math.isnan(v) else v)
            for k, v in asdict(self).items()
        }


def _reaches(severity: np.ndarray, limit: float) -> np.ndarray:
    """Where a severity has reached a signed limit."""
    return severity * math.copysign(1.0, limit) >= abs(limit)


def failure(defects: Defects, times_s: np.ndarray, labels: Mapping[str, np.ndarray]) -> Failure:
    """The failure of a brake with ``defects`` over a run sampled at ``times_s`` (s), from
    its per-sample severity ``labels`` (label column name -> values, the kind's unit), else
    from the growth laws (module doc)."""
    times = np.asarray(times_s, dtype=np.float64)
    first = Failure(math.nan)
    for active in defects.active():  # catalogue order: a tie goes to the earlier kind
        kind = KIND_BY_NAME[active.kind]
        limit = kind.service_limit
        if limit == 0.0:
            continue
        common = dict(kind=kind.name, location=active.location, service_limit=limit, unit=kind.unit)
        growth = defects.growth_of(active.kind, active.location)
        column = labels.get(label_column(kind, active.location))
        hit = np.flatnonzero(
            _reaches(np.asarray(column, dtype=np.float64), limit)
            if column is not None and len(column) == len(times)
            else np.zeros(0, dtype=bool)
        )
        if hit.size:
            found = Failure(float(times[hit[0]]), **common, source="run")
        # active() without a time: each defect's final severity; a law that follows time
        # alone (not friction work) knows its future
        elif growth.follows_time and bool(_reaches(np.array([active.severity]), limit)[0]):
            t = max(growth.onset_s, growth.reached_s(limit))
            found = Failure(t, **common, source="law")
        else:
            continue
        if math.isnan(first.time_s) or found.time_s < first.time_s:
            first = found
    return first


def rul_series(times_s: np.ndarray, fail: Failure) -> np.ndarray:
    """``max(0, t_fail - t)`` at each of ``times_s`` (s); NaN throughout when censored."""
    times = np.asarray(times_s, dtype=np.float64)
    if math.isnan(fail.time_s):
        return np.full(times.shape[0], math.nan)
    return np.maximum(0.0, fail.time_s - times)
