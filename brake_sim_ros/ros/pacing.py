"""Pacing of the simulation against the wall clock. Pure logic: no ROS, no clock reads.

The node asks, at every tick, how many steps are due. A step here is one output sample,
the stepper's unit (it takes whole physics substeps inside it). The answer comes from an
anchor ``(wall_s, step)`` set when pacing (re)starts:

    target_step(now) = anchor_step + floor((now - anchor_wall_s) * real_time_factor / period)

with ``period`` the sample period.

The target is computed from the wall time elapsed since the anchor, never by adding up
per-tick increments, so timer jitter and late ticks do not accumulate into drift: a late
tick simply finds more steps due and catches up.

Modes:
    real time (``real_time_factor > 0``): simulated time tracks wall time x factor. Steps
        are taken in whole chunks, as soon as a chunk's last sample is due.
    as fast as possible (``real_time_factor == 0``): no target; the caller steps for a
        bounded wall-time budget per tick so that it stays responsive.
    paused: nothing is due; the caller may still step on request (the step service).

Any change of mode or factor re-anchors at the current ``(wall, step)``, so the
simulation continues from where it is, without a jump.

Catch-up is bounded: at most ``max_chunks`` chunks are taken per tick. A backlog larger
than ``max_lag_s`` of wall time (the process was starved, e.g. suspended) is not worked
off at full speed forever: the excess is dropped by re-anchoring (reported as a *slip*),
so that the published stream does not burst for seconds after a stall.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass


class PacingMode(enum.Enum):
    REAL_TIME = "real_time"
    AS_FAST_AS_POSSIBLE = "as_fast_as_possible"
    PAUSED = "paused"


@dataclass(frozen=True)
class TickPlan:
    """What one tick should do.

    Attributes:
        steps: samples to take now: a whole number of chunks, or the remainder up
            to ``end_step``. In as-fast-as-possible mode, the most the tick may take (the
            caller also bounds the tick by wall time).
        behind_steps: steps that are due but left for later ticks (catch-up).
        slipped_steps: steps dropped from the target because the backlog exceeded
            ``max_lag_s`` (the anchor moved forward by that much simulated time).
    """

    steps: int
    behind_steps: int = 0
    slipped_steps: int = 0


class Pacer:
    """Decides how many steps are due at a wall-clock instant.

    Args:
        sample_period_s: time between samples (steps), s.
        real_time_factor: simulated seconds per wall second; 0 = as fast as possible.
        paused: start paused.
        max_lag_s: largest backlog, in wall seconds, that is caught up; beyond it the
            excess is dropped (a slip).

    All ``now_s`` arguments are readings of one monotonic clock, s.
    """

    def __init__(
        self,
        sample_period_s: float,
        *,
        real_time_factor: float = 1.0,
        paused: bool = False,
        max_lag_s: float = 0.5,
    ) -> None:
        if not (math.isfinite(sample_period_s) and sample_period_s > 0):
            raise ValueError(f"sample_period_s={sample_period_s!r}: allowed a finite period > 0 s")
        _check_factor(real_time_factor)
        if not max_lag_s > 0:
            raise ValueError(f"max_lag_s={max_lag_s!r}: allowed > 0 s")
        self.sample_period_s = float(sample_period_s)
        self._factor = float(real_time_factor)
        self._paused = bool(paused)
        self.max_lag_s = float(max_lag_s)
        self._anchor_wall_s = 0.0
        self._anchor_step = 0

    # -- state ----------------------------------------------------------------------------
    @property
    def real_time_factor(self) -> float:
        return self._factor

    @property
    def paused(self) -> bool:
        return self._paused

    @property
    def mode(self) -> PacingMode:
        if self._paused:
            return PacingMode.PAUSED
        if self._factor == 0.0:
            return PacingMode.AS_FAST_AS_POSSIBLE
        return PacingMode.REAL_TIME

    def restart(self, now_s: float, step: int) -> None:
        """Anchor pacing at ``(now_s, step)``: the simulation is on time there."""
        self._anchor_wall_s = float(now_s)
        self._anchor_step = int(step)

    def set_real_time_factor(self, factor: float, now_s: float, step: int) -> None:
        _check_factor(factor)
        self._factor = float(factor)
        self.restart(now_s, step)

    def set_paused(self, paused: bool, now_s: float, step: int) -> None:
        self._paused = bool(paused)
        self.restart(now_s, step)

    # -- queries --------------------------------------------------------------------------
    def target_step(self, now_s: float) -> int:
        """Step index the simulation should have reached at ``now_s`` (real-time mode)."""
        if self.mode is not PacingMode.REAL_TIME:
            raise RuntimeError(f"no target step in {self.mode.value} mode")
        elapsed = max(0.0, now_s - self._anchor_wall_s)
        # the tiny epsilon keeps an exact multiple of the period from flooring one step short
        return self._anchor_step + math.floor(elapsed * self._factor / self.sample_period_s + 1e-9)

    def deadline_s(self, step: int) -> float:
        """Wall instant at which the simulation should reach ``step`` (real-time mode)."""
        if self.mode is not PacingMode.REAL_TIME:
            raise RuntimeError(f"no deadline in {self.mode.value} mode")
        return (
            self._anchor_wall_s + (step - self._anchor_step) * self.sample_period_s / self._factor
        )

    def chunk_wall_period_s(self, chunk_steps: int) -> float:
        """Wall time one chunk spans (real-time mode)."""
        return chunk_steps * self.sample_period_s / self._factor

    def plan(
        self,
        now_s: float,
        step: int,
        chunk_steps: int,
        max_chunks: int,
        end_step: int | None = None,
    ) -> TickPlan:
        """Steps to take at ``now_s`` when the simulation is at ``step``.

        Args:
            now_s: current wall time, s.
            step: the simulation's current step index.
            chunk_steps: steps per published chunk (>= 1).
            max_chunks: most chunks to take in this tick (>= 1).
            end_step: the run ends here (no steps beyond it); None for no end.
        """
        if chunk_steps < 1 or max_chunks < 1:
            raise ValueError(f"chunk_steps={chunk_steps}, max_chunks={max_chunks}: allowed >= 1")
        remaining = None if end_step is None else max(0, end_step - step)
        mode = self.mode
        if mode is PacingMode.PAUSED or remaining == 0:
            return TickPlan(0)
        if mode is PacingMode.AS_FAST_AS_POSSIBLE:
            budget = max_chunks * chunk_steps
            return TickPlan(budget if remaining is None else min(budget, remaining))
        due = self.target_step(now_s) - step
        if due <= 0:
            return TickPlan(0)
        if remaining is not None and due >= remaining and remaining < chunk_steps:
            return TickPlan(remaining)  # the final, partial chunk
        chunks = due // chunk_steps
        slipped = 0
        lag_s = due * self.sample_period_s / self._factor
        if chunks > max_chunks and lag_s > self.max_lag_s:
            # starved for longer than we are willing to catch up: drop the excess
            slipped = due - max_chunks * chunk_steps
            self._anchor_step -= slipped
            due -= slipped
            chunks = max_chunks
        take = min(chunks, max_chunks) * chunk_steps
        if remaining is not None:
            take = min(take, remaining)
        return TickPlan(take, behind_steps=max(0, due - take), slipped_steps=slipped)


def _check_factor(factor: float) -> None:
    if not (isinstance(factor, int | float) and math.isfinite(factor) and factor >= 0.0):
        raise ValueError(
            f"real_time_factor={factor!r}: allowed a finite factor >= 0 (0 = as fast as possible)"
        )
