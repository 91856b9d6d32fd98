"""The rows of a results store, typed: one frozen dataclass per table, the same type
written by a run and read back.

A run builds a row without its run's identity (``run_id``, ``experiment`` and
``method`` are the store's to fill in, :meth:`ResultsStore.add`); a row read back has
them. Each row is read by attribute (``row.success``) and, like :class:`sqlite3.Row`, by
column name (``row["success"]``), so that a table's columns can be listed and copied
(:meth:`Row.items`). Written, NaN stands for no value; read back, NULL reads as None and
integer flags as ``bool``. A store written by an older copi reads the same: columns it
lacks read as None, except the global strategy, which older stores carried in the
method's name or the run's configuration (see :func:`copi.results.split_legacy_name`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

__all__ = ["EpisodeRow", "GameRow", "LifeRow", "Row", "RunRow", "build", "columns"]

_NOT_A_COLUMN = {"column": False}
"""Field metadata of what a row carries beside its table's columns (a trajectory, stored
in table ``trajectories``)."""


class Row:
    """Attribute and column-name access to a dataclass row."""

    def __getitem__(self, key: str) -> Any:
        try:
            return getattr(self, key)
        except AttributeError:
            raise KeyError(key) from None

    def get(self, key: str, default: Any = None) -> Any:
        return getattr(self, key, default)

    def keys(self) -> list[str]:
        """The row's columns (what it carries beside them, a trajectory, left out)."""
        return columns(type(self))

    def items(self) -> Iterator[tuple[str, Any]]:
        for key in self.keys():
            yield key, getattr(self, key)

    def as_dict(self) -> dict[str, Any]:
        return dict(self.items())


def columns(cls: type[Row], *, identity: bool = True) -> list[str]:
    """The columns of ``cls``'s table, in order (``identity=False``: without the run's
    ``run_id``, ``experiment`` and ``method``, which the store writes)."""
    skip = set() if identity else {"run_id", "experiment", "method"}
    return [
        f.name
        for f in dataclasses.fields(cls)  # type: ignore[arg-type]
        if f.metadata.get("column", True) and f.name not in skip
    ]


@dataclass(frozen=True)
class RunRow(Row):
    """A run: its identity (the configuration that decides its results) and versions."""

    run_id: str
    experiment: str
    method: str
    config: dict[str, Any]
    versions: dict[str, str]
    created: float


@dataclass(frozen=True, kw_only=True)
class EpisodeRow(Row):
    """One (run, method, episode) of table ``episodes`` (Experiment 1, the benchmark)."""

    run_id: str = ""
    experiment: str = ""
    method: str = ""
    episode: int
    world: str
    seed: int
    success: bool
    """Reached the goal within the step limit without touching a moving obstacle."""
    reached: bool
    collided: bool
    """Touched a moving obstacle (exclusive of success and timeout)."""
    timed_out: bool
    """Neither reached the goal nor touched anything within the step limit."""
    steps: int
    contacts: int
    """Steps with a contact (at most 1 when contacts end episodes)."""
    path_length: float | None
    optimal_length: float | None
    """Lower bound (within 0.12 %) on the shortest path to the goal's tolerance disc on
    the snapshot at t = 0 with obstacles frozen (NaN, or None read back: none)."""
    excess: float | None
    """path_length / optimal_length - 1 on success (>= 0), else no value."""
    decision_us: float | None
    """Mean wall time of one decision (global direction and local choice), µs."""
    strategy_us: float | None
    """Kept for older readers: 0 (the decision time includes the global direction)."""
    unfamiliar: float | None
    """Share of this episode's decisions whose reading was unfamiliar (copi's modes)."""
    no_policy: int | None
    """Steps at which the method commanded no motion."""
    family: str | None = "star"
    sensing: str | None = "map"
    outcome: str | None = "timeout"
    """success, collision or timeout (exclusive); "skipped" when the episode's world has
    no valid task (then ``reason`` says why, and the episode counts in no rate)."""
    time_to_goal: float | None = math.nan
    """Steps to the goal on success."""
    min_clearance: float | None = math.nan
    """Least surface distance to a moving obstacle over the episode."""
    smoothness: float | None = math.nan
    """Sum of turning angles between consecutive moves, radians."""
    reason: str | None = None
    """Why an episode was skipped (None otherwise)."""
    strategy: str | None = "route"
    """"route" (levels with a map), else the sensor-level strategy."""
    close_steps: int | None = None
    """Steps closer to a moving obstacle than the family's discomfort distance (CrowdNav's
    scenarios; no value for a family that has none)."""
    trajectory: dict[str, Any] | None = field(default=None, metadata=_NOT_A_COLUMN)
    """For recorded episodes: world, path, obstacle traces and radii (JSON-able); stored
    in table ``trajectories``, never read back with the row."""


@dataclass(frozen=True, kw_only=True)
class GameRow(Row):
    """One game of table ``games`` (Experiment 2)."""

    run_id: str = ""
    experiment: str = ""
    method: str = ""
    game: int
    world: str
    seed: int
    dynamic: bool
    captured: bool
    capture_time: float | None
    """Time of capture (no value when the evader survived)."""
    survival: float
    """Capture time, or the horizon."""
    contacts: int
    """Steps at which the evader touched a moving obstacle."""
    closest: float | None
    gamma: float
    beta: float
    outcome: str | None = "escaped"
    """"captured", "collision" (touched a moving obstacle first; ends the game when
    contacts end games) or "escaped" (survived the horizon). Exclusive."""
    trajectory: dict[str, Any] | None = field(default=None, metadata=_NOT_A_COLUMN)
    """For recorded games: world, both paths, obstacle traces (JSON-able)."""


@dataclass(frozen=True, kw_only=True)
class LifeRow(Row):
    """One task of one life of table ``lifelong`` (Experiment 3)."""

    run_id: str = ""
    experiment: str = ""
    method: str = ""
    world: str
    life: int
    task: int
    seed: int
    family: str
    sensing: str
    outcome: str
    """success, collision or timeout; "skipped" when the world has no valid chain of
    tasks (the life's rows then count in no rate)."""
    success: bool
    steps: int
    path_length: float | None
    optimal_length: float | None
    excess: float | None
    decision_us: float | None
    unfamiliar: float | None
    grown: int | None
    """Context nodes grown so far in this life (continual methods)."""
    options: int | None
    """Options recorded in the causal map so far in this life (causal methods)."""
    strategy: str | None = "route"
    """The arm's global strategy ("route" at level map)."""


_BOOLS = {"success", "reached", "collided", "timed_out", "dynamic", "captured"}


def build(cls: type[Row], values: dict[str, Any]) -> Any:
    """A row of ``cls`` from a column -> value mapping (flags as bool)."""
    clean = {k: (bool(v) if k in _BOOLS and v is not None else v) for k, v in values.items()}
    return cls(**clean)
