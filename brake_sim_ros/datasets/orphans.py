"""Worker processes that end when their parent does, however it ends.

A sweep's local pool is a fork server (a child of the sweep) and the workers it forks. When
the sweep is killed (SIGKILL, SIGTERM, an out-of-memory kill) nothing in it runs to stop
them, so each asks the Linux kernel to send it SIGKILL when its parent dies
(``prctl(PR_SET_PDEATHSIG)``); they would otherwise run on for minutes holding the
caller's stdout open. Elsewhere than Linux this does nothing.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import signal
import sys

_PR_SET_PDEATHSIG = 1  # <linux/prctl.h>


def die_with_parent() -> None:
    """Have this process killed (SIGKILL) when its parent process ends; if the parent has
    ended already (this process was adopted by init), end now."""
    if not sys.platform.startswith("linux"):
        return
    parent = os.getppid()
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
    except (OSError, AttributeError):  # no libc prctl: nothing to ask for
        return
    # the parent may have died before the request: then this process was adopted
    if parent == 1 or os.getppid() != parent:
        os._exit(1)
