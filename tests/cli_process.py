"""``brake-sim`` commands and nodes in processes of their own, without paying the
interpreter's start-up in each.

A test worker starts one server process (``python -m tests.cli_process``) that imports
what the commands import and loads the default kernels once; for each command it forks a
child that runs the module as ``python -m MODULE ARGS`` does (:func:`runpy.run_module`),
with its own standard streams, working directory, environment, process group and exit
status. A command is still a real process (its exit status, what it prints, what it
leaves behind, its signals, a crash of its own); what the child does not repeat is the
start-up: the interpreter, the imports and numba's loading of the kernels (about 1.3 s of
CPU a command, hundreds of commands in the suite). Whether a command's start imports only
what it needs is tested in ``tests/cli/test_cli.py`` with fresh interpreters.

:func:`run` takes :func:`subprocess.run`'s arguments and :func:`popen` those of
:class:`subprocess.Popen` (output to files only), for ``python -m`` of one of
:data:`MODULES`; each falls back to :mod:`subprocess` where the server cannot stand in:
another command line, standard input or a pipe, or an environment that differs from the
server's in a variable read at start-up (numba's, Python's, the kernel cache's). With
``BRAKE_SIM_TESTS_FRESH=1`` in the environment every command gets a fresh interpreter.
"""

from __future__ import annotations

import atexit
import gc
import importlib
import io
import json
import locale
import os
import runpy
import select
import signal
import subprocess
import sys
import tempfile
import threading
import time
import traceback
from pathlib import Path
from typing import Any

MODULES = ("brake_sim_ros.cli", "brake_sim_ros.app.node")
REPO = Path(__file__).resolve().parents[1]
# read when the interpreter starts or a module is imported: only a fresh interpreter
# honours a change of them (but those of HONOURED, see _child)
IMPORT_TIME_ENV = (
    "PYTHON", "NUMBA_", "BRAKE_SIM_CACHE_DIR", "XDG_CACHE_HOME", "OPENBLAS", "OMP_", "MKL_", "LD_"
)  # fmt: skip
HONOURED = {"PYTHONPATH", "PYTHONUNBUFFERED"}
FRESH_ENV = "BRAKE_SIM_TESTS_FRESH"  # set (to anything): every command a fresh interpreter
RUN_ARGS = {"capture_output", "text", "timeout", "cwd", "env", "check"}
POPEN_ARGS = {"stdout", "stderr", "env", "cwd"}


def _module(cmd: list[Any]) -> str | None:
    """The module of ``python -m MODULE ...`` with this interpreter, if one of MODULES."""
    ok = len(cmd) >= 3 and cmd[0] == sys.executable and cmd[1] == "-m" and cmd[2] in MODULES
    return cmd[2] if ok else None


class _Server:
    """The client's end: one server per test process, started at first use."""

    def __init__(self) -> None:
        self.env = dict(os.environ)
        self.scratch = Path(tempfile.mkdtemp(prefix="brake-sim-cli-"))
        self.count = 0  # scratch files
        self.served = 0  # requests
        with (self.scratch / "server.err").open("w") as log:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "tests.cli_process"],
                cwd=REPO,
                env=self.env,
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=log,
                text=True,
                bufsize=1,
                start_new_session=True,
            )
        self.request({})  # its line once warm

    def request(self, request: dict[str, Any]) -> dict[str, Any]:
        if request:
            self.served += 1
            self.proc.stdin.write(json.dumps(request) + "\n")
            self.proc.stdin.flush()
        reply = self.proc.stdout.readline()
        if not reply.startswith("{"):
            said = (self.scratch / "server.err").read_text().strip().splitlines()
            raise RuntimeError(f"the CLI server failed: {said[-1:]}")
        return json.loads(reply)

    def usable_env(self, env: dict[str, str]) -> bool:
        """Whether a fresh interpreter with ``env`` would start as the server did: the same
        variables read at start-up but those the child honours."""
        keys = set(env) | set(self.env)
        changed = {k for k in keys if env.get(k) != self.env.get(k)} - HONOURED
        return not any(k.startswith(IMPORT_TIME_ENV) for k in changed)

    def scratch_file(self, suffix: str) -> Path:
        self.count += 1
        return self.scratch / f"{self.count}.{suffix}"

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.stdin.close()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()
        for p in self.scratch.iterdir():
            p.unlink()
        self.scratch.rmdir()


_server: _Server | None = None


def _server_for(cmd: list[Any], kwargs: dict[str, Any], allowed: set[str]) -> _Server | None:
    """The server, if it can run ``cmd`` with ``kwargs`` as a fresh interpreter would."""
    global _server
    if _module(cmd) is None or set(kwargs) - allowed or os.environ.get(FRESH_ENV):
        return None
    if _server is None:
        _server = _Server()
        atexit.register(_server.close)
    env = os.environ if kwargs.get("env") is None else kwargs["env"]
    return _server if _server.usable_env(dict(env)) else None


def _request(cmd: list[Any], kwargs: dict[str, Any], out: str, err: str) -> dict[str, Any]:
    env = dict(os.environ if kwargs.get("env") is None else kwargs["env"])
    cwd = os.fspath(kwargs.get("cwd") or os.getcwd())
    argv = [os.fspath(a) for a in cmd[3:]]
    return {"module": cmd[2], "argv": argv, "cwd": cwd, "env": env, "out": out, "err": err}


def run(cmd: list[Any], **kwargs: Any) -> subprocess.CompletedProcess:
    """:func:`subprocess.run` of ``cmd``, through the server where it can stand in."""
    server = _server_for(cmd, kwargs, RUN_ARGS)
    if server is None or not kwargs.get("capture_output"):
        return subprocess.run(cmd, **kwargs)
    out, err = server.scratch_file("out"), server.scratch_file("err")
    timeout = kwargs.get("timeout")
    request = _request(cmd, kwargs, str(out), str(err))
    status = server.request({"op": "run", "timeout": timeout, **request})
    stdout, stderr = out.read_bytes(), err.read_bytes()
    out.unlink()
    err.unlink()
    if kwargs.get("text"):
        stdout, stderr = _text(stdout), _text(stderr)
    if status.get("timed_out"):
        raise subprocess.TimeoutExpired(cmd, timeout, stdout, stderr)
    done = subprocess.CompletedProcess(cmd, status["returncode"], stdout, stderr)
    if kwargs.get("check"):
        done.check_returncode()
    return done


class ForkedProcess:
    """What a test uses of :class:`subprocess.Popen`, for a child of the server."""

    def __init__(self, server: _Server, args: list[Any], pid: int) -> None:
        self._server, self.args, self.pid = server, args, pid
        self.returncode: int | None = None

    def poll(self) -> int | None:
        if self.returncode is None:
            self.returncode = self._server.request({"op": "poll", "pid": self.pid})["returncode"]
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        if self.returncode is None:
            status = self._server.request({"op": "wait", "pid": self.pid, "timeout": timeout})
            if status.get("timed_out"):
                raise subprocess.TimeoutExpired(self.args, timeout)
            self.returncode = status["returncode"]
        return self.returncode

    def send_signal(self, sig: int) -> None:
        if self.poll() is None:  # not yet reaped, so the pid is still the child's
            os.kill(self.pid, sig)

    def terminate(self) -> None:
        self.send_signal(signal.SIGTERM)

    def kill(self) -> None:
        self.send_signal(signal.SIGKILL)


def popen(cmd: list[Any], **kwargs: Any) -> subprocess.Popen | ForkedProcess:
    """:class:`subprocess.Popen` of ``cmd`` with ``stdout`` a file or ``DEVNULL`` and
    ``stderr`` a file, ``DEVNULL`` or ``STDOUT``, through the server where it can stand in."""
    out, err = (_path(kwargs.get(name)) for name in ("stdout", "stderr"))
    server = _server_for(cmd, kwargs, POPEN_ARGS)
    if server is None or out is None or err is None:
        return subprocess.Popen(cmd, **kwargs)
    pid = server.request({"op": "spawn", **_request(cmd, kwargs, out, err)})["pid"]
    return ForkedProcess(server, cmd, pid)


def _path(stream: Any) -> str | None:
    """Where a child writes a stream given to Popen as a file, DEVNULL or (stderr) STDOUT;
    None for anything else (a pipe, the test's own streams)."""
    if stream == subprocess.DEVNULL:
        return os.devnull
    if stream == subprocess.STDOUT:
        return "&1"
    name = getattr(stream, "name", None)
    return name if isinstance(name, str) and os.path.isfile(name) else None


def _text(data: bytes) -> str:
    """As ``subprocess.run(text=True)`` decodes: the locale's encoding, universal newlines."""
    return io.TextIOWrapper(io.BytesIO(data), encoding=locale.getpreferredencoding(False)).read()


# --- the server's end -------------------------------------------------------------------


def _warm() -> None:
    """What nearly every command imports, and the default kernels loaded and run once."""
    import brake_sim_ros.cli  # noqa: F401
    from brake_sim_ros.scenarios import load_scenario
    from brake_sim_ros.solvers.warmup import ensure_compiled
    from brake_sim_ros.stream.run import run_scenario

    ensure_compiled()
    run_scenario(load_scenario("symmetric"), duration_s=0.002)


def _child(request: dict[str, Any]) -> None:
    """In the forked child: become ``python -m MODULE ARGV``; never returns."""
    code = 1
    try:
        os.setpgid(0, 0)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        append = os.O_WRONLY | os.O_CREAT | os.O_APPEND
        for fd, path, flags in ((0, os.devnull, os.O_RDONLY), (1, request["out"], append)):
            opened = os.open(path, flags, 0o600)
            os.dup2(opened, fd)
            os.close(opened)
        if request["err"] == "&1":
            os.dup2(1, 2)
        else:
            opened = os.open(request["err"], append, 0o600)
            os.dup2(opened, 2)
            os.close(opened)
        os.chdir(request["cwd"])
        os.environ.clear()
        os.environ.update(request["env"])
        # as python -m: the working directory first, then PYTHONPATH's entries
        sys.path[0] = os.getcwd()
        known = {os.path.realpath(p) for p in sys.path if p}
        given = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
        sys.path[1:1] = [p for p in given if os.path.realpath(p) not in known]
        importlib.invalidate_caches()  # directories written since the server listed them
        if os.environ.get("PYTHONUNBUFFERED"):  # as python -u: no buffer under the text
            for name, fd in (("stdout", 1), ("stderr", 2)):
                old = getattr(sys, name)
                raw = open(fd, "wb", buffering=0, closefd=False)  # noqa: SIM115
                new = io.TextIOWrapper(raw, old.encoding, old.errors, write_through=True)
                setattr(sys, name, new)
        sys.argv = ["-m", *request["argv"]]  # run_module puts the module's path first
        try:
            runpy.run_module(request["module"], run_name="__main__", alter_sys=True)
            code = 0
        except SystemExit as exc:
            code = exc.code
        if code is None:
            code = 0
        elif not isinstance(code, int):
            print(code, file=sys.stderr)
            code = 1
    except BaseException:
        traceback.print_exc()
        code = 1
    finally:
        try:
            threading._shutdown()  # as the interpreter's exit does: its threads, then atexit
            atexit._run_exitfuncs()
            sys.stdout.flush()
            sys.stderr.flush()
        finally:
            os._exit(code)


def _wait(pid: int, timeout: float | None, kill: bool) -> dict[str, Any]:
    """The child's exit status; once ``timeout`` s have passed, its group killed (``kill``)
    or the time-out said."""
    end = None if timeout is None else time.monotonic() + timeout
    fd = os.pidfd_open(pid)
    try:
        left = None if end is None else max(0.0, end - time.monotonic())
        if not select.select([fd], [], [], left)[0]:
            if not kill:
                return {"timed_out": True}
            os.killpg(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            return {"returncode": -signal.SIGKILL, "timed_out": True}
    finally:
        os.close(fd)
    _, status = os.waitpid(pid, 0)
    return {"returncode": os.waitstatus_to_exitcode(status)}


def _fork(request: dict[str, Any]) -> int:
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:
        _child(request)
    return pid


def _answer(request: dict[str, Any]) -> dict[str, Any]:
    op = request["op"]
    if op == "run":
        return _wait(_fork(request), request["timeout"], kill=True)
    if op == "spawn":
        return {"pid": _fork(request)}
    if op == "wait":
        return _wait(request["pid"], request["timeout"], kill=False)
    pid, status = os.waitpid(request["pid"], os.WNOHANG)  # "poll"
    return {"returncode": os.waitstatus_to_exitcode(status) if pid else None}


def serve() -> None:
    """Read one request a line on stdin, answer each with one line."""
    _warm()
    gc.freeze()  # what the warm-up made: never collected in a child, so never copied by it
    if threading.active_count() != 1:  # a fork copies no thread but the caller
        raise RuntimeError(f"{threading.active_count()} threads: cannot fork safely")
    print(json.dumps({"ready": True}), flush=True)
    for line in sys.stdin:
        print(json.dumps(_answer(json.loads(line))), flush=True)


if __name__ == "__main__":
    serve()
