"""Calling a user's detector: whatever its code raises (an exception of any kind,
``SystemExit``, ``MemoryError``, a ``SyntaxError`` at import) becomes one
:class:`DetectorCodeError` naming the class and the method, with the exception's type and
message; the traceback is kept on the error for ``--debug``. Ctrl-C still interrupts.
"""

from __future__ import annotations

import contextlib
import traceback
from collections.abc import Iterator

from brake_sim_ros.errors import BrakeSimError

MESSAGE_LIMIT = 300  # characters of the user's exception message kept in the line


class DetectorCodeError(BrakeSimError, RuntimeError):
    """A user's detector raised: one line; ``traceback_text`` holds the traceback."""

    def __init__(self, message: str, traceback_text: str = "") -> None:
        super().__init__(message)
        self.traceback_text = traceback_text


def describe_code(owner: object) -> str:
    """``module.Class`` of a detector (an instance or a class), or the text given."""
    if isinstance(owner, str):
        return owner
    cls = owner if isinstance(owner, type) else type(owner)
    return f"{getattr(cls, '__module__', '?')}.{getattr(cls, '__qualname__', cls.__name__)}"


def _ours(owner: object) -> bool:
    """Whether ``owner`` is one of this package's detectors (not a user's code)."""
    if isinstance(owner, str):
        return False
    cls = owner if isinstance(owner, type) else type(owner)
    return str(getattr(cls, "__module__", "")).startswith("brake_sim_ros.")


def _shown(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    text = "".join(c if c.isprintable() else "?" for c in text)
    if len(text) > MESSAGE_LIMIT:
        text = text[: MESSAGE_LIMIT - 60] + " ... " + text[-40:]
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


@contextlib.contextmanager
def user_code(
    owner: object, method: str, *, passthrough: tuple[type[BaseException], ...] = ()
) -> Iterator[None]:
    """Run the block as a call of ``owner``'s ``method`` (a user's code).

    Args:
        owner: the detector, its class, or a text naming it (``module:Class``).
        method: the method (``__init__``, ``fit``, ``assess``, ``import``).
        passthrough: exception types the caller handles itself.

    Raises:
        DetectorCodeError: the block raised anything but KeyboardInterrupt, a
            :class:`DetectorCodeError` (already named) or one of ``passthrough``; a
            built-in detector's (this package's) errors go on unchanged.
    """
    try:
        yield
    except (KeyboardInterrupt, DetectorCodeError):
        raise
    except BaseException as exc:
        if (passthrough and isinstance(exc, passthrough)) or _ours(owner):
            raise  # the caller's to handle, or a built-in detector's own one-line error
        where = describe_code(owner)
        raise DetectorCodeError(
            f"detector {where}: {method} raised {_shown(exc)}", traceback.format_exc()
        ) from None
