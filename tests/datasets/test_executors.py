"""``sweep --scheduler`` at an address where no Dask scheduler answers: one line within the
connect timeout, never a hang nor a traceback (a real listening socket and a real Dask
client; the timeout shortened)."""

from __future__ import annotations

import socket
import threading
import time

import pytest

from brake_sim_ros.datasets import executors


def _server(reply: bytes) -> tuple[socket.socket, str]:
    """A TCP server on localhost that accepts and sends ``reply`` (nothing: it stays
    silent, as an HTTP server waiting for a request), in a thread."""
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen()
    held: list[socket.socket] = []

    def serve() -> None:
        while True:
            try:
                conn, _ = listener.accept()
            except OSError:
                return
            held.append(conn)
            if reply:
                conn.sendall(reply)

    threading.Thread(target=serve, daemon=True).start()
    return listener, f"tcp://127.0.0.1:{listener.getsockname()[1]}"


@pytest.mark.parametrize(
    "reply", [b"", b"\xff" * 64, b"HTTP/1.0 200 OK\r\n\r\n" * 4], ids=["silent", "ff", "http"]
)
def test_a_server_that_is_no_scheduler_is_one_line_in_time(monkeypatch, reply):
    pytest.importorskip("distributed")
    monkeypatch.setattr(executors, "CONNECT_TIMEOUT_S", 2.0)
    listener, address = _server(reply)
    start = time.monotonic()
    try:
        with (
            pytest.raises(executors.ExecutorError) as info,
            executors.open_executor(1, address, lambda: None),
        ):
            pass
    finally:
        listener.close()
    assert time.monotonic() - start < 2.0 + 5.0 + 3.0
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"--scheduler {address}: ")
