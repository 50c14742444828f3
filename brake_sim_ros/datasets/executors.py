"""Where a sweep's runs execute: a local pool of worker processes, or the workers of a Dask
cluster. Both give the same two operations (:class:`Executor`), and both turn every way a
worker can fail (a process killed, out of memory, a cluster without workers, Dask's
``KilledWorker``) into one :class:`ExecutorError` line.

The local pool's processes fork from one server (:func:`pool_context`) and end with the
sweep however it ends (:mod:`.orphans`). Dask task keys carry a caller's tag, so two
sweeps on one shared cluster never share a key (and so never each other's results).
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import multiprocessing
import threading
from collections.abc import Callable, Iterator, Sequence
from typing import Any, Protocol, TypeVar

from brake_sim_ros.errors import BrakeSimError

T = TypeVar("T")
WORKERS_TIMEOUT_S = 60.0  # how long a cluster may have no worker before the sweep ends
CONNECT_TIMEOUT_S = 10.0  # how long a scheduler may take to be connected to, s
MAX_WORKERS = 1024  # local worker processes a command may ask for
DIED = (
    "a worker process died (killed, or out of memory?) with {n} runs unfinished: the"
    " finished ones are kept; run the command again to resume"
)


def check_workers(workers: int, option: str = "--workers") -> None:
    """Refuse a count of local worker processes outside 1 to :data:`MAX_WORKERS`.

    Raises:
        BrakeSimError: one line naming ``option``.
    """
    if not 1 <= workers <= MAX_WORKERS:
        raise BrakeSimError(f"{option} {workers}: allowed 1 to {MAX_WORKERS} worker processes")


class ExecutorError(BrakeSimError, ValueError):
    """The workers failed as a whole (not one run): one line."""


class Executor(Protocol):
    def map(self, fn: Callable[[Any], T], items: Sequence[Any], keys: Sequence[str]) -> Iterator[T]:
        """``fn(item)`` of each item, in the order they finish (``keys``: Dask's)."""
        ...

    def call(self, fn: Callable[[Any], T], item: Any, key: str) -> T:
        """``fn(item)`` on a worker, waited for."""
        ...


def one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= 500 else text[:400] + " ... " + text[-60:]


def pool_context() -> multiprocessing.context.BaseContext:
    """The local pool's process context: workers fork from one server process that
    imported and warmed the run path once (:mod:`.warm_worker`); none of this process's
    state is copied. The server starts on first use and serves every later pool of this
    process."""
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["brake_sim_ros.datasets.warm_worker"])
    return context


class _Local:
    def __init__(self, pool: concurrent.futures.ProcessPoolExecutor) -> None:
        self.pool = pool

    def map(self, fn: Callable[[Any], T], items: Sequence[Any], keys: Sequence[str]) -> Iterator[T]:
        futures = [self.pool.submit(fn, item) for item in items]
        try:
            for future in concurrent.futures.as_completed(futures):
                yield future.result()
        except concurrent.futures.process.BrokenProcessPool:
            unfinished = sum(not f.done() or f.exception() is not None for f in futures)
            # join the pool's manager thread now: left to interpreter exit, its closing of
            # the wake-up pipe races the exit hook's write to it, which then printed an
            # OSError traceback after the one-line error (seen once in a whole-suite run)
            self.pool.shutdown(wait=True, cancel_futures=True)
            raise ExecutorError(DIED.format(n=unfinished)) from None

    def call(self, fn: Callable[[Any], T], item: Any, key: str) -> T:
        return next(iter(self.map(fn, [item], [key])))


class _Dask:
    def __init__(self, client: Any, scheduler: str) -> None:
        self.client = client
        self.scheduler = scheduler

    def _wait_for_workers(self) -> None:
        try:
            self.client.wait_for_workers(1, timeout=WORKERS_TIMEOUT_S)
        except (TimeoutError, OSError):
            raise ExecutorError(
                f"--scheduler {self.scheduler}: no worker joined in {WORKERS_TIMEOUT_S:.0f} s:"
                " start workers (dask worker ADDRESS) that share the output directory"
            ) from None

    def map(self, fn: Callable[[Any], T], items: Sequence[Any], keys: Sequence[str]) -> Iterator[T]:
        from distributed import as_completed

        self._wait_for_workers()
        futures = self.client.map(fn, items, pure=False, key=list(keys))
        try:
            for future in as_completed(futures):
                yield future.result()
        except GeneratorExit:
            raise
        except Exception as exc:  # KilledWorker, a lost scheduler: the cluster's, not a run's
            self.client.cancel(futures)
            unfinished = sum(not f.done() for f in futures)
            if type(exc).__name__ == "KilledWorker":
                raise ExecutorError(DIED.format(n=unfinished)) from None
            raise ExecutorError(
                f"--scheduler {self.scheduler}: the cluster failed ({type(exc).__name__}:"
                f" {one_line(exc)}) with {unfinished} runs unfinished: the finished ones are"
                " kept; run the command again to resume"
            ) from None

    def call(self, fn: Callable[[Any], T], item: Any, key: str) -> T:
        return next(iter(self.map(fn, [item], [key])))


def _connect(client_class: Any, scheduler: str) -> Any:
    """A Dask client of the scheduler at ``scheduler``, within :data:`CONNECT_TIMEOUT_S`.

    The client's own timeout covers the connection, not the handshake: a server that is no
    Dask scheduler may never answer it (an HTTP server waits for a request), or answer it
    with bytes read as a message's length (3 EiB, once). The client is made in a thread
    waited for that long; whatever it raises is the scheduler's refusal, in one line.

    Raises:
        ExecutorError: no Dask scheduler answered there in time.
    """
    made: list[Any] = []
    failed: list[BaseException] = []

    def connect() -> None:
        try:
            made.append(client_class(scheduler, timeout=CONNECT_TIMEOUT_S))
        except BaseException as exc:  # any failure is the scheduler's
            failed.append(exc)

    thread = threading.Thread(target=connect, name="dask-connect", daemon=True)
    thread.start()
    thread.join(CONNECT_TIMEOUT_S + 5.0)
    if made:
        return made[0]
    if failed:
        exc = failed[0]
        why = one_line(exc) if isinstance(exc, OSError | TimeoutError | ValueError) else ""
        raise ExecutorError(
            f"--scheduler {scheduler}: cannot connect ({why or type(exc).__name__}): allowed"
            " a Dask scheduler's address"
        )
    raise ExecutorError(
        f"--scheduler {scheduler}: no Dask scheduler answered in {CONNECT_TIMEOUT_S + 5.0:.0f} s"
    )


@contextlib.contextmanager
def open_executor(
    workers: int, scheduler: str | None, initializer: Callable[[], None]
) -> Iterator[Executor]:
    """A local pool of ``workers`` processes (each started with ``initializer``), or the
    Dask cluster at ``scheduler``.

    Raises:
        ExecutorError: the scheduler cannot be reached (before anything else).
    """
    if scheduler is None:
        pool = concurrent.futures.ProcessPoolExecutor(
            max_workers=workers, mp_context=pool_context(), initializer=initializer
        )
        try:
            yield _Local(pool)
        except BaseException:  # Ctrl-C or a refusal: queued runs are dropped, not waited for
            pool.shutdown(wait=False, cancel_futures=True)
            raise
        pool.shutdown(wait=True)
        return
    try:
        from distributed import Client
    except ImportError:
        raise ExecutorError(
            "--scheduler needs dask.distributed: pip install 'dask[distributed]'"
        ) from None
    client = _connect(Client, scheduler)
    try:
        yield _Dask(client, scheduler)
    finally:
        client.close()
