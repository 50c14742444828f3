"""The parser of every command line: argparse, but a bad command line is one line on
stderr (exit 2), never the usage. ``brake-sim``'s commands (:mod:`brake_sim_ros.cli`) and
the studies' own command lines (``brake-sim bench ...``, :mod:`brake_sim_ros.studies`)
share it. Imports nothing beyond the standard library."""

from __future__ import annotations

import argparse
from typing import NoReturn

EXIT_ERROR = 2


class Parser(argparse.ArgumentParser):
    """argparse, but a bad command line is one line on stderr (exit 2), not the usage."""

    def error(self, message: str) -> NoReturn:
        text = " ".join(message.split())
        text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
        if len(text) > 500:
            text = text[:400] + " ... " + text[-60:]
        self.exit(EXIT_ERROR, f"{self.prog}: error: {text} (see {self.prog} --help)\n")
