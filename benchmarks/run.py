"""Run every benchmark (``make bench``); exits non-zero if a goal was missed."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks import (  # noqa: E402
    bench_baselines,
    bench_games,
    bench_learning,
    bench_lifelong,
    bench_online,
    bench_planning,
    bench_rl,
    bench_world,
)


def main() -> int:
    results = {
        "world": bench_world.main(),
        "planning": bench_planning.main(),
        "learning": bench_learning.main(),
        "online": bench_online.main(),
        "games": bench_games.main(),
        "baselines": bench_baselines.main(),
        "lifelong": bench_lifelong.main(),
        "rl": bench_rl.main(),
    }
    missed = [name for name, ok in results.items() if not ok]
    print("all goals met" if not missed else f"goals missed in: {', '.join(missed)}")
    return 1 if missed else 0


if __name__ == "__main__":
    raise SystemExit(main())
