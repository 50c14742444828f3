"""Contact: impact markers on the pivot-force plot, and impacts, separations and regime
changes in the event log.

Impacts come from ContactEvent messages (ground truth at the full sample rate): each
onset is an event and a marker at its exact sample, valued |F_pivot| of that sample (N;
when the chunk holding it was received); each separation is an event and a marker at the
episode's peak |F_pivot| (``pivot_force/impacts/<side>/peak``). A stream without
ContactEvents (an older recording) falls back to the state rate: a contact onset
(:mod:`brake_sim_ros.analysis.onsets`) between two BrakeStates' contact flags gives an
event and a marker at the largest |F_pivot| of that shoe since the previous state (raise
``state_rate_hz`` to resolve every bounce). Regime changes are events.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import rerun as rr

from brake_sim_ros.analysis.onsets import contact_changes
from brake_sim_ros.model.layout import REGIME_NAMES
from brake_sim_ros.viz import entities as E
from brake_sim_ros.viz.pivot_samples import RecentPivotForces
from brake_sim_ros.viz.timeline import NS_PER_S, log_event, set_sim_time, stamp_ns

_KIND_ONSET = 0  # ContactEvent.KIND_ONSET; SHOE_LEFT = 0, SHOE_RIGHT = 1 index E.SIDES


class ContactMarkers:
    """Draws impacts and regime changes.

    Args:
        rec: where to log.
        recent: the pivot-force samples the markers take their values from.

    Attributes:
        impacts: contact onsets seen per side.
    """

    def __init__(self, rec: rr.RecordingStream, recent: RecentPivotForces) -> None:
        self._rec = rec
        self._recent = recent
        self.impacts = {side: 0 for side in E.SIDES}
        # True once a ContactEvent arrived: impacts come from them, not from the states
        self._contact_events_seen = False
        self._last_state: Any = None
        self._last_state_index: int | None = None

    def restart(self) -> None:
        """The simulation restarted: the next state has no previous sample to look back to."""
        self._last_state_index = None

    def on_contact_event(self, msg: Any, *, rate_hz: float | None) -> bool:
        """Draw a ContactEvent; False when its shoe is unknown (then only a warning).

        ``rate_hz``: the pivot-force sample rate, None before the first chunk (the sample
        times are then scaled from the event's stamp).
        """
        self._contact_events_seen = True
        ns = stamp_ns(msg)
        index = int(msg.sample_index)
        shoe = int(msg.shoe)
        side = E.SIDES[shoe] if 0 <= shoe < len(E.SIDES) else None
        if side is None:
            log_event(self._rec, ns, f"contact event of an unknown shoe {shoe} ignored", "WARN")
            return False
        if int(msg.kind) == _KIND_ONSET:
            self.impacts[side] += 1
            pivot = self._recent.at(index)
            if pivot is not None:
                set_sim_time(self._rec, ns)
                self._rec.log(f"{E.IMPACTS}/{side}", rr.Scalars(float(np.hypot(*pivot[side]))))
            log_event(self._rec, ns, f"impact: {side} shoe touches the drum (sample {index})")
        else:
            peak = float(msg.peak_pivot_force_n)
            peak_index = int(msg.peak_sample_index)
            peak_ns = _sample_ns(peak_index, msg, rate_hz)
            set_sim_time(self._rec, peak_ns)
            self._rec.log(E.impact_peak_path(side), rr.Scalars(peak))
            log_event(
                self._rec,
                ns,
                f"separation: {side} shoe leaves the drum after"
                f" {1e3 * float(msg.duration_s):.3f} ms; peak |F_pivot| {peak:.0f} N at"
                f" t = {peak_ns / NS_PER_S:.6f} s",
            )
        return True

    def on_state(self, msg: Any, ns: int, *, rate_hz: float | None) -> None:
        """A BrakeState stamped ``ns``: a regime change, and without ContactEvents the
        contact onsets since the previous state (``rate_hz``: pivot-force sample rate)."""
        index = int(msg.sample_index)
        prev = self._last_state
        regime = int(msg.regime)
        if prev is None or int(prev.regime) != regime:
            before = "start" if prev is None else _regime_name(int(prev.regime))
            log_event(self._rec, ns, f"regime: {before} -> {_regime_name(regime)}")
        if not self._contact_events_seen:  # else impacts come from the ContactEvents
            self._state_onsets(msg, ns, index, prev, rate_hz)
        self._last_state, self._last_state_index = msg, index

    def _state_onsets(
        self, msg: Any, ns: int, index: int, prev: Any, rate_hz: float | None
    ) -> None:
        for side in E.SIDES:
            # the BrakeState flags are onsets.in_contact of the indentation; an onset is
            # detected between consecutive states by the same rule as in the samples
            now_in = np.array([bool(getattr(msg, f"{side}_in_contact"))])
            was_in = prev is not None and bool(getattr(prev, f"{side}_in_contact"))
            if contact_changes(now_in, before=was_in).onsets.size:
                self.impacts[side] += 1
                peak = self._recent.peak_since(side, self._last_state_index, index)
                text = f"impact: {side} shoe touches the drum (contact onset seen at this state"
                if peak is not None:
                    peak_ns = round(peak[0] * NS_PER_S / (rate_hz or 1.0))
                    text += f"; largest |F_pivot| since the previous state {peak[1]:.0f} N"
                    set_sim_time(self._rec, peak_ns)
                    self._rec.log(f"{E.IMPACTS}/{side}", rr.Scalars(peak[1]))
                log_event(self._rec, ns, text + ")")


def _sample_ns(index: int, msg: Any, rate_hz: float | None) -> int:
    """Time (ns) of sample ``index``, as the pivot-force series times it; without a
    chunk seen yet (``rate_hz`` None), scaled from the stamp of ``msg`` (a ContactEvent)."""
    if rate_hz is not None:
        return round(index * (NS_PER_S / rate_hz))
    event_index = int(msg.sample_index)
    return stamp_ns(msg) if event_index == 0 else stamp_ns(msg) * index // event_index


def _regime_name(regime: int) -> str:
    return REGIME_NAMES[regime] if 0 <= regime < len(REGIME_NAMES) else f"unknown ({regime})"
