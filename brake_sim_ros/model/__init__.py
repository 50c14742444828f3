"""The physics core: parameters, geometry, contact, standstill and the compiled kernels.

Importing this package points numba's on-disk kernel cache at a directory keyed by a hash
of the compiled folders' sources (:data:`COMPILED_ROOMS`) and of the checkout's path.
numba checks only the file of each cached function, not the files of the functions it
inlines, so after a change to ``contact.py`` alone the kernels in ``kernel.py`` would
otherwise be loaded stale from the cache. ``NUMBA_CACHE_DIR`` (numba's own setting) or
``BRAKE_SIM_CACHE_DIR`` override the location.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numba

# The package's folders that hold compiled (numba) functions: the physics here, the sensors'
# signal paths in sensing/ (which inline this folder's functions too).
COMPILED_ROOMS = ("model", "sensing")


def _kernel_cache_dir() -> Path:
    digest = hashlib.sha256()
    package = Path(__file__).parent.parent
    # numba files its cache under each source file's path: a second checkout of the same
    # sources gets a directory (and compiled-part markers) of its own
    digest.update(str(package.resolve()).encode())
    for room in COMPILED_ROOMS:
        for source in sorted((package / room).glob("*.py")):
            digest.update(f"{room}/{source.name}".encode())
            digest.update(source.read_bytes())
    base = os.environ.get("BRAKE_SIM_CACHE_DIR")
    if not base:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "brake-sim"
    return Path(base) / "numba" / digest.hexdigest()[:16]


if not os.environ.get("NUMBA_CACHE_DIR"):
    numba.config.CACHE_DIR = str(_kernel_cache_dir())
