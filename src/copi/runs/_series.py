"""The one loop of every experiment: independent, seeded items (episodes, games, lives)
run in this process, on a local pool or on a Dask cluster, into a results store, each
committed as it comes back, so that an interrupted run resumes where it stopped
(:func:`run_series`)."""

from __future__ import annotations

import os
import signal
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass
from typing import Any

from copi.errors import Interrupted, ctrl_c_behind
from copi.results import ResultsStore
from copi.runs._executor import ExecutorError, InlineExecutor, make_executor
from copi.runs._inputs import run_id

__all__ = [
    "MAX_EPISODES",
    "MAX_LIFE_TASKS",
    "MAX_LIVES",
    "MAX_TASKS",
    "Series",
    "run_one",
    "run_series",
]


class Tally:
    """Items of a run stored so far, out of all (for the interruption message)."""

    def __init__(self, finished: int, total: int) -> None:
        self.finished = finished
        self.total = total


@contextmanager
def stops_cleanly(
    tally: Tally,
    output: str | os.PathLike[str],
    unit: str,
    saved: Callable[[], int] | None = None,
) -> Iterator[None]:
    """Turn Ctrl-C, wherever it lands (numba reports one that arrives inside a compiled
    call as a SystemError), into :class:`copi.errors.Interrupted` saying what is saved:
    ``saved()`` counts it in the store (a Ctrl-C may land between a row's commit and
    the tally), else the tally."""
    def stored() -> int:
        if saved is not None:
            try:
                return saved()
            except Exception:  # the count is a courtesy; the message must get out
                pass
        return tally.finished

    try:
        yield
    except BrokenProcessPool:
        raise ExecutorError(
            f"a worker process died (killed, or out of memory): {stored()}/{tally.total} "
            f"{unit} saved in {output}; rerun the same command to resume"
        ) from None
    except (KeyboardInterrupt, SystemError) as exc:
        if isinstance(exc, SystemError) and ctrl_c_behind(exc) is None:
            raise
        raise Interrupted(
            f"{stored()}/{tally.total} {unit} saved in {output}; rerun the same command to "
            "resume"
        ) from None


@contextmanager
def ctrl_c_remembered() -> Iterator[Callable[[], bool]]:
    """Within: whether Ctrl-C (SIGINT) was pressed, as a callable. Python's own handler
    raises a KeyboardInterrupt wherever the main thread is, which code of another
    package may catch and drop (a run was once seen going on for a minute after
    Ctrl-C); so the handler here also notes the press, for the loop to check between
    items. Only Python's default handler is replaced, and only in the main thread: an
    ignored SIGINT (a background job) or a caller's own handler stays as it was."""
    presses: list[int] = []
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler):  # fmt: skip
        yield lambda: False
        return

    def noted(signum: int, frame: Any) -> None:
        presses.append(signum)
        raise KeyboardInterrupt

    signal.signal(signal.SIGINT, noted)
    try:
        yield lambda: bool(presses)
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)


MAX_EPISODES = 100_000
"""Most episodes (or games) a run may ask for per family: at a tenth of a second each,
three hours a method; more is a typing error, refused before anything is written."""
MAX_LIVES = 10_000
"""Most lives (worlds) of a lifelong run, and MAX_TASKS tasks in each."""
MAX_TASKS = 10_000
MAX_LIFE_TASKS = 1_000_000
"""Most tasks of a lifelong run in all (lives times tasks)."""


def execute(
    config: Any,
    items: list[Any],
    *,
    one: Callable[[Any, Any], list[Any]],
    many: Callable[[Any, list[Any]], list[Any]],
    commit: Callable[[list[Any]], None],
    pool: Any,
    workers: int,
    chunk: int,
    stopping: AbstractContextManager[Any],
) -> None:
    """Run every item on ``pool`` (:func:`~copi.runs.make_executor`'s) and hand its
    results to ``commit`` as they come back: in this process one item at a time
    (``one(config, item)``), or on a local pool or a Dask cluster in chunks of at most
    ``chunk`` (``many(config, items)``, which must pickle). On any exception the chunks
    not started are cancelled; ``stopping`` wraps the whole (e.g. the one-line Ctrl-C
    message). A Ctrl-C is also remembered (:func:`ctrl_c_remembered`) and stops the run
    at the next item or chunk, should the KeyboardInterrupt it raised have been swallowed
    on its way out."""
    with stopping, ctrl_c_remembered() as pressed:
        if isinstance(pool, InlineExecutor):
            for item in items:
                if pressed():
                    raise KeyboardInterrupt
                commit(one(config, item))
            return
        n_workers = workers if isinstance(pool, ProcessPoolExecutor) else 4
        size = max(1, min(chunk, len(items) // (4 * n_workers)))
        futures = [
            pool.submit(many, config, items[i : i + size]) for i in range(0, len(items), size)
        ]
        try:
            for fut in as_completed(futures):
                commit(fut.result())
                if pressed():
                    raise KeyboardInterrupt
        except BaseException:
            for fut in futures:
                fut.cancel()
            raise


@dataclass(frozen=True)
class Series:
    """One run in a results store: a method's items 0 .. total - 1 (episodes, games or
    lives) of one group (a family, a world file; None when the run has one).

    Experiments with several runs (the benchmark: every method on every family;
    Experiment 3: every method in the same lives) share each item's drawing between
    their series: an item runs once for all the series still missing it."""

    run_id: str
    experiment: str
    method: str
    """The method's label in the store."""
    config: dict[str, Any]
    """The run's identity (what decides its results)."""
    table: str
    """"episodes", "games" or "lifelong"."""
    total: int
    group: Any = None


Work = Callable[[Any, Any, int, list[Series]], list[tuple[Series, Any]]]
"""work(config, group, k, series) -> [(series, its result for item k)] (one result per
series; for table "lifelong", a result is a life: a list of task rows)."""


def run_series(
    config: Any,
    output: str | os.PathLike[str],
    series: list[Series],
    *,
    work: Work,
    unit: str,
    workers: int = 1,
    scheduler: str | None = None,
    progress: Callable[[int, int], None] | None = None,
    chunk: int = 8,
) -> None:
    """The one store loop of every experiment: register (or resume) each series in
    ``output``, run every item some series still misses (``work``, in this process or on
    a pool or Dask cluster, which must pickle it), and commit each result as it comes
    back, so that an interrupted run resumes where it stopped. ``progress(done, total)``
    counts (series, item) pairs; ``unit`` names them in the Ctrl-C message. The executor
    comes first: a scheduler that cannot be reached leaves no file behind."""
    with make_executor(workers, scheduler) as pool, ResultsStore(output) as store:
        missing: dict[tuple[Any, int], list[Series]] = {}
        total = 0
        for s in series:
            store.begin(s.run_id, s.experiment, s.method, s.config)
            done = store.done(s.run_id, s.method, s.table)
            total += s.total
            for k in range(s.total):
                if k not in done:
                    missing.setdefault((s.group, k), []).append(s)
        items = [(g, k, todo) for (g, k), todo in missing.items()]
        tally = Tally(total - sum(len(t) for _, _, t in items), total)
        if progress is not None:
            progress(tally.finished, total)

        def commit(results: list[tuple[Series, Any]]) -> None:
            for s, result in results:
                if s.table == "episodes":
                    store.add(s.run_id, s.experiment, s.method, result)
                elif s.table == "games":
                    store.add_game(s.run_id, s.experiment, s.method, result)
                elif result:
                    store.add_life(s.run_id, s.experiment, s.method, result)
                tally.finished += 1
            if progress is not None:
                progress(tally.finished, total)

        if not items:
            return

        def saved() -> int:
            return sum(len(store.done(s.run_id, s.method, s.table)) for s in series)

        execute(
            config, items, one=lambda c, item: work(c, *item), many=_many(work),
            commit=commit, pool=pool, workers=workers, chunk=chunk,
            stopping=stops_cleanly(tally, output, unit, saved),
        )  # fmt: skip


def run_one(
    config: Any,
    identity: dict[str, Any],
    output: str | os.PathLike[str],
    *,
    experiment: str,
    method: str,
    table: str,
    total: int,
    item: Callable[[Any, int], Any],
    unit: str,
    chunk: int,
    workers: int = 1,
    scheduler: str | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> str:
    """Run (or resume) an experiment of one run, items 0 .. total - 1 (``item(config,
    k)``, a module-level function), into ``output`` through :func:`run_series`; returns
    the run id (:func:`~copi.runs.run_id` of ``identity``)."""
    rid = run_id(identity)
    series = Series(rid, experiment, method, identity, table, total)
    run_series(config, output, [series], work=_Single(item), unit=unit, workers=workers,
               scheduler=scheduler, progress=progress, chunk=chunk)  # fmt: skip
    return rid


class _Single:
    """The work of a one-run experiment: item k of the config for its one series."""

    def __init__(self, item: Callable[[Any, int], Any]) -> None:
        self.item = item

    def __call__(self, config: Any, group: Any, k: int, todo: list[Series]) -> list[Any]:
        return [(s, self.item(config, k)) for s in todo]


class _many:
    """Several items in one task (fewer round trips to the workers); picklable."""

    def __init__(self, work: Work) -> None:
        self.work = work

    def __call__(self, config: Any, items: list[tuple[Any, int, list[Series]]]) -> list[Any]:
        return [r for g, k, todo in items for r in self.work(config, g, k, todo)]
