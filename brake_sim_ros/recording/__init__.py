"""MCAP recording of the simulator's stream (rosbag2 compatible), and recovery after a crash.

Modules: :mod:`.schemas` (complete ros2msg definitions), :mod:`.metadata` (the records a
file carries), :mod:`.writer` (:class:`McapRecorder`), :mod:`.record` (offline runs and
node recordings), :mod:`.recover` (salvage a truncated file), :mod:`.benchmark`.
"""

from brake_sim_ros.recording.writer import McapRecorder, RecordingError, RecordingOptions

__all__ = ["McapRecorder", "RecordingError", "RecordingOptions"]
