"""A user's detector class, named ``module:Class`` or ``path/to/file.py:Class``.

``module:Class`` imports ``module`` from ``sys.path`` (the installed packages, and the
current directory only when Python put it there: ``python -m``, not the ``brake-sim``
script); ``path/to/file.py:Class`` loads that file, wherever it is, with no change to
``sys.path``. Either way the class must subclass
:class:`~brake_sim_ros.detection.detector.Detector` and be built without arguments.

An import that fails is one line saying which: the module or file not found, or, when it
was found, the error raised while importing it (a module it imports that is missing, a
syntax error with its line), never as if the user's own module were missing.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import os
import sys
import traceback
from types import ModuleType

from brake_sim_ros.detection.detector import Detector


def _failure(spec: str, exc: BaseException) -> ValueError:
    """The one line for an exception raised while importing ``spec``'s module: the
    exception and where in the user's code it came from."""
    where = ""
    if isinstance(exc, SyntaxError) and exc.filename:
        where = f" ({exc.filename}, line {exc.lineno})"
    else:
        frames = traceback.extract_tb(exc.__traceback__)
        user = [f for f in frames if "importlib" not in f.filename]
        if user:
            where = f" ({user[-1].filename}, line {user[-1].lineno})"
    text = " ".join(str(exc).split())[:300]
    return ValueError(f"detector {spec!r}: importing it raised {type(exc).__name__}: {text}{where}")


def _from_file(spec: str, path: str) -> ModuleType:
    if not os.path.isfile(path):
        raise ValueError(f"detector {spec!r}: no file {path!r}; allowed path/to/file.py:Class")
    # a private module name per file, so two files of one name do not collide
    digest = hashlib.sha256(os.path.realpath(path).encode()).hexdigest()[:12]
    name = f"brake_sim_user_{digest}"
    if name in sys.modules:
        return sys.modules[name]
    module_spec = importlib.util.spec_from_file_location(name, path)
    if module_spec is None or module_spec.loader is None:
        raise ValueError(f"detector {spec!r}: {path!r} is not a Python file")
    module = importlib.util.module_from_spec(module_spec)
    sys.modules[name] = module  # dataclasses and pickling look their module up here
    try:
        module_spec.loader.exec_module(module)
    except KeyboardInterrupt:
        del sys.modules[name]
        raise
    except BaseException as exc:  # the user's code may raise anything (SystemExit too)
        del sys.modules[name]
        raise _failure(spec, exc) from None
    return module


def _from_module(spec: str, name: str) -> ModuleType:
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as exc:
        missing = exc.name or ""
        if name == missing or name.startswith(missing + "."):  # the named module itself
            raise ValueError(
                f"detector {spec!r}: no module {name!r} on the Python path; allowed an"
                " importable module:Class, or path/to/file.py:Class"
            ) from None
        raise _failure(spec, exc) from None
    except KeyboardInterrupt:
        raise
    except BaseException as exc:  # the user's code may raise anything (SystemExit too)
        raise _failure(spec, exc) from None


def load_class(spec: str) -> type[Detector]:
    """The :class:`Detector` subclass ``spec`` names (module docstring).

    Raises:
        ValueError: one line (not found, failed to import, not a Detector subclass).
    """
    where, sep, attr = spec.rpartition(":")
    if not sep or not where or not attr.isidentifier():
        raise ValueError(f"detector {spec!r}: allowed module:Class or path/to/file.py:Class")
    module = _from_file(spec, where) if where.endswith(".py") else _from_module(spec, where)
    cls = getattr(module, attr, None)
    if cls is None:
        raise ValueError(f"detector {spec!r}: {where} has no {attr!r}")
    if not (isinstance(cls, type) and issubclass(cls, Detector)):
        raise ValueError(f"detector {spec!r}: not a brake_sim_ros.detection Detector subclass")
    return cls
