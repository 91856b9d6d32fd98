"""Rows read back from a results store, typed: one frozen dataclass per table.

Each row is read by attribute (``row.success``) and, like :class:`sqlite3.Row`, by
column name (``row["success"]``), so that a table's columns can be listed and copied
(:meth:`Row.items`). NULL reads as None; integer flags read as ``bool``. A store written
by an older copi reads the same: columns it lacks read as None, except the global
strategy, which older stores carried in the method's name or the run's configuration
(see :func:`copi.experiments.methods.split_legacy_name`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

__all__ = ["EpisodeRow", "GameRecord", "LifeRow", "Row", "RunRow"]


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
        return [f.name for f in dataclasses.fields(self)]  # type: ignore[arg-type]

    def items(self) -> Iterator[tuple[str, Any]]:
        for key in self.keys():
            yield key, getattr(self, key)

    def as_dict(self) -> dict[str, Any]:
        return dict(self.items())


@dataclass(frozen=True)
class RunRow(Row):
    """A run: its identity (the configuration that decides its results) and versions."""

    run_id: str
    experiment: str
    method: str
    config: dict[str, Any]
    versions: dict[str, str]
    created: float


@dataclass(frozen=True)
class EpisodeRow(Row):
    """One (run, method, episode) of table ``episodes`` (Experiment 1, the benchmark)."""

    run_id: str
    experiment: str
    method: str
    episode: int
    world: str
    seed: int
    success: bool
    reached: bool
    collided: bool
    timed_out: bool
    steps: int
    contacts: int
    path_length: float | None
    optimal_length: float | None
    excess: float | None
    decision_us: float | None
    strategy_us: float | None
    unfamiliar: float | None
    no_policy: int | None
    family: str | None
    sensing: str | None
    outcome: str | None
    time_to_goal: float | None
    min_clearance: float | None
    smoothness: float | None
    reason: str | None
    strategy: str | None
    """"route" (levels with a map), else the sensor-level strategy."""


@dataclass(frozen=True)
class GameRecord(Row):
    """One game of table ``games`` (Experiment 2)."""

    run_id: str
    experiment: str
    method: str
    game: int
    world: str
    seed: int
    dynamic: bool
    captured: bool
    capture_time: float | None
    survival: float
    contacts: int
    closest: float | None
    gamma: float
    beta: float
    outcome: str | None


@dataclass(frozen=True)
class LifeRow(Row):
    """One task of one life of table ``lifelong`` (Experiment 3)."""

    run_id: str
    experiment: str
    method: str
    world: str
    life: int
    task: int
    seed: int
    family: str
    sensing: str
    outcome: str
    success: bool
    steps: int
    path_length: float | None
    optimal_length: float | None
    excess: float | None
    decision_us: float | None
    unfamiliar: float | None
    grown: int | None
    options: int | None
    strategy: str | None


_BOOLS = {"success", "reached", "collided", "timed_out", "dynamic", "captured"}


def build(cls: type[Row], values: dict[str, Any]) -> Any:
    """A row of ``cls`` from a column -> value mapping (flags as bool)."""
    clean = {k: (bool(v) if k in _BOOLS and v is not None else v) for k, v in values.items()}
    return cls(**clean)
