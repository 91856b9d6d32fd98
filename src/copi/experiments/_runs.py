"""What Experiment 1 and 2 runs share: identity from their configuration, and running
their independent, seeded items (episodes, games) into a results store."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from collections.abc import Callable, Iterator
from concurrent.futures import as_completed
from contextlib import AbstractContextManager, contextmanager
from typing import Any

from copi.errors import Interrupted, ResultsError
from copi.learning import Capabilities

__all__ = ["RunIdentity", "execute", "run_into_store", "stops_cleanly"]


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
    try:
        yield
    except (KeyboardInterrupt, SystemError) as exc:
        if isinstance(exc, SystemError) and not _from_ctrl_c(exc):
            raise
        done = tally.finished
        if saved is not None:
            try:
                done = saved()
            except Exception:  # the count is a courtesy; the message must get out
                pass
        raise Interrupted(
            f"{done}/{tally.total} {unit} saved in {output}; rerun the same command to resume"
        ) from None


def _from_ctrl_c(exc: BaseException) -> bool:
    seen = exc.__cause__ or exc.__context__
    while seen is not None:
        if isinstance(seen, KeyboardInterrupt):
            return True
        seen = seen.__cause__ or seen.__context__
    return False


def file_sha(path: str | os.PathLike[str]) -> str:
    """The SHA-256 of a file's content (read in blocks)."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def check_family_inputs(family: str, expected: dict[str, str]) -> None:
    """Refuse to draw an episode of ``family`` when the data it draws from is no longer
    what the run recorded (e.g. ``$COPI_MOVINGAI`` pointed elsewhere on a worker)."""
    from copi.world import family_inputs

    if expected and family_inputs(family) != expected:
        raise ResultsError(
            f"the data the {family} family draws from changed during the run "
            f"({', '.join(sorted(expected))} differs); rerun the same command to be told "
            "how it differs from the stored run"
        )


def code_version() -> str:
    """The version of copi that computes a run's results (part of every run's identity:
    results from another version are another run)."""
    from copi import __version__

    return __version__


class RunIdentity:
    """For a frozen dataclass with ``capabilities`` (a path) and ``capabilities_sha``
    fields, and optionally ``world_file`` and ``world_file_sha``: its identity is
    everything but the paths, the files' content hashes and copi's version included, so
    that a changed input never resumes into results made from the old one."""

    capabilities: str | None
    capabilities_sha: str

    def resolved(self) -> Any:
        """The config with its input files' content hashes (checks the capabilities
        load)."""
        changes: dict[str, Any] = {}
        if self.capabilities is not None:
            Capabilities.load(self.capabilities)
            changes["capabilities_sha"] = file_sha(self.capabilities)
        world_file = getattr(self, "world_file", None)
        if world_file is not None:
            changes["world_file_sha"] = file_sha(world_file)
        elif hasattr(self, "inputs") and hasattr(self, "family"):
            from copi.world import family_inputs

            changes["inputs"] = family_inputs(getattr(self, "family"))  # noqa: B009
        return dataclasses.replace(self, **changes)  # type: ignore[type-var]

    def identity(self) -> dict[str, Any]:
        """What makes two runs the same run (input paths excluded, their contents and
        copi's version included)."""
        d = dataclasses.asdict(self)  # type: ignore[call-overload]
        d.pop("capabilities")
        d.pop("world_file", None)
        d.update(d.pop("inputs", None) or {})  # a family's data, where it draws from any
        d["code"] = code_version()
        return d

    def run_id(self) -> str:
        return hashlib.sha256(json.dumps(self.identity(), sort_keys=True).encode()).hexdigest()[:16]


def execute(
    config: Any,
    items: list[Any],
    *,
    one: Callable[[Any, Any], list[Any]],
    many: Callable[[Any, list[Any]], list[Any]],
    commit: Callable[[list[Any]], None],
    workers: int,
    scheduler: str | None,
    chunk: int,
    stopping: AbstractContextManager[Any],
) -> None:
    """Run every item and hand its results to ``commit`` as they come back: in this
    process one item at a time (``one(config, item)``), or on a local pool or a Dask
    cluster in chunks of at most ``chunk`` (``many(config, items)``, which must pickle).
    On any exception the chunks not started are cancelled; ``stopping`` wraps the whole
    (e.g. the one-line Ctrl-C message)."""
    from copi.experiments.executor import InlineExecutor, make_executor

    with stopping, make_executor(workers, scheduler) as pool:
        if isinstance(pool, InlineExecutor):
            for item in items:
                commit(one(config, item))
            return
        n_workers = workers if scheduler is None else 4
        size = max(1, min(chunk, len(items) // (4 * n_workers)))
        futures = [
            pool.submit(many, config, items[i : i + size]) for i in range(0, len(items), size)
        ]
        try:
            for fut in as_completed(futures):
                commit(fut.result())
        except BaseException:
            for fut in futures:
                fut.cancel()
            raise


def run_into_store(
    config: Any,
    output: str | os.PathLike[str],
    *,
    experiment: str,
    method: str,
    table: str,
    total: int,
    one: Callable[[Any, int], Any],
    many: Callable[[Any, list[int]], list[Any]],
    workers: int,
    scheduler: str | None,
    progress: Callable[[int, int], None] | None,
    chunk: int,
) -> str:
    """Run items 0..total-1 of a resolved ``config`` that are not yet in ``output``,
    committing each as it comes back; returns the run id.

    In-process, one item runs and is committed at a time; with a pool or a Dask cluster,
    items go out in chunks of at most ``chunk`` and are committed as each chunk returns.
    """
    from copi.experiments.store import ResultsStore

    run_id = config.run_id()
    with ResultsStore(output) as store:
        store.begin(run_id, experiment, method, config.identity())
        add = store.add if table == "episodes" else store.add_game
        todo = [k for k in range(total) if k not in store.done(run_id, method, table)]
        tally = Tally(total - len(todo), total)
        if progress is not None:
            progress(tally.finished, total)

        def commit(results: list[Any]) -> None:
            for result in results:
                add(run_id, experiment, method, result)
                tally.finished += 1
            if progress is not None:
                progress(tally.finished, total)

        if not todo:
            return run_id

        def saved() -> int:
            return len(store.done(run_id, method, table))

        execute(
            config, todo, one=lambda c, k: [one(c, k)], many=many, commit=commit,
            workers=workers, scheduler=scheduler, chunk=chunk,
            stopping=stops_cleanly(tally, output, table, saved),
        )  # fmt: skip
    return run_id
