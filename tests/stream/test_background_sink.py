"""BackgroundSink: messages reach the wrapped sink in order, on another thread; a failure
reaches the producer; close hands everything over, closes the wrapped sink, never hangs."""

from __future__ import annotations

import threading

import pytest

from brake_sim_ros.stream import PIVOT_FORCES, STATE
from brake_sim_ros.stream.background import BackgroundSink


class ListSink:
    """Keeps what it is given and the thread that gave it; fails on request."""

    def __init__(self, fail_at: int | None = None, gate: threading.Event | None = None) -> None:
        self.got: list[tuple[str, object, int]] = []
        self.threads: set[str] = set()
        self.closed = 0
        self.fail_at = fail_at
        self.gate = gate

    def write(self, topic, msg, time_ns) -> None:
        if self.gate is not None:
            self.gate.wait(timeout=10.0)
        if self.fail_at is not None and len(self.got) == self.fail_at:
            raise OSError("disk full")
        self.threads.add(threading.current_thread().name)
        self.got.append((topic.name, msg, time_ns))

    def close(self) -> None:
        self.closed += 1


def test_messages_arrive_in_order_on_another_thread():
    inner = ListSink()
    sink = BackgroundSink(inner, max_pending=3)  # the producer waits for room, often
    sent = [(PIVOT_FORCES if i % 3 else STATE, object(), i * 1000) for i in range(500)]
    for topic, msg, ns in sent:
        sink.write(topic, msg, ns)
    sink.close()
    assert inner.got == [(t.name, m, ns) for t, m, ns in sent]
    assert threading.current_thread().name not in inner.threads
    assert inner.closed == 1
    sink.close()  # a second close does nothing
    assert inner.closed == 1


def test_the_producer_does_not_wait_for_a_slow_sink():
    gate = threading.Event()
    inner = ListSink(gate=gate)
    sink = BackgroundSink(inner)
    for i in range(100):  # returns although the sink has taken none of them
        sink.write(STATE, i, i)
    assert inner.got == []
    gate.set()
    sink.close()
    assert [m for _, m, _ in inner.got] == list(range(100))


def test_a_failure_is_raised_by_the_next_write_and_not_again_by_close():
    inner = ListSink(fail_at=5)
    sink = BackgroundSink(inner, max_pending=2)
    with pytest.raises(OSError, match="disk full"):
        for i in range(1000):  # fails within the queue's length after the sixth
            sink.write(STATE, i, i)
    assert len(inner.got) == 5
    with pytest.raises(OSError, match="disk full"):  # and on every write after it
        sink.write(STATE, -1, -1)
    sink.close()  # the owner drops and closes it: no second report, and no hang
    assert inner.closed == 1


def test_a_failure_while_closing_is_raised_by_close():
    gate = threading.Event()
    inner = ListSink(fail_at=5, gate=gate)
    sink = BackgroundSink(inner)
    for i in range(10):  # queued: nothing has failed yet when the producer finishes
        sink.write(STATE, i, i)
    gate.set()
    with pytest.raises(OSError, match="disk full"):
        sink.close()
    assert inner.closed == 1  # closed all the same


def test_write_after_close_is_refused():
    sink = BackgroundSink(ListSink())
    sink.close()
    with pytest.raises(RuntimeError, match="after close"):
        sink.write(STATE, 1, 1)


def test_a_bad_queue_length_is_refused():
    with pytest.raises(ValueError, match="max_pending"):
        BackgroundSink(ListSink(), max_pending=0)
