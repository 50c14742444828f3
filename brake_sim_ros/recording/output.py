"""Files a command writes: checked before anything is written, whole or not at all.

Rules (``recover FIXED``, ``view --save FILE.rrd``, ``simulate --out/--mcap/--rerun save``):

* an existing output is refused unless ``overwrite`` (``--overwrite``);
* an output that is a symbolic link is refused, even with ``overwrite`` (nothing is ever
  written through a link);
* an output that is one of the inputs is refused, even with ``overwrite``, whatever path
  names it (the same device and inode: another path, a hard link, a link to it);
* an output that exists and is not a regular file (a directory, a device) is refused;
* the directory must be writable (missing directories are created, and removed again if
  the command fails; with ``make_parents=False`` a missing directory is refused);
* :func:`probe_output` also proves it: it creates and removes a file there, so a directory
  that looks writable but takes no file (``/proc``, a full or read-only file system) is
  refused before any work is done.

All of this is checked before the first byte is written. The file is then written under a
temporary name in the target directory (``.NAME.XXXX.partial.SUFFIX``), fsync'ed and
renamed into place in one step: a failure or Ctrl-C leaves no partial output, and a
reader never sees half a file. Without ``overwrite`` the rename is a hard link, which
fails if the name was taken in the meantime.
"""

from __future__ import annotations

import contextlib
import errno
import itertools
import os
import secrets
import stat
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path

from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.recording.mcap_format import describe_path


class OutputError(BrakeSimError, ValueError):
    """An output path the rules above refuse, or a write that failed (one line)."""


def _identity(path: Path) -> tuple[int, int] | None:
    try:
        info = os.stat(path)
    except OSError:
        return None
    return info.st_dev, info.st_ino


def _missing_parents(directory: Path) -> list[Path]:
    """The directories of ``directory``'s path that do not exist yet, outermost first."""
    missing = []
    while not directory.exists():
        missing.append(directory)
        if directory.parent == directory:
            break
        directory = directory.parent
    return missing[::-1]


def _make_directory(directory: Path, made: list[Path]) -> None:
    """Make ``directory``, one of ``made``. Another process (a sweep's other worker) may make
    it between the check and here: a directory made so is used, and dropped from ``made``
    (not ours to remove); anything else in its place is refused."""
    try:
        directory.mkdir()
    except FileExistsError:
        if not directory.is_dir():
            raise
        made.remove(directory)


def check_output_directory(path: str | os.PathLike[str], option: str = "--out") -> Path:
    """Check the directory ``path`` a command will write its files into, before its work
    (nothing is made): refused if empty, a symbolic link or not a directory, or if missing
    where its nearest existing parent is not a writable directory.

    Raises:
        OutputError: one line naming the directory.
    """
    if not os.fspath(path).strip():
        raise OutputError(f"{option} {os.fspath(path)!r}: allowed a directory path")
    out = Path(path)
    name = describe_path(out)
    try:
        info = os.lstat(out)
    except (FileNotFoundError, NotADirectoryError):
        info = None
    except OSError as exc:
        raise OutputError(f"{option} {name}: cannot check it ({exc.strerror or exc})") from None
    if info is not None and stat.S_ISLNK(info.st_mode):
        raise OutputError(
            f"{option} {name} is a symbolic link: outputs are never written through a link"
        )
    if info is not None and not stat.S_ISDIR(info.st_mode):
        raise OutputError(f"{option} {name} exists and is not a directory: allowed a directory")
    missing = _missing_parents(out)
    existing = missing[0].parent if missing else out
    if not existing.is_dir():
        raise OutputError(f"{option} {name}: {describe_path(existing)} is not a directory")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise OutputError(f"{option} {name}: directory {describe_path(existing)} is not writable")
    return out


def output_directory(path: str | os.PathLike[str], option: str = "--out") -> Path:
    """The directory ``path`` a command writes its files into, checked
    (:func:`check_output_directory`) and made (with its parents) if missing. Nothing else is
    written.

    Raises:
        OutputError: one line naming the directory.
    """
    out = check_output_directory(path, option)
    name = describe_path(out)
    if not out.is_dir():
        try:
            out.mkdir(parents=True)
        except OSError as exc:
            raise OutputError(f"{option} {name}: cannot make it ({exc.strerror or exc})") from None
    return out


def same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """Whether two output paths name one file (the same directory and name, or the same
    existing file through another path)."""
    pa, pb = Path(a), Path(b)
    if (os.path.realpath(pa.parent), pa.name) == (os.path.realpath(pb.parent), pb.name):
        return True
    ia = _identity(pa)
    return ia is not None and ia == _identity(pb)


def check_output(
    path: str | os.PathLike[str],
    *,
    inputs: Sequence[str | os.PathLike[str]] = (),
    overwrite: bool = False,
    suffix: str | None = None,
    option: str = "output",
    make_parents: bool = True,
) -> Path:
    """Apply the module's rules to ``path`` (nothing is written).

    Args:
        inputs: the files the command reads; the output may be none of them.
        suffix: the required suffix (``".mcap"``), or None.
        option: how the output is named in messages (``"--save"``, ``"FIXED"``).
        make_parents: False to refuse a directory that does not exist (else it is made).

    Raises:
        OutputError: the first rule that refuses ``path``.
    """
    out = Path(path)
    name = describe_path(path)
    if not out.name or os.fspath(path).endswith(os.sep):
        raise OutputError(f"{option} {name}: allowed a file path, not a directory")
    if suffix is not None and out.suffix != suffix:
        raise OutputError(f"{option} {name}: allowed a path ending in {suffix}")
    try:
        info = os.lstat(out)
    except (FileNotFoundError, NotADirectoryError):  # the directory is checked below
        info = None
    except OSError as exc:
        raise OutputError(f"{option} {name}: cannot check it ({exc.strerror or exc})") from None
    if info is not None:
        if stat.S_ISLNK(info.st_mode):
            raise OutputError(
                f"{option} {name} is a symbolic link: outputs are never written through a"
                " link; give another path"
            )
        for source in inputs:
            if (info.st_dev, info.st_ino) == _identity(Path(source)):
                raise OutputError(
                    f"{option} {name} is the input {describe_path(source)}: an output never"
                    " replaces an input; give another path"
                )
        if not stat.S_ISREG(info.st_mode):
            raise OutputError(
                f"{option} {name} exists and is not a regular file: give another path"
            )
        if not overwrite:
            raise OutputError(f"{option} {name} exists: pass --overwrite to replace it")
    parent = out.parent
    missing = _missing_parents(parent)
    if missing and not make_parents:
        raise OutputError(
            f"{option} {name}: directory {describe_path(missing[-1])} does not exist: allowed a"
            " path in an existing directory"
        )
    existing = missing[0].parent if missing else parent
    if not existing.is_dir():
        raise OutputError(f"{option} {name}: {describe_path(existing)} is not a directory")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise OutputError(
            f"{option} {name}: directory {describe_path(existing)} is not writable here"
        )
    return out


@contextlib.contextmanager
def atomic_output(
    path: str | os.PathLike[str],
    *,
    inputs: Sequence[str | os.PathLike[str]] = (),
    overwrite: bool = False,
    suffix: str | None = None,
    option: str = "output",
    make_parents: bool = True,
) -> Iterator[Path]:
    """Check ``path`` (:func:`check_output`), then yield a temporary path beside it to write.

    When the block ends normally the temporary file is fsync'ed and renamed to ``path``
    (the rules are checked once more just before); when it raises, the temporary file and
    any directory made for it are removed and the exception goes on.

    Raises:
        OutputError: a rule refuses ``path``, or the file cannot be created or renamed.
    """
    rules = {"inputs": inputs, "overwrite": overwrite, "suffix": suffix, "option": option}
    out = check_output(path, make_parents=make_parents, **rules)
    name = describe_path(path)
    made = _missing_parents(out.parent)
    tmp: Path | None = None
    try:
        try:
            for directory in list(made):
                _make_directory(directory, made)
            tmp = _create_temporary(out)
        except OSError as exc:
            raise OutputError(
                f"{option} {name}: cannot write there ({exc.strerror or exc})"
            ) from None
        yield tmp
        check_output(path, make_parents=make_parents, **rules)
        try:
            with open(tmp, "rb+") as f:
                os.fsync(f.fileno())
            _publish(tmp, out, overwrite=overwrite)
            tmp = None
            _fsync_directory(out.parent)
        except FileExistsError:
            raise OutputError(
                f"{option} {name} appeared while it was written: pass --overwrite to replace it"
            ) from None
        except OSError as exc:
            raise OutputError(f"{option} {name}: cannot write it ({exc.strerror or exc})") from None
    except BaseException:
        if tmp is not None:
            with contextlib.suppress(OSError):
                tmp.unlink()
        for directory in reversed(made):
            with contextlib.suppress(OSError):
                directory.rmdir()  # only if still empty
        raise


def replace_output(
    path: str | os.PathLike[str], write: Callable[[Path], None], *, option: str = "--out"
) -> Path:
    """A file that a rerun replaces (a report, a figure): ``write`` fills a temporary file
    beside ``path`` (:func:`atomic_output`), which is then renamed over ``path``; never
    written through a link nor over anything but a regular file, never left half written.

    Raises:
        OutputError: a rule refuses ``path``, or it cannot be written.
    """
    with atomic_output(path, overwrite=True, option=option) as tmp:
        write(tmp)
    return Path(path)


def probe_output(
    path: str | os.PathLike[str],
    *,
    inputs: Sequence[str | os.PathLike[str]] = (),
    overwrite: bool = False,
    suffix: str | None = None,
    option: str = "output",
) -> Path:
    """:func:`check_output` with ``make_parents=False``, then prove the directory takes a
    new file: an empty temporary file is created beside ``path`` and removed at once.

    For a command that works long before it writes (``simulate``): a directory that looks
    writable but is not (``/proc``, a full or read-only file system; root passes every
    permission check) is refused before the work starts. Nothing is left behind.

    Raises:
        OutputError: a rule refuses ``path``, or no file can be created in its directory.
    """
    out = check_output(
        path, inputs=inputs, overwrite=overwrite, suffix=suffix, option=option, make_parents=False
    )
    try:
        tmp = _create_temporary(out)
    except OSError as exc:
        raise OutputError(
            f"{option} {describe_path(path)}: cannot write there ({exc.strerror or exc})"
        ) from None
    with contextlib.suppress(OSError):
        tmp.unlink()
    return out


def check_outputs(
    named: Sequence[tuple[str, str | os.PathLike[str], Mapping[str, str]]],
    *,
    inputs: Sequence[str | os.PathLike[str]] = (),
    overwrite: bool = False,
) -> dict[str, Path]:
    """Every output of one command, checked before the command works: each names its own
    file, ends in one of its suffixes and passes :func:`probe_output`.

    Args:
        named: ``(option, path, {suffix: what it is})`` per output; an empty description
            shows the bare suffix in the refusal.

    Returns:
        The checked path by option.

    Raises:
        OutputError: the first output a rule refuses.
    """
    for (option, path, _), (other, other_path, _) in itertools.combinations(named, 2):
        if same_file(path, other_path):
            raise OutputError(
                f"{option} {describe_path(path)} and {other} {describe_path(other_path)} name"
                " the same file: give each output its own path"
            )
    checked = {}
    for option, path, suffixes in named:
        rules = {"inputs": inputs, "overwrite": overwrite, "option": option}
        check_output(path, make_parents=False, **rules)  # the scenario file, a link: first
        if Path(path).suffix not in suffixes:
            allowed = " or ".join(f"{s} ({what})" if what else s for s, what in suffixes.items())
            raise OutputError(f"{option} {describe_path(path)}: allowed a path ending in {allowed}")
        checked[option] = probe_output(path, **rules)
    return checked


def _create_temporary(out: Path) -> Path:
    """A new empty file beside ``out``, with the permissions the umask gives new files."""
    for _ in range(100):
        tmp = out.with_name(f".{out.name}.{secrets.token_hex(4)}.partial{out.suffix}")
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o666)
        except FileExistsError:
            continue
        os.close(fd)
        return tmp
    raise FileExistsError(errno.EEXIST, "no free temporary name", str(out))


def _publish(tmp: Path, out: Path, *, overwrite: bool) -> None:
    """Rename ``tmp`` to ``out`` in one step; without ``overwrite`` never over a file."""
    if overwrite:
        os.replace(tmp, out)  # replaces a link itself, never writes through it
        return
    try:
        os.link(tmp, out)  # fails with EEXIST if ``out`` was created meanwhile
    except OSError as exc:
        if exc.errno not in (errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EMLINK):
            raise
        if os.path.lexists(out):  # a file system without hard links: check, then rename
            raise FileExistsError(errno.EEXIST, "exists", str(out)) from None
        os.rename(tmp, out)
        return
    tmp.unlink()


def _fsync_directory(directory: Path) -> None:
    """Make the rename durable (best effort: not every file system allows it)."""
    try:
        fd = os.open(directory, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        return
    try:
        with contextlib.suppress(OSError):
            os.fsync(fd)
    finally:
        os.close(fd)
