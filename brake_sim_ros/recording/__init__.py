"""MCAP recording of the simulator's stream (rosbag2 compatible), checked reading, recovery.

Modules: :mod:`.schemas` (complete ros2msg definitions), :mod:`.metadata` (the records a
file carries), :mod:`.writer` (:class:`McapRecorder`), :mod:`.record` (offline runs and
node recordings), :mod:`.mcap_format` (MCAP framing and record checks for hostile input),
:mod:`.cdr` (payloads checked against the installed definitions), :mod:`.reader` (the
strict reader of ``view`` and ``replay``), :mod:`.recover` (keep the intact chunks of a
cut-short or damaged file), :mod:`.output` (outputs checked and written whole),
:mod:`.benchmark`.
"""

from brake_sim_ros.recording.writer import McapRecorder, RecordingError, RecordingOptions

__all__ = ["McapRecorder", "RecordingError", "RecordingOptions"]
