"""The results store: one SQLite file per run (docs/design.md, "Results store").

Table ``runs`` records each run's parameters and versions; ``episodes`` holds one row per
(run, method, episode), inserted and committed as each episode ends (``games``
likewise for Experiment 2, ``lifelong`` one life at a time for Experiment 3), so that an
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
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import asdict
from pathlib import Path
from typing import Any
from urllib.parse import quote

from copi.errors import ResultsError
from copi.results._legacy import split_legacy_name
from copi.results._rows import EpisodeRow, GameRow, LifeRow, RunRow, build, columns

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
    reason TEXT,
    strategy TEXT,
    close_steps INTEGER,
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
CREATE TABLE IF NOT EXISTS lifelong (
    run_id TEXT NOT NULL,
    experiment TEXT NOT NULL,
    method TEXT NOT NULL,
    world TEXT NOT NULL,
    life INTEGER NOT NULL,
    task INTEGER NOT NULL,
    seed INTEGER NOT NULL,
    family TEXT NOT NULL,
    sensing TEXT NOT NULL,
    outcome TEXT NOT NULL,
    success INTEGER NOT NULL,
    steps INTEGER NOT NULL,
    path_length REAL,
    optimal_length REAL,
    excess REAL,
    decision_us REAL,
    unfamiliar REAL,
    grown INTEGER,
    options INTEGER,
    strategy TEXT,
    PRIMARY KEY (run_id, method, life, task)
);
CREATE TABLE IF NOT EXISTS trajectories (
    run_id TEXT NOT NULL,
    method TEXT NOT NULL,
    episode INTEGER NOT NULL,
    data TEXT NOT NULL,
    PRIMARY KEY (run_id, method, episode)
);
"""

EPISODE_COLUMNS = columns(EpisodeRow, identity=False)
GAME_COLUMNS = columns(GameRow, identity=False)
LIFELONG_COLUMNS = columns(LifeRow, identity=False)

# Columns added after the first format, with their SQL types: older stores gain them
# (NULL in their old rows) when opened for writing.
_ADDED_EPISODE_COLUMNS = {
    "family": "TEXT", "sensing": "TEXT", "outcome": "TEXT", "time_to_goal": "REAL",
    "min_clearance": "REAL", "smoothness": "REAL", "reason": "TEXT", "strategy": "TEXT",
    "close_steps": "INTEGER",
}  # fmt: skip


APPLICATION_ID = 0x636F7069  # "copi": SQLite's header field for the file's owner
STORE_VERSION = 1  # PRAGMA user_version of the format above

_COPI_TABLES = {"runs", "episodes", "games", "lifelong", "trajectories"}
_RUN_COLUMNS = {"run_id", "experiment", "method", "config", "versions", "created"}
_FIRST_EPISODE_COLUMNS = {
    "run_id", "experiment", "method", "world", "episode", "seed", "success", "collided",
    "timed_out", "steps", "path_length", "optimal_length", "excess",
}  # fmt: skip


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


def _sqlite_message(exc: sqlite3.Error) -> str:
    text = str(exc)
    if "disk is full" in text or "disk I/O" in text:
        return f"cannot write ({text}): free some space and rerun the same command to resume"
    if "readonly" in text or "read-only" in text:
        return f"cannot write ({text}): the file or its directory is read-only"
    if "malformed" in text or "not a database" in text:
        return f"corrupted results file ({text})"
    if "locked" in text or "busy" in text:
        return f"the file is locked by another process ({text})"
    return text


class ResultsStore:
    """A results file. Opening checks that an existing file is one of copi's.

    A file is written only if it is new (absent or empty) or already a copi store, as
    its SQLite header says (``application_id`` "copi"); a store written before that
    mark existed is recognised by its tables and columns (only copi's, with runs and
    episodes as copi writes them) and marked when opened for writing. With
    ``readonly=True`` (reading back, e.g. for a report) the file is never changed.
    """

    def __init__(self, path: str | os.PathLike[str], *, readonly: bool = False) -> None:
        self.path = Path(path)
        self.readonly = readonly
        existed = self.path.exists()
        if existed and self.path.is_dir():
            raise ResultsError(f"{self.path}: is a directory, expected a results file")
        size = self.path.stat().st_size if existed else 0
        if readonly and not existed:
            raise ResultsError(f"{self.path}: no such results file")
        if readonly and size == 0:
            raise ResultsError(f"{self.path}: an empty file, not a copi results store")
        if size:
            try:
                with open(self.path, "rb") as fh:
                    head = fh.read(100)
            except OSError as exc:
                raise ResultsError(f"{self.path}: cannot read ({exc.strerror})") from None
            if not head.startswith(b"SQLite format 3\x00"):
                raise ResultsError(f"{self.path}: not a copi results file (not SQLite)")
            if len(head) < 100:
                raise ResultsError(f"{self.path}: a truncated SQLite file")
            app_id = int.from_bytes(head[68:72], "big")
            if app_id not in (0, APPLICATION_ID):
                raise ResultsError(
                    f"{self.path}: an SQLite file of another application "
                    f"(application_id {app_id:#x}), not a copi results store"
                )
        try:
            if readonly:
                uri = "file:" + quote(str(self.path.resolve())) + "?mode=ro"
                self.db = sqlite3.connect(uri, uri=True, timeout=30)
            else:
                self.db = sqlite3.connect(self.path, timeout=30, isolation_level=None)
        except sqlite3.Error as exc:
            raise ResultsError(f"{self.path}: cannot open ({_sqlite_message(exc)})") from None
        try:
            if readonly:
                self._check_format()
            else:
                with self._transaction():
                    if not self._check_format():
                        self._create()
        except sqlite3.Error as exc:
            self.db.close()
            raise ResultsError(f"{self.path}: {_sqlite_message(exc)}") from None
        except ResultsError:
            self.db.close()
            raise

    def _check_format(self) -> bool:
        """Whether the file holds copi's tables (raises when it holds anything else)."""
        app_id = self.db.execute("PRAGMA application_id").fetchone()[0]
        version = self.db.execute("PRAGMA user_version").fetchone()[0]
        tables = {
            r[0] for r in self.db.execute("SELECT name FROM sqlite_master WHERE type='table'")
        }
        if app_id == APPLICATION_ID:
            if version > STORE_VERSION:
                raise ResultsError(
                    f"{self.path}: written by a newer copi (store format {version}); "
                    f"this copi reads formats up to {STORE_VERSION}: upgrade copi"
                )
            if not self.readonly and not tables >= _COPI_TABLES:
                self._create()  # tables added since the file was written (e.g. lifelong)
            return True
        if not tables:
            if self.readonly:
                raise ResultsError(f"{self.path}: an empty SQLite file, not a copi results store")
            return False
        runs = {r[1] for r in self.db.execute("PRAGMA table_info(runs)")}
        episodes = {r[1] for r in self.db.execute("PRAGMA table_info(episodes)")}
        if (
            not tables <= _COPI_TABLES
            or not _RUN_COLUMNS <= runs
            or not _FIRST_EPISODE_COLUMNS <= episodes
        ):
            raise ResultsError(
                f"{self.path}: an SQLite file, but not a copi results store (tables "
                f"{', '.join(sorted(tables))}); nothing was changed"
            )
        # A store from before the format mark: adopted, and marked when written.
        if not self.readonly:
            self._create()
        return True

    def _create(self) -> None:
        """Create (or complete) copi's tables and mark the file as a copi store."""
        for statement in SCHEMA.split(";"):
            if statement.strip():
                self.db.execute(statement)
        have = {r[1] for r in self.db.execute("PRAGMA table_info(episodes)")}
        for column, kind in _ADDED_EPISODE_COLUMNS.items():
            if column not in have:
                self.db.execute(f"ALTER TABLE episodes ADD COLUMN {column} {kind}")
        if "outcome" not in {r[1] for r in self.db.execute("PRAGMA table_info(games)")}:
            self.db.execute("ALTER TABLE games ADD COLUMN outcome TEXT")
        if "strategy" not in {r[1] for r in self.db.execute("PRAGMA table_info(lifelong)")}:
            self.db.execute("ALTER TABLE lifelong ADD COLUMN strategy TEXT")
        self.db.execute(f"PRAGMA application_id = {APPLICATION_ID}")
        self.db.execute(f"PRAGMA user_version = {STORE_VERSION}")

    @contextmanager
    def _transaction(self) -> Iterator[None]:
        """One write transaction, taken at once (BEGIN IMMEDIATE), so that two processes
        starting on the same file never both see it without a run and both add it."""
        self.db.execute("BEGIN IMMEDIATE")
        try:
            yield
        except BaseException:
            if self.db.in_transaction:  # SQLite may have rolled back already (disk full)
                self.db.execute("ROLLBACK")
            raise
        self.db.execute("COMMIT")

    @contextmanager
    def _errors(self) -> Iterator[None]:
        """SQLite's errors (disk full, read-only, corrupted, locked) as one-line
        ResultsErrors naming the file."""
        try:
            yield
        except sqlite3.Error as exc:
            raise ResultsError(f"{self.path}: {_sqlite_message(exc)}") from None

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
        self._writable()
        with self._errors(), self._transaction():
            rows = self.db.execute(
                "SELECT run_id, config FROM runs WHERE experiment = ? AND method = ?",
                (experiment, method),
            ).fetchall()
            for rid, text in rows:
                if rid == run_id:
                    return
                other = _config_of(self.path, text)
                # runs of the method on other worlds, levels or strategies are other runs
                if any(other.get(k) != config.get(k) for k in _SERIES_KEYS):
                    continue
                if not self._holds_rows(rid):
                    # a run that stopped before its first result (a method or a sampler
                    # that broke at once): nothing of it to mix with, so it makes way
                    self.db.execute("DELETE FROM runs WHERE run_id = ?", (rid,))
                    continue
                raise ResultsError(_difference(self.path, experiment, method, other, config))
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

    def _holds_rows(self, run_id: str) -> bool:
        """Whether any result of the run is stored (an episode, a game, a life)."""
        for table in ("episodes", "games", "lifelong", "trajectories"):
            if table == "lifelong" and not self._has_table("lifelong"):
                continue
            if self.db.execute(f"SELECT 1 FROM {table} WHERE run_id = ? LIMIT 1",
                               (run_id,)).fetchone():  # fmt: skip
                return True
        return False

    def _writable(self) -> None:
        if self.readonly:
            raise ResultsError(f"{self.path}: opened read-only")

    def done(self, run_id: str, method: str, table: str = "episodes") -> set[int]:
        """Episodes (or games, with ``table="games"``) of the run already stored."""
        key = {"episodes": "episode", "games": "game", "lifelong": "life"}[table]
        if table == "lifelong" and not self._has_table("lifelong"):
            return set()
        with self._errors():
            rows = self.db.execute(
                f"SELECT {key} FROM {table} WHERE run_id = ? AND method = ?", (run_id, method)
            ).fetchall()
        return {int(r[0]) for r in rows}

    def add(self, run_id: str, experiment: str, method: str, result: EpisodeRow) -> None:
        """Store one episode (and its trajectory, if recorded) and commit."""
        self._insert(
            "episodes", EPISODE_COLUMNS, run_id, experiment, method, result, result.episode
        )

    def add_game(self, run_id: str, experiment: str, method: str, result: GameRow) -> None:
        """Store one game (and its trajectory, if recorded) and commit."""
        self._insert("games", GAME_COLUMNS, run_id, experiment, method, result, result.game)

    def add_life(self, run_id: str, experiment: str, method: str, rows: list[LifeRow]) -> None:
        """Store one life's tasks (Experiment 3) in one transaction: a life is resumed
        whole or not at all."""
        names = ", ".join(LIFELONG_COLUMNS)
        marks = ", ".join("?" * len(LIFELONG_COLUMNS))
        self._writable()
        with self._errors(), self._transaction():
            for result in rows:
                row = asdict(result)
                values = [
                    int(row[c]) if isinstance(row[c], bool) else _real(row[c])
                    for c in LIFELONG_COLUMNS
                ]
                self.db.execute(
                    f"INSERT OR IGNORE INTO lifelong (run_id, experiment, method, {names}) "
                    f"VALUES (?, ?, ?, {marks})",
                    [run_id, experiment, method, *values],
                )

    def _has_table(self, table: str) -> bool:
        with self._errors():
            row = self.db.execute(
                "SELECT 1 FROM sqlite_master WHERE type='table' AND name = ?", (table,)
            ).fetchone()
        return row is not None

    def lifelong(self, run_id: str | None = None) -> list[LifeRow]:
        """Rows of Experiment 3 (none in a store written before it existed). Rows of an
        older store, whose method labels carried the level and strategy
        (``dwa+mapping``), read with them apart."""
        if not self._has_table("lifelong"):
            return []
        cols = ["run_id", "experiment", "method", *LIFELONG_COLUMNS]
        out = []
        for d in self._rows("lifelong", cols, run_id, "method, life, task"):
            if d["strategy"] is None:
                method, _, strategy = split_legacy_name(d["method"])
                d["method"] = method
                d["strategy"] = strategy or ("route" if d["sensing"] != "sensor" else "greedy")
            out.append(build(LifeRow, d))
        return out

    def _rows(
        self, table: str, cols: list[str], run_id: str | None, order: str
    ) -> list[dict[str, Any]]:
        q = f"SELECT {self._select(table, cols)} FROM {table}"
        args: tuple[Any, ...] = ()
        if run_id is not None:
            q += " WHERE run_id = ?"
            args = (run_id,)
        with self._errors():
            rows = self.db.execute(f"{q} ORDER BY {order}", args).fetchall()
        return [dict(zip(cols, r, strict=True)) for r in rows]

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
        self._writable()
        # one transaction: the row and its trajectory, or nothing
        with self._errors(), self._transaction():
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

    def runs(self) -> list[RunRow]:
        """Every run of the store, in the order they were registered."""
        with self._errors():
            cur = self.db.execute(
                "SELECT run_id, experiment, method, config, versions, created FROM runs "
                "ORDER BY rowid"
            ).fetchall()
        return [
            RunRow(run_id=r[0], experiment=r[1], method=r[2],
                   config=_config_of(self.path, r[3]),
                   versions=_config_of(self.path, r[4], "a run's stored versions"),
                   created=r[5])
            for r in cur
        ]  # fmt: skip

    def _select(self, table: str, cols: list[str]) -> str:
        """The column list of a SELECT: columns a store written by an earlier copi lacks
        (it is read as it is, not migrated) read as NULL."""
        with self._errors():
            have = {r[1] for r in self.db.execute(f"PRAGMA table_info({table})")}
        return ", ".join(c if c in have else f"NULL AS {c}" for c in cols)

    def episodes(self, run_id: str | None = None) -> list[EpisodeRow]:
        """Episodes of one run (or of all), by method and episode. Rows of an older
        store without the strategy column read with the strategy its run used."""
        cols = ["run_id", "experiment", "method", *EPISODE_COLUMNS]
        rows = self._rows("episodes", cols, run_id, "method, episode")
        configs: dict[str, dict[str, Any]] | None = None
        out = []
        for d in rows:
            if d["strategy"] is None:
                if configs is None:
                    configs = {r.run_id: r.config for r in self.runs()}
                if d["sensing"] in ("map", "oracle"):
                    d["strategy"] = "route"
                else:
                    cfg = configs.get(d["run_id"], {})
                    d["strategy"] = cfg.get("strategy", cfg.get("sensor_strategy", "greedy"))
            d["method"] = split_legacy_name(d["method"])[0]
            out.append(build(EpisodeRow, d))
        return out

    def games(self, run_id: str | None = None) -> list[GameRow]:
        """Games of one run (or of all), by method and game."""
        cols = ["run_id", "experiment", "method", *GAME_COLUMNS]
        return [build(GameRow, d) for d in self._rows("games", cols, run_id, "method, game")]

    def trajectories(self, run_id: str, method: str) -> list[dict[str, Any]]:
        with self._errors():
            cur = self.db.execute(
                "SELECT episode, data FROM trajectories WHERE run_id = ? AND method = ? "
                "ORDER BY episode",
                (run_id, method),
            ).fetchall()
        return [{"episode": r[0], **_config_of(self.path, r[1], "a stored trajectory")}
                for r in cur]  # fmt: skip


def _config_of(path: Path, text: Any, what: str = "a run's stored configuration") -> dict[
    str, Any
]:
    """A JSON object the store keeps (a run's configuration, its versions, a trajectory),
    or one clear error when it is not one."""
    try:
        config = json.loads(text)
    except (TypeError, ValueError, RecursionError) as exc:  # junk, 5000-digit numbers
        raise ResultsError(f"{path}: {what} is not JSON ({type(exc).__name__}); the file "
                           "is damaged") from None  # fmt: skip
    if not isinstance(config, dict):
        raise ResultsError(f"{path}: {what} is not a JSON object (found "
                           f"{type(config).__name__}); the file is damaged")  # fmt: skip
    return config


_SERIES_KEYS = ("family", "sensing", "strategy")
"""Keys of a run's identity that make it another series of the same method (not a
conflicting configuration of the same one)."""

# Keys of a run's identity that stand for an input's content, in words.
_INPUTS = {
    "capabilities_sha": "the capabilities file's content",
    "world_file_sha": "the world file's content",
    "code": "copi's version",
    "maps_sha": "the maps family's map set",
}


def _difference(
    path: Path, experiment: str, method: str, other: dict[str, Any], config: dict[str, Any]
) -> str:
    """One line saying how a run's configuration differs from the one already stored."""
    diff = sorted(k for k in set(other) | set(config) if other.get(k) != config.get(k))
    for kind in ("method", "family"):
        if f"{kind}_origin" in diff or f"{kind}_code" in diff:
            name = method if kind == "method" else config.get("family", "?")
            there = other.get(f"{kind}_origin") or "copi's own"
            now = config.get(f"{kind}_origin") or "copi's own"
            how = f"from {there} there, from {now} now" if there != now else (
                f"from {now}, whose code changed since")  # fmt: skip
            return (
                f"{path} holds a {experiment} run of {kind} {name!r} {how}: write to another "
                "output file (a run of one never resumes into the other's)"
            )
    changed = [_INPUTS[k] for k in diff if k in _INPUTS and other.get(k) and config.get(k)]
    if changed and len(changed) == len(diff):
        return (
            f"{path} holds a {experiment} run of method {method!r} made with other inputs: "
            f"{' and '.join(changed)} changed since; write to another output file"
        )
    shown = ", ".join(f"{k}: {other.get(k)!r} there, {config.get(k)!r} now" for k in diff[:3])
    return (
        f"{path} already holds a {experiment} run of method {method!r} with a "
        f"different configuration ({shown}); write to another output file"
    )
