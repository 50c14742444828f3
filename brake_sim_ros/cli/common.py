"""What every command of ``brake-sim`` shares: exit codes, the parser class, a command's
entry in the parser, the progress report and the one-line form of an error.

Imports nothing beyond the standard library (and :mod:`brake_sim_ros.command_line`,
which neither does): ``brake-sim --help`` and every command's
start pay only for what the command itself imports.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

# the parser and its exit code, for the commands (defined below the studies, which share them)
from brake_sim_ros.command_line import EXIT_ERROR, Parser  # noqa: F401

EXIT_BROKEN_PIPE = 141  # 128 + SIGPIPE, what a shell reports for a pipe its reader closed
EXIT_INTERRUPTED = 130  # 128 + SIGINT

DEBUG_HELP = "on a user detector's error, show its traceback too"


@dataclass(frozen=True)
class Command:
    """One ``brake-sim`` command as the top-level parser lists it.

    Attributes:
        name: the command's word.
        help: its line in ``brake-sim --help``.
        options: adds its description, options and ``func`` to its sub-parser; None for a
            command that parses its own command line (``main`` hands it the arguments).
            Called only for the command being run (or for every one, by ``build_parser``):
            the options of some name what heavy modules hold (presets, detectors).
    """

    name: str
    help: str
    options: Callable[[argparse.ArgumentParser], None] | None = None


def progress(label: str) -> Callable[[float], None]:
    """Progress callback printing a fraction to stderr, at most a few times a second."""
    last = [0.0]

    def report(fraction: float) -> None:
        now = time.monotonic()
        if now - last[0] > 0.5 or fraction >= 1.0:
            last[0] = now
            end = "\n" if fraction >= 1.0 else "\r"
            print(f"{label}: {100 * fraction:5.1f} %", end=end, file=sys.stderr, flush=True)

    return report


def one_line(exc: BaseException) -> str:
    """An exception's message on one line (a detector's or a dataset's may span several)."""
    return " ".join(str(exc).split())


def debug_traceback(exc: BaseException, debug: bool) -> None:
    """With ``--debug``, the traceback of a user detector's error before its one line."""
    text = getattr(exc, "traceback_text", "")
    if debug and text:
        print(text.rstrip(), file=sys.stderr)
