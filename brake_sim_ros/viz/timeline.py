"""The ``sim_time`` timeline: message stamps in ns, rows logged at a time, the event log.

Every time here is simulated time since the start of the run, integer nanoseconds, taken
from the messages' stamps (never the wall clock).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import rerun as rr

from brake_sim_ros.viz import entities as E

NS_PER_S = 1_000_000_000


def stamp_ns(msg: Any) -> int:
    """The ``header.stamp`` of ``msg`` in ns."""
    stamp = msg.header.stamp
    return int(stamp.sec) * NS_PER_S + int(stamp.nanosec)


def set_sim_time(rec: rr.RecordingStream, ns: int) -> None:
    """Log what follows on ``rec`` at ``ns`` of simulated time."""
    rec.set_time(E.TIMELINE, duration=np.timedelta64(int(ns), "ns"))


def send_scalar_columns(
    rec: rr.RecordingStream, path: str, ns: np.ndarray, values: np.ndarray
) -> None:
    """One ``send_columns`` call: scalars ``values`` at times ``ns`` (int ns, same length)."""
    rec.send_columns(
        path,
        indexes=[
            rr.TimeColumn(E.TIMELINE, duration=np.asarray(ns, np.int64).astype("timedelta64[ns]"))
        ],
        columns=rr.Scalars.columns(scalars=values),
    )


def log_event(rec: rr.RecordingStream, ns: int, text: str, level: str = "INFO") -> None:
    """A line of the event log (``events``) at ``ns``; ``level`` as rr.TextLog takes it."""
    set_sim_time(rec, ns)
    rec.log(E.EVENTS, rr.TextLog(text, level=level))
