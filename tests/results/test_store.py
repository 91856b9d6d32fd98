"""The results store refuses what is not its own, never changes a file it only reads,
and turns SQLite's failures into one-line errors (issue 14)."""

from __future__ import annotations

import math
import multiprocessing
import os
import sqlite3
from pathlib import Path

import pytest

from copi.experiments.navigation import EpisodeRow
from copi.results import ResultsError, ResultsStore
from copi.results._store import APPLICATION_ID


def _row(k: int) -> EpisodeRow:
    return EpisodeRow(
        episode=k, world="w", seed=0, success=True, reached=True, collided=False,
        timed_out=False, steps=10, contacts=0, path_length=9.5, optimal_length=9.0,
        excess=0.5 / 9.0, decision_us=3.0, strategy_us=0.0, unfamiliar=0.0, no_policy=0,
        outcome="success", time_to_goal=10.0, min_clearance=math.inf, smoothness=0.1,
    )  # fmt: skip


def _store_with_rows(path: Path, n: int = 3) -> None:
    with ResultsStore(path) as store:
        store.begin("r1", "navigation", "m", {"seed": 0})
        for k in range(n):
            store.add("r1", "navigation", "m", _row(k))


def test_a_new_store_is_marked_as_copi_s(tmp_path: Path) -> None:
    path = tmp_path / "r.sqlite"
    _store_with_rows(path)
    with sqlite3.connect(path) as db:
        assert db.execute("PRAGMA application_id").fetchone()[0] == APPLICATION_ID
    with ResultsStore(path, readonly=True) as store:
        assert [r["episode"] for r in store.episodes()] == [0, 1, 2]


@pytest.mark.parametrize(
    "schema",
    [
        "CREATE TABLE runs (a); CREATE TABLE episodes (b)",  # the same names, other columns
        "CREATE TABLE t (x)",
    ],
)
def test_a_foreign_sqlite_file_is_refused_and_left_unchanged(tmp_path: Path, schema: str) -> None:
    path = tmp_path / "foreign.sqlite"
    with sqlite3.connect(path) as db:
        db.executescript(schema)
    before = path.read_bytes()
    with pytest.raises(ResultsError, match="not a copi results store"):
        ResultsStore(path)
    with pytest.raises(ResultsError, match="not a copi results store"):
        ResultsStore(path, readonly=True)
    assert path.read_bytes() == before


def test_another_application_s_sqlite_file_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "other.sqlite"
    with sqlite3.connect(path) as db:
        db.execute("PRAGMA application_id = 42")
        db.execute("CREATE TABLE runs (x)")
    with pytest.raises(ResultsError, match="another application"):
        ResultsStore(path)


def test_a_zero_byte_report_input_is_refused_and_left_empty(tmp_path: Path) -> None:
    path = tmp_path / "empty.sqlite"
    path.touch()
    with pytest.raises(ResultsError, match="empty file"):
        ResultsStore(path, readonly=True)
    assert path.stat().st_size == 0
    with pytest.raises(ResultsError, match="no such results file"):
        ResultsStore(tmp_path / "missing.sqlite", readonly=True)
    assert not (tmp_path / "missing.sqlite").exists()


def test_a_store_from_before_the_mark_is_adopted(tmp_path: Path) -> None:
    path = tmp_path / "old.sqlite"
    _store_with_rows(path)
    with sqlite3.connect(path) as db:  # as copi wrote stores before the format mark
        db.execute("PRAGMA application_id = 0")
        db.execute("PRAGMA user_version = 0")
    before = path.read_bytes()
    with ResultsStore(path, readonly=True) as store:
        assert len(store.episodes()) == 3
    assert path.read_bytes() == before  # reading never marks
    with ResultsStore(path) as store:
        assert store.done("r1", "m") == {0, 1, 2}
    with sqlite3.connect(path) as db:
        assert db.execute("PRAGMA application_id").fetchone()[0] == APPLICATION_ID


def test_a_store_from_an_earlier_copi_reads_without_its_new_columns(tmp_path: Path) -> None:
    # Found after the merge: `report` on a store of the previous version failed on the
    # newest column (reading does not migrate, so missing columns read as NULL).
    path = tmp_path / "earlier.sqlite"
    _store_with_rows(path)
    with sqlite3.connect(path) as db:
        for column in ("reason", "smoothness", "outcome"):
            db.execute(f"ALTER TABLE episodes DROP COLUMN {column}")
        db.execute("ALTER TABLE games DROP COLUMN outcome")
    before = path.read_bytes()
    with ResultsStore(path, readonly=True) as store:
        rows = store.episodes()
        assert store.games() == []
    assert len(rows) == 3 and rows[0]["reason"] is None and rows[0]["outcome"] is None
    assert rows[0]["path_length"] == 9.5
    assert path.read_bytes() == before


def test_reading_never_writes(tmp_path: Path) -> None:
    path = tmp_path / "r.sqlite"
    _store_with_rows(path)
    before = path.read_bytes()
    with ResultsStore(path, readonly=True) as store:
        with pytest.raises(ResultsError, match="read-only"):
            store.begin("r2", "navigation", "m2", {})
    assert path.read_bytes() == before


def _begin(args: tuple[str, int]) -> str:
    path, k = args
    try:
        with ResultsStore(path) as store:
            store.begin(f"run-{k // 2}", "navigation", f"m{k // 2}", {"seed": 0})
        return "ok"
    except Exception as exc:  # reported to the test, which shows it
        return f"{type(exc).__name__}: {exc}"


def test_two_processes_starting_on_a_new_file_both_succeed(tmp_path: Path) -> None:
    ctx = multiprocessing.get_context("fork")
    with ctx.Pool(2) as pool:
        for attempt in range(12):
            path = str(tmp_path / f"race{attempt}.sqlite")
            assert pool.map(_begin, [(path, 0), (path, 1)]) == ["ok", "ok"]
            with ResultsStore(path, readonly=True) as store:
                assert len(store.runs()) == 1


def test_disk_full_is_one_error_naming_the_file(tmp_path: Path) -> None:
    path = tmp_path / "full.sqlite"
    _store_with_rows(path, 1)
    with ResultsStore(path) as store:
        pages = store.db.execute("PRAGMA page_count").fetchone()[0]
        store.db.execute(f"PRAGMA max_page_count = {pages}")  # as a full disk would
        big = _row(5)
        object.__setattr__(big, "trajectory", {"path": [[0.5, 0.5]] * 5000})
        with pytest.raises(ResultsError, match=f"{path}: cannot write .*full"):
            store.add("r1", "navigation", "m", big)
        assert store.done("r1", "m") == {0}  # the failed row is not half there


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes read-only files")
def test_a_read_only_results_file_is_one_error(tmp_path: Path) -> None:
    path = tmp_path / "ro.sqlite"
    _store_with_rows(path, 1)
    path.chmod(0o444)
    try:
        with pytest.raises(ResultsError, match="read-only"):
            with ResultsStore(path) as store:
                store.begin("r2", "navigation", "m2", {})
        with ResultsStore(path, readonly=True) as store:  # reading still works
            assert len(store.episodes()) == 1
    finally:
        path.chmod(0o644)


def test_a_corrupted_results_file_is_one_error(tmp_path: Path) -> None:
    path = tmp_path / "bad.sqlite"
    _store_with_rows(path, 50)
    data = bytearray(path.read_bytes())
    data[200:] = b"\xff" * (len(data) - 200)  # the schema page and all rows garbled
    path.write_bytes(bytes(data))
    for readonly in (True, False):
        with pytest.raises(ResultsError, match=str(path)):
            with ResultsStore(path, readonly=readonly) as store:
                store.episodes()
