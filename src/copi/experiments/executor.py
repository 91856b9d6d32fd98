"""Where episodes run: in this process, a local process pool, or a Dask cluster.

All three are ``concurrent.futures.Executor``s. Episodes are independent and seeded by
their index, so the results do not depend on which one ran them, or in what order.
"""

from __future__ import annotations

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


@contextmanager
def make_executor(workers: int = 1, scheduler: str | None = None) -> Iterator[Executor]:
    """An executor for ``workers`` local processes, or the Dask cluster at ``scheduler``
    (``tcp://host:port``, via ``distributed.Client``)."""
    if scheduler is not None:
        try:
            from distributed import Client
        except ImportError:  # pragma: no cover - distributed is a dependency
            raise ExecutorError("--scheduler needs the 'distributed' package") from None
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise ExecutorError(f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None
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
    pool = ProcessPoolExecutor(workers, mp_context=get_context(method))
    try:
        yield pool
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
