"""Where episodes run: in this process, a local process pool, or a Dask cluster.

All three are ``concurrent.futures.Executor``s. Episodes are independent and seeded by
their index, so the results do not depend on which one ran them, or in what order.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from contextlib import contextmanager
from multiprocessing import get_context
from typing import Any

from copi.errors import CopiError, InvalidArgumentError

__all__ = ["ExecutorError", "InlineExecutor", "make_executor"]


class ExecutorError(CopiError):
    """The requested executor cannot be had (e.g. an unreachable Dask scheduler)."""


class InlineExecutor(Executor):
    """Runs each task at once in the calling process (one worker, no pickling)."""

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future[Any]:
        fut: Future[Any] = Future()
        try:
            fut.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # delivered through the future, as a pool would
            fut.set_exception(exc)
        return fut


HANDSHAKE_SECONDS = 5.0
"""How long a Dask scheduler has to answer (a server of another kind at the address may
accept the connection and then say nothing, forever): with copi's start-up, a command
pointed at no scheduler ends within 10 s."""


def _connect(client_class: Any, scheduler: str) -> Any:
    """A ``distributed.Client`` of ``scheduler``, or one clear error within
    :data:`HANDSHAKE_SECONDS`: the handshake runs in a daemon thread, abandoned if it
    does not end."""
    box: dict[str, Any] = {}

    def connect() -> None:
        try:
            box["client"] = client_class(scheduler, timeout=f"{HANDSHAKE_SECONDS:g}s")
        except BaseException as exc:  # reported below, in the caller's thread
            box["error"] = exc

    thread = threading.Thread(target=connect, name="copi-dask-connect", daemon=True)
    thread.start()
    thread.join(HANDSHAKE_SECONDS)
    if thread.is_alive():
        raise ExecutorError(
            f"cannot reach the Dask scheduler at {scheduler}: none answered within "
            f"{HANDSHAKE_SECONDS:g} s (nothing listens there, or something else does)"
        )
    if "error" in box:
        exc = box["error"]
        if isinstance(exc, OSError | TimeoutError | ValueError):
            raise ExecutorError(f"cannot reach the Dask scheduler at {scheduler}: {exc}")
        if isinstance(exc, MemoryError | OverflowError):
            # a server of another kind spoke first: its bytes read as a message's length
            raise ExecutorError(f"cannot reach the Dask scheduler at {scheduler}: what "
                                "answered there is not a Dask scheduler") from None  # fmt: skip
        raise exc
    return box["client"]


@contextmanager
def make_executor(workers: int = 1, scheduler: str | None = None) -> Iterator[Executor]:
    """An executor for ``workers`` local processes, or the Dask cluster at ``scheduler``
    (``tcp://host:port``, via ``distributed.Client``)."""
    if scheduler is not None:
        try:
            from distributed import Client
        except ImportError:  # pragma: no cover - distributed is a dependency
            raise ExecutorError("--scheduler needs the 'distributed' package") from None
        client = _connect(Client, scheduler)
        try:
            yield client.get_executor()
        finally:
            client.close()
        return
    if int(workers) != workers or workers < 1:
        raise InvalidArgumentError(f"workers must be a positive int; got {workers!r}")
    if workers == 1:
        yield InlineExecutor()
        return
    # fork where the platform has it: workers start with copi imported and its compiled
    # functions loaded, instead of paying seconds of start-up each (spawn elsewhere).
    import multiprocessing

    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    pool = ProcessPoolExecutor(
        workers, mp_context=get_context(method), initializer=_worker_init,
        initargs=(os.getpid(),),
    )  # fmt: skip
    try:
        yield pool
    except BaseException:
        _stop_now(pool)
        raise
    pool.shutdown(wait=True, cancel_futures=True)


def _stop_now(pool: ProcessPoolExecutor, grace: float = 5.0) -> None:
    """Stop an interrupted or failed pool without waiting for its chunks, whose results
    could no longer be stored anyway, and without any wait that has no bound.

    ``shutdown(wait=True)`` after terminating workers can block for ever on CPython 3.11
    (the pool's manager thread joins a queue feeder that may be stuck on a pipe nobody
    reads, or a lock a signal left taken), so: no new work, workers terminated then killed,
    and the manager thread given ``grace`` seconds. The command line exits at once should
    that thread outlive it (see ``copi.cli.main``)."""
    # taken first: shutdown(wait=False) drops the pool's references to both
    running = getattr(pool, "_processes", None) or {}
    procs = [proc for proc in list(running.values()) if proc.is_alive()]
    manager = getattr(pool, "_executor_manager_thread", None)
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in procs:
        proc.terminate()
    deadline = time.monotonic() + grace
    for proc in procs:
        proc.join(max(0.0, deadline - time.monotonic()))
        if proc.is_alive():
            proc.kill()
            proc.join(1.0)
    if manager is not None:
        manager.join(max(0.1, deadline - time.monotonic()))


def _worker_init(parent: int) -> None:
    """Set up a pool worker: it dies with its parent (even on kill -9), and leaves
    Ctrl-C to the parent, which stops the pool (no traceback from every worker)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):  # pragma: no cover - no prctl
            pass
    if os.getppid() != parent:  # the parent died before the line above
        os._exit(1)
    # Elsewhere (and as a second guard), a thread that ends the worker once orphaned.
    threading.Thread(target=_watch_parent, args=(parent,), daemon=True).start()


def _watch_parent(parent: int) -> None:
    while os.getppid() == parent:
        time.sleep(0.5)
    os._exit(1)
