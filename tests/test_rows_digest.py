"""tools/rows_digest.py: the same seeds give the same digest whatever the workers, and a
changed row changes it (how copi checks that a change of code keeps every stored row)."""

from __future__ import annotations

import importlib.util
import sqlite3
from pathlib import Path

from copi.experiments import BenchmarkConfig, run_benchmark

TOOL = Path(__file__).resolve().parents[1] / "tools" / "rows_digest.py"


def _tool():  # type: ignore[no-untyped-def]
    spec = importlib.util.spec_from_file_location("rows_digest", TOOL)
    module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module


def test_same_seeds_same_digest_and_a_changed_row_changes_it(tmp_path: Path) -> None:
    tool = _tool()
    config = BenchmarkConfig(methods=("straight@map", "dwa@sensor"), families=("star",),
                             episodes=3)  # fmt: skip
    run_benchmark(config, tmp_path / "a.sqlite")
    run_benchmark(config, tmp_path / "b.sqlite", workers=2)
    a, b = tool.digests(tmp_path / "a.sqlite"), tool.digests(tmp_path / "b.sqlite")
    assert a == b and "episodes (6 rows)" in a
    with sqlite3.connect(tmp_path / "b.sqlite") as db:
        db.execute("UPDATE episodes SET steps = steps + 1 WHERE episode = 1")
    changed = tool.digests(tmp_path / "b.sqlite")
    assert changed["episodes (6 rows)"] != a["episodes (6 rows)"]
    assert {k: v for k, v in changed.items() if not k.startswith("episodes")} == {
        k: v for k, v in a.items() if not k.startswith("episodes")}  # fmt: skip
