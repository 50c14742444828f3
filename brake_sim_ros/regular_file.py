"""One file read as hostile input: a regular file, at most a stated size, never waited on.

The one bounded read behind every checked file of the package (scenario and campaign
files, a sweep's lock, manifest and runs, saved detectors). It says why it refused as a
:class:`FileRefusedError` with a reason, not a message: each caller words the refusal for its
own reader (its error type, the file's name, what is allowed).
"""

from __future__ import annotations

import os
import stat
from collections.abc import Callable

# why read_regular_file refused (FileRefusedError.reason)
MISSING = "missing"  # no such file
NOT_OPENED = "not opened"  # the open failed (permission, a link refused, a loop, ...)
NOT_A_PATH = "not a path"  # a NUL byte in the path, or not a path at all
NOT_REGULAR = "not regular"  # a directory, FIFO, device or socket
TOO_LARGE = "too large"  # larger than the limit when opened
GREW = "grew"  # grew past the limit while it was read
NOT_READ = "not read"  # an error of the OS while it was read

# what a file that is not a regular one is, for a message
FILE_TYPES: tuple[tuple[Callable[[int], bool], str], ...] = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


class FileRefusedError(Exception):
    """Why :func:`read_regular_file` gave no bytes.

    Attributes:
        reason: one of :data:`MISSING`, :data:`NOT_OPENED`, :data:`NOT_A_PATH`,
            :data:`NOT_REGULAR`, :data:`TOO_LARGE`, :data:`GREW`, :data:`NOT_READ`.
        detail: the OS's message (MISSING, NOT_OPENED, NOT_READ), or what the file is
            (NOT_REGULAR: "a directory", ... from :data:`FILE_TYPES`; "" for another kind).
        size: the file's size when opened, bytes (TOO_LARGE; else 0).
    """

    def __init__(self, reason: str, detail: str = "", size: int = 0) -> None:
        super().__init__(reason, detail)
        self.reason = reason
        self.detail = detail
        self.size = size


def _os_message(exc: OSError) -> str:
    return str(exc.strerror or exc)


def read_regular_file(
    path: str | os.PathLike[str], limit: int, *, follow_symlinks: bool = True
) -> bytes:
    """The bytes of the regular file ``path``, at most ``limit`` bytes, checked on the open
    file: it is opened without blocking (a FIFO is refused, never waited on), its type and
    size are checked before a byte is read, and the read stops past ``limit`` (the file may
    grow after it was opened).

    Args:
        limit: the largest size allowed, bytes.
        follow_symlinks: False refuses a final symbolic link (O_NOFOLLOW).

    Raises:
        FileRefusedError: the reason (and the OS's message or the file's kind); never the
            file's content.
    """
    # O_NONBLOCK: opening a FIFO does not wait for a writer; it is refused below
    flags = os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC
    if not follow_symlinks:
        flags |= getattr(os, "O_NOFOLLOW", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError as exc:
        raise FileRefusedError(MISSING, _os_message(exc)) from None
    except OSError as exc:
        raise FileRefusedError(NOT_OPENED, _os_message(exc)) from None
    except (ValueError, TypeError):
        raise FileRefusedError(NOT_A_PATH) from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            kind = next((what for test, what in FILE_TYPES if test(info.st_mode)), "")
            raise FileRefusedError(NOT_REGULAR, kind)
        if info.st_size > limit:
            raise FileRefusedError(TOO_LARGE, size=info.st_size)
        chunks, size = [], 0
        while size <= limit:
            chunk = os.read(fd, limit + 1 - size)
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    except OSError as exc:
        raise FileRefusedError(NOT_READ, _os_message(exc)) from None
    finally:
        os.close(fd)
    if size > limit:
        raise FileRefusedError(GREW)
    return b"".join(chunks)
