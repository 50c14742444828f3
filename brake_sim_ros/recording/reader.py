"""The one reader of this project's MCAP recordings: every byte checked before it is used.

``view``, ``replay`` and ``recover`` read recordings through this module only. A recording
is hostile until checked, so nothing here trusts a length, an offset, a name or a CRC the
file gives without comparing it with what the file can hold:

* The path must be a regular file (a FIFO or a device is refused before it is opened for
  reading, so nothing hangs) no larger than :attr:`Limits.max_file_bytes`; bytes are read
  with ``pread`` at checked offsets, never through a memory map, so a file truncated
  while it is read gives an error, not a crash.
* Records are framed by hand: every record length must fit in what is left of the file
  (and under :attr:`Limits.max_record_bytes`) before it is read, and every field must fit
  in its record; a record must be used up exactly.
* A chunk must carry a CRC; it is decompressed to at most the size its header declares
  (zstd or none, as the recorder writes) and its CRC compared before one of its records
  is parsed.
* Schemas must be ``ros2msg`` definitions of a type in the simulator's topic table
  (:data:`brake_sim_ros.stream.topics.TYPES`); the schema text of the file is never used
  to decode and never names a module to import. Channels must be ``cdr`` on a valid ROS
  topic name; a ``topic_type_hash`` that disagrees with the installed definition is
  refused.
* Every message is checked against its type (:func:`.cdr.check`) before anything is
  published or shown.

:func:`open_recording` is the strict reader of ``view`` and ``replay``: the whole file is
checked first (header, every chunk, every message, the summary against what the data
section holds, the footer and its CRC) and any fault refuses the whole file with one
:class:`RecordingReadError` line naming the file, the offset, the chunk or message and
what is allowed, and pointing to ``brake-sim recover``. Nothing of a damaged file is
published or shown. The check itself is :mod:`.file_check`, a channel's QoS
:mod:`.channel_qos`. The format layer underneath (:mod:`.mcap_format`: framing, record
parsers, chunk checks) is shared with :mod:`.recover`, which keeps what is intact instead
of refusing.
"""

from __future__ import annotations

import heapq
import os
from collections.abc import Collection, Iterator
from dataclasses import dataclass

from brake_sim_ros.recording.file_check import CheckedFile, ChunkInfo
from brake_sim_ros.recording.mcap_format import (
    DEFAULT_LIMITS,
    FRAME_BYTES,
    Limits,
    MalformedError,
    Op,
    RecordingReadError,
    Source,
    parse_chunk,
    parse_message,
    read_frame,
    recover_hint,
    verify_chunk,
)
from brake_sim_ros.stream import Topic


@dataclass(frozen=True)
class RecordedMessage:
    """One message of a checked recording; ``index`` counts messages in file order."""

    index: int
    topic: Topic
    channel_id: int
    log_time_ns: int
    publish_time_ns: int
    data: bytes


class Recording(CheckedFile):
    """A recording checked from end to end by :func:`open_recording`.

    Attributes:
        path, size_bytes, profile, library: the file and its header.
        metadata: metadata records in file order, ``(name, {key: value})``.
        channels: by channel id (only channels of recorded types exist).
        chunks: every chunk, in file order.
        message_count, start_ns, end_ns: over all messages (times None without any).
    """

    # -- reading messages -----------------------------------------------------------------
    def messages(
        self,
        *,
        topics: Collection[str] | None = None,
        start_ns: int | None = None,
        end_ns: int | None = None,
    ) -> Iterator[RecordedMessage]:
        """Messages in log-time order (file order among equal times), optionally only of
        ``topics`` and with ``start_ns <= log time < end_ns``.

        Each chunk is read again and must still have the CRC it was checked with.

        Raises:
            RecordingReadError: the file changed since it was checked.
        """
        wanted = None if topics is None else set(topics)
        chunks = sorted(
            (
                c
                for c in self.chunks
                if (start_ns is None or c.end_ns >= start_ns)
                and (end_ns is None or c.start_ns < end_ns)
            ),
            key=lambda c: (c.start_ns, c.number),
        )
        heap: list[tuple[int, int, RecordedMessage]] = []
        next_chunk = 0
        while heap or next_chunk < len(chunks):
            while next_chunk < len(chunks) and (
                not heap or chunks[next_chunk].start_ns <= heap[0][0]
            ):
                for msg in self._chunk_messages(chunks[next_chunk]):
                    if wanted is not None and msg.topic.name not in wanted:
                        continue
                    if start_ns is not None and msg.log_time_ns < start_ns:
                        continue
                    if end_ns is not None and msg.log_time_ns >= end_ns:
                        continue
                    heapq.heappush(heap, (msg.log_time_ns, msg.index, msg))
                next_chunk += 1
            if heap:
                yield heapq.heappop(heap)[2]

    def _chunk_messages(self, chunk: ChunkInfo) -> list[RecordedMessage]:
        try:
            opcode, length = read_frame(
                self._src, chunk.offset, self.size_bytes, self._limits.max_record_bytes
            )
            header = parse_chunk(self._src.read(chunk.offset + FRAME_BYTES, length))
            if opcode != Op.CHUNK or header.crc != chunk.crc:
                raise MalformedError("it is not the chunk that was checked")
            records = verify_chunk(header, self._limits)
            out = []
            for _offset, op, body in records:
                if op != Op.MESSAGE:
                    continue
                message = parse_message(body)
                topic = self._catalog.check_message(message, header.start_ns, header.end_ns)
                out.append(
                    RecordedMessage(
                        chunk.first_index + len(out),
                        topic,
                        message.channel_id,
                        message.log_time,
                        message.publish_time,
                        message.data,
                    )
                )
        except MalformedError as exc:
            raise RecordingReadError(
                f"{self.name}: chunk {chunk.number} at offset {chunk.offset} changed since the"
                f" file was checked ({exc}); nothing more is read"
            ) from None
        if len(out) != chunk.message_count:
            raise RecordingReadError(
                f"{self.name}: chunk {chunk.number} at offset {chunk.offset} changed since the"
                " file was checked; nothing more is read"
            )
        return out

    def metadata_record(self, name: str) -> dict[str, str] | None:
        """The last metadata record named ``name`` (None if there is none)."""
        found = None
        for record_name, values in self.metadata:
            if record_name == name:
                found = values
        return found

    def close(self) -> None:
        self._src.close()

    def __enter__(self) -> Recording:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def open_recording(path: str | os.PathLike[str], *, limits: Limits = DEFAULT_LIMITS) -> Recording:
    """Check a whole recording and return it, ready to read (close it after use).

    Raises:
        RecordingReadError: anything the module doc lists; one line, nothing of the file
            used.
    """
    src = Source(path, limits)
    recording = Recording(src, limits)
    try:
        recording._check()
    except MalformedError as exc:  # a read past the end the checks above did not frame
        src.close()
        raise RecordingReadError(f"{src.name}: {exc}; {recover_hint(src.name)}") from None
    except BaseException:
        src.close()
        raise
    return recording


__all__ = [
    "Limits",
    "RecordedMessage",
    "Recording",
    "RecordingReadError",
    "open_recording",
]
