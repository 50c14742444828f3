"""Impacts, impact periods, regimes and stopping time from recorded samples.

Definitions (used by the validation report and the tests alike):

* impact: a contact onset as :mod:`.onsets` defines it, at the instant the shoe's
  indentation crosses zero upward (linearly interpolated between samples); a contact
  already present at the first sample is no impact;
* impact period ``T``: time from a shoe's first impact to its second; the whole series of
  onset-to-onset intervals is kept too;
* peak pivot force of an impact: the largest ``|F_pivot|`` between that onset and the
  next separation (parabolic refinement around the largest sample);
* end of the impacting regime: the onset of the first contact that lasts at least
  ``settle_s`` (the shoe rides on the drum from then on);
* contact-regime pivot force: time-weighted mean ``|F_pivot|`` over ``window_s``
  (default 1 s to 6 s), cut at the stop if the drum stops earlier; none (NaN, with the
  reason in words) when fewer than two samples fall in the window, e.g. when the drum
  locks during the impacting regime or the run ends before 1 s;
* stopping time: the instant the brake locks (sliding speed down to the smoothing width).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from brake_sim_ros.analysis.onsets import contact_changes, crossing_times, in_contact
from brake_sim_ros.model.run_setup import SampleBlock

CONTACT_WINDOW_S = (1.0, 6.0)
SETTLE_S = 0.05


@dataclass(frozen=True)
class ShoeMetrics:
    """What happened to one shoe; forces in N, times in s.

    Attributes:
        onsets_s, separations_s: interpolated contact onsets and separations.
        impact_peaks_n: peak ``|F_pivot|`` of each impact.
        first_impact_actuation_n: actuation force at the first impact (NaN without one).
        end_of_impacting_s: onset of the first settled contact (NaN without one).
        contact_regime_force_n: contact-regime mean ``|F_pivot|`` (NaN without one).
        impacts_analysed: False where the run kept no impact signals or its shoes had no
            impact dynamics (then the impact fields above are empty or NaN).
        no_contact_regime_reason: why ``contact_regime_force_n`` is NaN, in words; empty
            where it is a number.
    """

    onsets_s: np.ndarray
    separations_s: np.ndarray
    impact_peaks_n: np.ndarray
    first_impact_actuation_n: float
    end_of_impacting_s: float
    contact_regime_force_n: float
    impacts_analysed: bool = True
    no_contact_regime_reason: str = ""

    @property
    def n_impacts(self) -> int:
        return int(self.onsets_s.size)

    @property
    def first_impact_peak_n(self) -> float:
        return float(self.impact_peaks_n[0]) if self.impact_peaks_n.size else float("nan")

    @property
    def period_s(self) -> float:
        """First-to-second impact period T (nan with fewer than two impacts)."""
        return (
            float(self.onsets_s[1] - self.onsets_s[0]) if self.onsets_s.size > 1 else float("nan")
        )

    @property
    def periods_s(self) -> np.ndarray:
        return np.diff(self.onsets_s)


@dataclass(frozen=True)
class EventMetrics:
    left: ShoeMetrics
    right: ShoeMetrics
    stop_time_s: float | None

    def shoe(self, side: str) -> ShoeMetrics:
        return self.left if side == "left" else self.right


def _refined_peak(y: np.ndarray, i: int) -> float:
    """Parabolic refinement of a sampled maximum at index ``i`` (uniform spacing assumed)."""
    if 0 < i < y.size - 1:
        a, b, c = y[i - 1], y[i], y[i + 1]
        denom = a - 2 * b + c
        if denom < 0:
            return float(b - 0.125 * (a - c) ** 2 / denom)
    return float(y[i])


def time_weighted_mean(t: np.ndarray, y: np.ndarray, start: float, end: float) -> float:
    mask = (t >= start) & (t <= end)
    if mask.sum() < 2:
        return float("nan")
    tt, yy = t[mask], y[mask]
    return float(np.trapezoid(yy, tt) / (tt[-1] - tt[0]))


def contact_regime_force(
    t: np.ndarray,
    pivot_force_n: np.ndarray,
    *,
    stop_time_s: float | None,
    window_s: tuple[float, float] = CONTACT_WINDOW_S,
) -> float:
    """Contact-regime pivot force: time-weighted mean ``|F_pivot|`` (N) over ``window_s``,
    cut at the stop if the drum stops earlier."""
    end = window_s[1] if stop_time_s is None else min(window_s[1], stop_time_s)
    return time_weighted_mean(t, pivot_force_n, window_s[0], end)


def no_contact_regime_reason(
    t: np.ndarray,
    *,
    stop_time_s: float | None,
    end_of_impacting_s: float | None,
    window_s: tuple[float, float] = CONTACT_WINDOW_S,
) -> str:
    """Why :func:`contact_regime_force` of samples at times ``t`` (s) has no value.

    Args:
        stop_time_s: the lock instant the force was cut at, or None.
        end_of_impacting_s: the shoe's end of the impacting regime (NaN: it never settled),
            or None where impacts were not analysed.
    """
    start, end = window_s
    window = f"the contact-regime window ({start:g}-{end:g} s)"
    if t.size == 0:
        return "no samples"
    if stop_time_s is not None and stop_time_s < start:
        during = ""
        if end_of_impacting_s is not None and not end_of_impacting_s < stop_time_s:
            during = " during the impacting regime"
        return f"the drum locked at {stop_time_s:.4f} s{during}, before {window}"
    if t[-1] < start:
        return f"not reached within the run: it ends at {t[-1]:.3f} s, before {window}"
    return f"fewer than two samples in {window}"


def contact_only_metrics(
    block: SampleBlock,
    side: str,
    *,
    stop_time_s: float | None,
    window_s: tuple[float, float] = CONTACT_WINDOW_S,
) -> ShoeMetrics:
    """Metrics of a model without impacts (or a run that kept no impact signals): only the
    contact-regime force, when the pivot force was kept; everything else empty or nan."""
    force, reason = float("nan"), "its pivot force was not kept (not asked for)"
    if block.has(f"{side}_pivot_fx_n", f"{side}_pivot_fy_n"):
        t = block.time_s
        force = contact_regime_force(
            t, block.pivot_force_magnitude(side), stop_time_s=stop_time_s, window_s=window_s
        )
        reason = (
            no_contact_regime_reason(
                t, stop_time_s=stop_time_s, end_of_impacting_s=None, window_s=window_s
            )
            if math.isnan(force)
            else ""
        )
    empty = np.empty(0)
    nan = float("nan")
    return ShoeMetrics(
        empty,
        empty,
        empty,
        nan,
        nan,
        force,
        impacts_analysed=False,
        no_contact_regime_reason=reason,
    )


def shoe_metrics(
    block: SampleBlock,
    side: str,
    *,
    stop_time_s: float | None,
    window_s: tuple[float, float] = CONTACT_WINDOW_S,
    settle_s: float = SETTLE_S,
) -> ShoeMetrics:
    t = block.time_s
    eps = block[f"{side}_indentation_m"]
    fr = block.pivot_force_magnitude(side)
    changes = contact_changes(in_contact(eps))  # no change at the first sample
    on_idx, sep_idx = changes.onsets, changes.separations
    onsets = crossing_times(t, eps, on_idx)
    seps = crossing_times(t, eps, sep_idx)
    peaks = []
    for i0 in on_idx:
        later = sep_idx[sep_idx > i0 - 1]
        i1 = int(later[0]) if later.size else t.size - 1
        window = fr[i0 : i1 + 1] if i1 >= i0 else fr[i0 : i0 + 1]
        j = int(np.argmax(window))
        # refine only an interior maximum: at the window's edge the force jumps (onset)
        peaks.append(_refined_peak(fr, i0 + j) if 0 < j < window.size - 1 else float(window[j]))
    actuation = (
        float(np.interp(onsets[0], t, block[f"{side}_actuation_force_n"]))
        if (onsets.size)
        else float("nan")
    )
    end_impacting = float("nan")
    for t_on in onsets:
        nxt = seps[seps > t_on]
        lasts = (nxt[0] if nxt.size else t[-1]) - t_on
        if lasts >= settle_s:
            end_impacting = float(t_on)
            break
    contact = contact_regime_force(t, fr, stop_time_s=stop_time_s, window_s=window_s)
    reason = (
        no_contact_regime_reason(
            t, stop_time_s=stop_time_s, end_of_impacting_s=end_impacting, window_s=window_s
        )
        if math.isnan(contact)
        else ""
    )
    return ShoeMetrics(
        onsets_s=onsets,
        separations_s=seps,
        impact_peaks_n=np.asarray(peaks),
        first_impact_actuation_n=actuation,
        end_of_impacting_s=end_impacting,
        contact_regime_force_n=contact,
        no_contact_regime_reason=reason,
    )


def event_metrics(
    block: SampleBlock,
    *,
    stop_time_s: float | None,
    window_s: tuple[float, float] = CONTACT_WINDOW_S,
) -> EventMetrics:
    """Metrics of both shoes. ``stop_time_s``: the located lock instant (or None)."""
    return EventMetrics(
        left=shoe_metrics(block, "left", stop_time_s=stop_time_s, window_s=window_s),
        right=shoe_metrics(block, "right", stop_time_s=stop_time_s, window_s=window_s),
        stop_time_s=stop_time_s,
    )
