"""Contact events (impact ground truth) from consecutive sample blocks, at the full rate.

A *contact episode* of a shoe is a maximal run of consecutive samples in contact, as
:mod:`.onsets` defines it (indentation ``<side>_indentation_m`` > 0). Its *onset* is the
first sample in contact, its *separation* the first sample out of contact again; these
are the samples :mod:`brake_sim_ros.analysis.impacts` reports (the sample after each
interpolated zero crossing), found by the same function.

:class:`ContactEventDetector` is fed the blocks of a run in order and returns each event
as soon as it is known: an onset in the block of its sample, a separation in the block of
its sample together with the episode's peak pivot force (largest ``|F_pivot|``, N, over
the episode's samples, onset included, separation excluded), the sample of that peak and
the episode's duration. It carries the open episodes between blocks, so the events do not
depend on how the run is cut into blocks. A contact present at the very first sample of a
run counts as an onset there (``impacts`` sees no crossing in that case); an episode still
open at the end of the run has no separation. Pure numpy: no ROS.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from brake_sim_ros.analysis.onsets import contact_changes, in_contact
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.model.run_setup import SampleBlock

SHOE_LEFT = 0
SHOE_RIGHT = 1
SHOES = SIDES  # position = SHOE_* value

KIND_ONSET = 0
KIND_SEPARATION = 1


@dataclass(frozen=True)
class ContactEvent:
    """One onset or separation of one shoe's contact with the drum.

    Attributes:
        sample_index: running index of the event sample (0-based count since the reset).
        time_s: simulated time of that sample, s (``sample_index * dt``).
        shoe: ``SHOE_LEFT`` or ``SHOE_RIGHT``.
        kind: ``KIND_ONSET`` or ``KIND_SEPARATION``.
        peak_pivot_force_n: separation only (0 for an onset): largest ``|F_pivot|`` of the
            shoe over the episode, N (magnitude, frame-independent).
        peak_sample_index: separation only (0 for an onset): sample of that peak (the first
            one on a tie).
        duration_s: separation only (0 for an onset): separation minus onset time, s.
    """

    sample_index: int
    time_s: float
    shoe: int
    kind: int
    peak_pivot_force_n: float = 0.0
    peak_sample_index: int = 0
    duration_s: float = 0.0

    @property
    def side(self) -> str:
        """``"left"`` or ``"right"``."""
        return SHOES[self.shoe]


@dataclass
class _Episode:
    """An open contact episode: onset sample and the running peak."""

    onset_index: int
    peak_n: float
    peak_index: int


class ContactEventDetector:
    """Onsets and separations of both shoes from the blocks of one run, fed in order.

    Call :meth:`reset` when the simulation restarts (new run, scenario switch): the
    detector refuses a block that does not continue the previous one.
    """

    def __init__(self) -> None:
        self._next_index: int | None = None
        self._open: list[_Episode | None] = [None, None]

    def reset(self) -> None:
        """Forget the run: no open episode, the next block may start anywhere."""
        self._next_index = None
        self._open = [None, None]

    def feed(self, block: SampleBlock) -> list[ContactEvent]:
        """The events whose sample lies in ``block``, ordered by sample, left before right.

        Args:
            block: the next samples of the run; needs the columns ``<side>_indentation_m``
                and ``<side>_pivot_fx_n``, ``<side>_pivot_fy_n`` of both shoes.

        Raises:
            ValueError: ``block`` does not start where the previous one ended (call
                :meth:`reset` first when the simulation restarted).
        """
        first = int(block.first_index)
        if self._next_index is not None and first != self._next_index:
            raise ValueError(
                f"block starts at sample {first}, the previous one ended before"
                f" {self._next_index}; reset() the detector when the run restarts"
            )
        self._next_index = first + len(block)
        events: list[ContactEvent] = []
        for shoe, side in enumerate(SHOES):
            events += self._feed_shoe(block, shoe, side)
        events.sort(key=lambda e: (e.sample_index, e.shoe))
        return events

    def _feed_shoe(self, block: SampleBlock, shoe: int, side: str) -> list[ContactEvent]:
        n = len(block)
        if n == 0:
            return []
        dt = block.sample_period_s
        first = int(block.first_index)
        contact = in_contact(block[f"{side}_indentation_m"])
        magnitude = block.pivot_force_magnitude(side)
        episode = self._open[shoe]
        changes = contact_changes(contact, before=episode is not None).positions
        events: list[ContactEvent] = []
        # segments [start, end) of constant contact flag; each change opens one with an event
        change_set = set(changes.tolist())
        starts = sorted({0, *change_set})
        for start, end in zip(starts, [*starts[1:], n], strict=True):
            if start in change_set:
                index = first + start
                if contact[start]:
                    episode = _Episode(index, -np.inf, index)
                    events.append(ContactEvent(index, index * dt, shoe, KIND_ONSET))
                else:
                    assert episode is not None
                    events.append(
                        ContactEvent(
                            index,
                            index * dt,
                            shoe,
                            KIND_SEPARATION,
                            peak_pivot_force_n=float(episode.peak_n),
                            peak_sample_index=episode.peak_index,
                            duration_s=(index - episode.onset_index) * dt,
                        )
                    )
                    episode = None
            if contact[start]:
                assert episode is not None
                k = int(np.argmax(magnitude[start:end]))
                if magnitude[start + k] > episode.peak_n:  # strict: the first peak wins a tie
                    episode.peak_n = float(magnitude[start + k])
                    episode.peak_index = first + start + k
        self._open[shoe] = episode
        return events
