"""The results store: one SQLite file per run (DESIGN.md, "Results store").

Table ``runs`` records each run's parameters and versions; ``episodes`` holds one row per
(run, method, episode), inserted and committed as each episode ends (``games``
likewise for Experiment 2), so that an
interrupted run (Ctrl-C, kill -9) resumes where it stopped: SQLite's transactions make
each row all-or-nothing, and the primary key makes a row impossible to write twice.
``trajectories`` keeps the paths of a few episodes for the figures, as JSON.
"""

from __future__ import annotations

import json
import math
import os
import platform
import sqlite3
import time
from collections.abc import Iterable
from dataclasses import asdict
from pathlib import Path
from typing import Any

from copi.errors import CopiError

__all__ = ["ResultsError", "ResultsStore"]

SCHEMA = """
CREATE TABLE IF NOT EXISTS runs (
    run_id TEXT PRIMARY KEY,
    experiment TEXT NOT NULL,
    method TEXT NOT NULL,
    config TEXT NOT NULL,
    versions TEXT NOT NULL,
    created REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS episodes (
    run_id TEXT NOT NULL,
    experiment TEXT NOT NULL,
    method TEXT NOT NULL,
    world TEXT NOT NULL,
    episode INTEGER NOT NULL,
    seed INTEGER NOT NULL,
    success INTEGER NOT NULL,
    reached INTEGER NOT NULL,
    collided INTEGER NOT NULL,
    timed_out INTEGER NOT NULL,
    steps INTEGER NOT NULL,
    contacts INTEGER NOT NULL,
    path_length REAL,
    optimal_length REAL,
    excess REAL,
    decision_us REAL,
    strategy_us REAL,
    unfamiliar REAL,
    no_policy INTEGER,
    family TEXT,
    sensing TEXT,
    outcome TEXT,
    time_to_goal REAL,
    min_clearance REAL,
    smoothness REAL,
    PRIMARY KEY (run_id, method, episode)
);
CREATE TABLE IF NOT EXISTS games (
    run_id TEXT NOT NULL,
    experiment TEXT NOT NULL,
    method TEXT NOT NULL,
    world TEXT NOT NULL,
    game INTEGER NOT NULL,
    seed INTEGER NOT NULL,
    dynamic INTEGER NOT NULL,
    captured INTEGER NOT NULL,
    capture_time REAL,
    survival REAL NOT NULL,
    contacts INTEGER NOT NULL,
    closest REAL,
    gamma REAL NOT NULL,
    beta REAL NOT NULL,
    outcome TEXT,
    PRIMARY KEY (run_id, method, game)
);
CREATE TABLE IF NOT EXISTS trajectories (
    run_id TEXT NOT NULL,
    method TEXT NOT NULL,
    episode INTEGER NOT NULL,
    data TEXT NOT NULL,
    PRIMARY KEY (run_id, method, episode)
);
"""

GAME_COLUMNS = [
    "game", "world", "seed", "dynamic", "captured", "capture_time", "survival", "contacts",
    "closest", "gamma", "beta", "outcome",
]  # fmt: skip

EPISODE_COLUMNS = [
    "episode", "world", "seed", "success", "reached", "collided", "timed_out", "steps",
    "contacts", "path_length", "optimal_length", "excess", "decision_us", "strategy_us",
    "unfamiliar", "no_policy", "family", "sensing", "outcome", "time_to_goal",
    "min_clearance", "smoothness",
]  # fmt: skip

# Columns added after the first format, with their SQL types: older stores gain them
# (NULL in their old rows) when opened for writing.
_ADDED_EPISODE_COLUMNS = {
    "family": "TEXT", "sensing": "TEXT", "outcome": "TEXT", "time_to_goal": "REAL",
    "min_clearance": "REAL", "smoothness": "REAL",
}  # fmt: skip


class ResultsError(CopiError):
    """A results file is not a copi results store, or holds a different run."""


def _versions() -> dict[str, str]:
    import numba
    import numpy
    import shapely

    from copi import __version__

    return {
        "copi": __version__,
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "numba": numba.__version__,
        "shapely": shapely.__version__,
    }


def _real(x: Any) -> Any:
    """NaN and inf as NULL (SQLite has no NaN); other values unchanged."""
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


class ResultsStore:
    """A results file. Opening checks that an existing file is one of copi's."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        existed = self.path.exists()
        if existed and self.path.is_dir():
            raise ResultsError(f"{self.path}: is a directory, expected a results file")
        if existed:
            with open(self.path, "rb") as fh:
                head = fh.read(16)
            if head and head != b"SQLite format 3\x00":
                raise ResultsError(f"{self.path}: not a copi results file (not SQLite)")
        try:
            self.db = sqlite3.connect(self.path, timeout=30)
            tables = {
                r[0] for r in self.db.execute("SELECT name FROM sqlite_master WHERE type='table'")
            }
        except sqlite3.DatabaseError as exc:
            raise ResultsError(f"{self.path}: not a readable results file ({exc})") from None
        if existed and tables and not {"runs", "episodes"} <= tables:
            self.db.close()
            raise ResultsError(f"{self.path}: an SQLite file, but not a copi results store")
        self.db.executescript(SCHEMA)
        have = {r[1] for r in self.db.execute("PRAGMA table_info(episodes)")}
        for column, kind in _ADDED_EPISODE_COLUMNS.items():
            if column not in have:
                self.db.execute(f"ALTER TABLE episodes ADD COLUMN {column} {kind}")
        if "outcome" not in {r[1] for r in self.db.execute("PRAGMA table_info(games)")}:
            self.db.execute("ALTER TABLE games ADD COLUMN outcome TEXT")
        self.db.commit()

    def close(self) -> None:
        self.db.close()

    def __enter__(self) -> ResultsStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- runs -------------------------------------------------------------------------

    def begin(self, run_id: str, experiment: str, method: str, config: dict[str, Any]) -> None:
        """Register a run, or resume it. A different configuration under the same method
        label (and, where the configuration names them, the same family and sensing level)
        is refused (nothing in the file is changed)."""
        rows = self.db.execute(
            "SELECT run_id, config FROM runs WHERE experiment = ? AND method = ?",
            (experiment, method),
        ).fetchall()
        for rid, text in rows:
            if rid == run_id:
                return
            other = json.loads(text)
            if any(other.get(k) != config.get(k) for k in ("family", "sensing")):
                continue
            diff = sorted(k for k in set(other) | set(config) if other.get(k) != config.get(k))
            shown = ", ".join(
                f"{k}: {other.get(k)!r} there, {config.get(k)!r} now" for k in diff[:3]
            )
            raise ResultsError(
                f"{self.path} already holds a {experiment} run of method {method!r} with a "
                f"different configuration ({shown}); use another output file or method label"
            )
        self.db.execute(
            "INSERT INTO runs VALUES (?, ?, ?, ?, ?, ?)",
            (
                run_id,
                experiment,
                method,
                json.dumps(config, sort_keys=True),
                json.dumps(_versions()),
                time.time(),
            ),
        )
        self.db.commit()

    def done(self, run_id: str, method: str, table: str = "episodes") -> set[int]:
        """Episodes (or games, with ``table="games"``) of the run already stored."""
        key = {"episodes": "episode", "games": "game"}[table]
        rows = self.db.execute(
            f"SELECT {key} FROM {table} WHERE run_id = ? AND method = ?", (run_id, method)
        )
        return {int(r[0]) for r in rows}

    def add(self, run_id: str, experiment: str, method: str, result: Any) -> None:
        """Store one episode (and its trajectory, if recorded) and commit."""
        self._insert(
            "episodes", EPISODE_COLUMNS, run_id, experiment, method, result, result.episode
        )

    def add_game(self, run_id: str, experiment: str, method: str, result: Any) -> None:
        """Store one game (and its trajectory, if recorded) and commit."""
        self._insert("games", GAME_COLUMNS, run_id, experiment, method, result, result.game)

    def _insert(
        self,
        table: str,
        columns: list[str],
        run_id: str,
        experiment: str,
        method: str,
        result: Any,
        key: int,
    ) -> None:
        row = asdict(result)
        trajectory = row.pop("trajectory", None)
        values = [int(row[c]) if isinstance(row[c], bool) else _real(row[c]) for c in columns]
        names = ", ".join(columns)
        marks = ", ".join("?" * len(columns))
        with self.db:  # one transaction: the row and its trajectory, or nothing
            self.db.execute(
                f"INSERT OR IGNORE INTO {table} (run_id, experiment, method, {names}) "
                f"VALUES (?, ?, ?, {marks})",
                [run_id, experiment, method, *values],
            )
            if trajectory is not None:
                self.db.execute(
                    "INSERT OR IGNORE INTO trajectories VALUES (?, ?, ?, ?)",
                    (run_id, method, key, json.dumps(trajectory)),
                )

    # -- reading back -----------------------------------------------------------------

    def runs(self) -> list[dict[str, Any]]:
        cur = self.db.execute(
            "SELECT run_id, experiment, method, config, versions, created FROM runs"
        )
        return [
            {"run_id": r[0], "experiment": r[1], "method": r[2], "config": json.loads(r[3]),
             "versions": json.loads(r[4]), "created": r[5]}
            for r in cur
        ]  # fmt: skip

    def episodes(self, run_id: str | None = None) -> list[dict[str, Any]]:
        cols = ["run_id", "experiment", "method", *EPISODE_COLUMNS]
        q = f"SELECT {', '.join(cols)} FROM episodes"
        args: Iterable[Any] = ()
        if run_id is not None:
            q += " WHERE run_id = ?"
            args = (run_id,)
        return [
            dict(zip(cols, r, strict=True))
            for r in self.db.execute(q + " ORDER BY method, episode", tuple(args))
        ]

    def games(self, run_id: str | None = None) -> list[dict[str, Any]]:
        cols = ["run_id", "experiment", "method", *GAME_COLUMNS]
        q = f"SELECT {', '.join(cols)} FROM games"
        args: tuple[Any, ...] = ()
        if run_id is not None:
            q += " WHERE run_id = ?"
            args = (run_id,)
        return [
            dict(zip(cols, r, strict=True))
            for r in self.db.execute(q + " ORDER BY method, game", args)
        ]

    def trajectories(self, run_id: str, method: str) -> list[dict[str, Any]]:
        cur = self.db.execute(
            "SELECT episode, data FROM trajectories WHERE run_id = ? AND method = ? "
            "ORDER BY episode",
            (run_id, method),
        )
        return [{"episode": r[0], **json.loads(r[1])} for r in cur]
