"""A message sink on a thread of its own: the producer hands each message over and goes on.

A real-time node pays for a sink's work inside the tick that publishes: a Rerun
recording's drawing of the brake costs several milliseconds (eight log calls) against a
chunk period of 10 ms, so the ticks that carried one ran late. :class:`BackgroundSink`
moves that work to a worker thread. The messages reach the wrapped sink in the order they
were written; the producer never waits unless ``max_pending`` messages are queued (then
it waits for room: memory stays bounded). A failure of the wrapped sink is raised by the
next ``write`` (and every one after it), so its owner drops it as it would drop the sink
itself; ``close`` raises it only if no ``write`` did, hands over everything still queued,
and closes the wrapped sink.

Only ``write`` and ``close`` are passed on: a sink with other hooks (a recorder's
``parameter_change``) stays in its producer's thread. The messages must not change after
``write``; the node builds fresh ones for every chunk.
"""

from __future__ import annotations

import queue
import threading
from typing import Any

from brake_sim_ros.stream.samples import MessageSink
from brake_sim_ros.stream.topics import Topic

_END = object()


class BackgroundSink:
    """``inner`` (a :class:`~brake_sim_ros.stream.samples.MessageSink`) fed from a worker
    thread; at most ``max_pending`` messages wait for it."""

    def __init__(self, inner: MessageSink, *, max_pending: int = 10_000) -> None:
        if max_pending < 1:
            raise ValueError(f"max_pending = {max_pending!r} is invalid: allowed >= 1")
        self.inner = inner
        self._queue: queue.Queue[Any] = queue.Queue(maxsize=max_pending)
        self._error: BaseException | None = None
        self._reported = False
        self._closed = False
        self._worker = threading.Thread(target=self._drain, name="background sink", daemon=True)
        self._worker.start()

    def __repr__(self) -> str:
        return repr(self.inner)

    def _drain(self) -> None:
        while True:
            item = self._queue.get()
            if item is _END:
                return
            if self._error is None:  # after a failure: taken, so no writer waits
                try:
                    self.inner.write(*item)
                except BaseException as exc:  # raised to the producer by its next call
                    self._error = exc

    def _raise_failure(self) -> None:
        if self._error is not None:
            self._reported = True
            raise self._error

    def write(self, topic: Topic, msg: Any, time_ns: int) -> None:
        """Queue one message; raises the wrapped sink's failure once it has failed."""
        if self._closed:
            raise RuntimeError(f"{self!r}: write() after close()")
        self._raise_failure()
        self._queue.put((topic, msg, time_ns))

    def close(self) -> None:
        """Hand over what is queued, stop the worker and close the wrapped sink; raises the
        wrapped sink's failure if no call raised it yet (it is closed all the same)."""
        if self._closed:
            return
        self._closed = True
        self._queue.put(_END)
        self._worker.join()
        try:
            if not self._reported:  # the owner that dropped the sink for it closes it
                self._raise_failure()
        finally:
            self.inner.close()
