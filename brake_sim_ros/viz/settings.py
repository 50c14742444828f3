"""How much of the stream a :class:`~.rerun_sink.RerunSink` sends, and its error."""

from __future__ import annotations

import math
from dataclasses import dataclass

from brake_sim_ros.errors import BrakeSimError


class RerunSinkError(BrakeSimError, ValueError):
    """A message the sink cannot log (inconsistent arrays, bad rate)."""


@dataclass(frozen=True)
class SinkSettings:
    """How much of the stream a :class:`~.rerun_sink.RerunSink` sends.

    Attributes:
        force_envelope_hz: None = every pivot-force sample (files); else buckets of
            ``1 / force_envelope_hz`` s of simulated time reduced to their min and max
            samples (live viewers cannot draw 25 kHz series).
        drawing_rate_hz: frames of the 2-D drawing per simulated second (at most the
            state rate: a frame is drawn at a BrakeState).
        batch_s: simulated seconds of samples per ``send_columns`` call.
    """

    force_envelope_hz: float | None = None
    drawing_rate_hz: float = 50.0
    batch_s: float = 0.5

    def __post_init__(self) -> None:
        for name in ("drawing_rate_hz", "batch_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise RerunSinkError(f"{name}={value!r}: allowed a finite value > 0")
        env = self.force_envelope_hz
        if env is not None and not (math.isfinite(env) and env > 0):
            raise RerunSinkError(f"force_envelope_hz={env!r}: allowed None or a value > 0")


FILE_SETTINGS = SinkSettings()
LIVE_SETTINGS = SinkSettings(force_envelope_hz=500.0, drawing_rate_hz=25.0, batch_s=0.1)
