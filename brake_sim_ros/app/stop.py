"""A stop request for a spin loop: SIGINT and SIGTERM set a flag the loop checks.

rclpy's own handlers shut the context down from the signal handler, wherever the program
is: inside a recorder's write, or between a loop's ``rclpy.ok()`` and its ``spin_once``,
which then fails on the dead context. With ``rclpy.init(...,
signal_handler_options=SignalHandlerOptions.NO)`` and a :class:`StopRequest`
(:func:`start_ros` does both), the loop ends between callbacks and shuts down itself. A
second signal interrupts at once.
"""

from __future__ import annotations

import signal

import rclpy
from rclpy.signals import SignalHandlerOptions


class StopRequest:
    """SIGINT/SIGTERM set :attr:`requested` (a second one raises KeyboardInterrupt)."""

    def __init__(self) -> None:
        self.requested = False
        self._previous = {
            sig: signal.signal(sig, self._handle) for sig in (signal.SIGINT, signal.SIGTERM)
        }

    def _handle(self, signum: int, _frame) -> None:
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True

    def restore(self) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)


def start_ros(args: list[str]) -> StopRequest:
    """``rclpy.init(args=args)`` without rclpy's signal handlers, and the
    :class:`StopRequest` that takes their place (restore it after shutting down)."""
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    return StopRequest()
