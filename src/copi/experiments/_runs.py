"""What Experiment 1 and 2 runs share: identity from their configuration, and running
their independent, seeded items (episodes, games) into a results store."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from collections.abc import Callable
from concurrent.futures import as_completed
from typing import Any

from copi.learning import Capabilities

__all__ = ["RunIdentity", "run_into_store"]


class RunIdentity:
    """For a frozen dataclass with ``capabilities`` (a path) and ``capabilities_sha``
    fields: its identity is everything but the path, the file's content hash included."""

    capabilities: str | None
    capabilities_sha: str

    def resolved(self) -> Any:
        """The config with the capabilities' content hash (checks the file loads)."""
        if self.capabilities is None:
            return self
        Capabilities.load(self.capabilities)
        with open(self.capabilities, "rb") as fh:
            sha = hashlib.sha256(fh.read()).hexdigest()
        return dataclasses.replace(self, capabilities_sha=sha)  # type: ignore[type-var]

    def identity(self) -> dict[str, Any]:
        """What makes two runs the same run (the capabilities' path excluded)."""
        d = dataclasses.asdict(self)  # type: ignore[call-overload]
        d.pop("capabilities")
        return d

    def run_id(self) -> str:
        return hashlib.sha256(json.dumps(self.identity(), sort_keys=True).encode()).hexdigest()[:16]


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
    from copi.experiments.executor import InlineExecutor, make_executor
    from copi.experiments.store import ResultsStore

    run_id = config.run_id()
    with ResultsStore(output) as store:
        store.begin(run_id, experiment, method, config.identity())
        add = store.add if table == "episodes" else store.add_game
        todo = [k for k in range(total) if k not in store.done(run_id, method, table)]
        finished = total - len(todo)
        if progress is not None:
            progress(finished, total)

        def commit(results: list[Any]) -> None:
            nonlocal finished
            for result in results:
                add(run_id, experiment, method, result)
                finished += 1
            if progress is not None:
                progress(finished, total)

        if not todo:
            return run_id
        with make_executor(workers, scheduler) as pool:
            if isinstance(pool, InlineExecutor):
                for k in todo:
                    commit([one(config, k)])
                return run_id
            n_workers = workers if scheduler is None else 4
            size = max(1, min(chunk, len(todo) // (4 * n_workers)))
            futures = [
                pool.submit(many, config, todo[i : i + size]) for i in range(0, len(todo), size)
            ]
            try:
                for fut in as_completed(futures):
                    commit(fut.result())
            except BaseException:
                for f in futures:
                    f.cancel()
                raise
    return run_id
