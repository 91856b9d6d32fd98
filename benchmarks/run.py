"""Run every benchmark (``make bench``); exits non-zero if a goal was missed. What they
printed is kept as docs/speed-run.md (generated; docs/speed.md quotes its tables)."""

from __future__ import annotations

import os
import platform
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks import (  # noqa: E402
    bench_baselines,
    bench_crowd,
    bench_games,
    bench_learning,
    bench_lifelong,
    bench_online,
    bench_planning,
    bench_rl,
    bench_world,
)
from benchmarks._timing import RECORD  # noqa: E402

BENCHMARKS = {
    "world": bench_world, "planning": bench_planning, "learning": bench_learning,
    "online": bench_online, "games": bench_games, "baselines": bench_baselines,
    "lifelong": bench_lifelong, "rl": bench_rl, "crowd": bench_crowd,
}  # fmt: skip


def main() -> int:
    results = {}
    page = ["# Speed, as `make bench` measured it", "",
            "<!-- generated: `make bench` (benchmarks/run.py) -->", "",
            f"Python {platform.python_version()}, {os.cpu_count()} cores; medians of repeated "
            "loops; every ratio measured in the same run. [Speed](speed.md) explains them.", ""]
    for name, module in BENCHMARKS.items():
        RECORD.clear()
        t0 = time.perf_counter()
        results[name] = module.main()
        took = time.perf_counter() - t0
        page += [f"## {name}", "", *RECORD, f"({took:.0f} s; goals "
                 f"{'met' if results[name] else 'MISSED'})", ""]  # fmt: skip
    missed = [name for name, ok in results.items() if not ok]
    print("all goals met" if not missed else f"goals missed in: {', '.join(missed)}")
    page.append("All goals met." if not missed else f"Goals missed in: {', '.join(missed)}.")
    out = Path(__file__).resolve().parents[1] / "docs" / "speed-run.md"
    out.write_text("\n".join(page) + "\n", encoding="utf-8")
    print(f"wrote {out.name}")
    return 1 if missed else 0


if __name__ == "__main__":
    raise SystemExit(main())
