"""A digest of every row of results stores, the timing columns aside: two runs of the same
seeds give the same digest, on any number of workers and after any refactoring.

    python tools/rows_digest.py DIR_OR_STORE [...]

prints one line per table of each store (its rows, in key order, hashed) and one for the
whole; compare two runs' outputs with diff."""

from __future__ import annotations

import hashlib
import json
import sqlite3
import sys
from pathlib import Path

TIMINGS = {"decision_us", "strategy_us", "created", "versions"}
"""What a rerun measures anew (wall times) or records of the machine (versions)."""


def digests(store: Path) -> dict[str, str]:
    """Per table of ``store``, the hash of its rows without :data:`TIMINGS`."""
    out = {}
    with sqlite3.connect(f"file:{store}?mode=ro", uri=True) as db:
        tables = [r[0] for r in db.execute(
            "SELECT name FROM sqlite_master WHERE type='table' ORDER BY name")]  # fmt: skip
        for table in tables:
            cols = [r[1] for r in db.execute(f"PRAGMA table_info({table})")
                    if r[1] not in TIMINGS]  # fmt: skip
            rows = db.execute(f"SELECT {', '.join(cols)} FROM {table} ORDER BY "
                              f"{', '.join(cols)}").fetchall()  # fmt: skip
            h = hashlib.sha256(json.dumps([cols, rows], default=repr).encode())
            out[f"{table} ({len(rows)} rows)"] = h.hexdigest()[:16]
    return out


def main(paths: list[str]) -> int:
    if not paths:
        print(__doc__)
        return 2
    stores = sorted(
        p for arg in paths
        for p in ([Path(arg)] if Path(arg).is_file() else Path(arg).rglob("*.sqlite"))
    )  # fmt: skip
    whole = hashlib.sha256()
    for store in stores:
        for table, digest in digests(store).items():
            print(f"{store}: {table}: {digest}")
            whole.update(f"{store.name}:{table}:{digest}".encode())
    print(f"all: {whole.hexdigest()[:16]}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
