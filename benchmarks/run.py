"""Run every benchmark (``make bench``); exits non-zero if a goal was missed. What they
printed is kept as docs/speed-run.md (generated; docs/speed.md quotes its tables)."""

from __future__ import annotations

import argparse
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


def _sections(text: str) -> dict[str, list[str]]:
    """The sections of a page this script wrote: {name: its lines, heading excluded}."""
    out: dict[str, list[str]] = {}
    name = None
    for line in text.splitlines():
        if line.startswith("## "):
            name = line[3:].strip()
            out[name] = []
        elif name is not None and not line.startswith(("All goals met", "Goals missed in")):
            out[name].append(line)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--only", default=None,
                    help=f"comma-separated benchmarks to run ({', '.join(BENCHMARKS)}); the "
                    "page keeps the others' sections of its last run")  # fmt: skip
    a = ap.parse_args(argv)
    names = list(BENCHMARKS) if a.only is None else [x.strip() for x in a.only.split(",")]
    unknown = [x for x in names if x not in BENCHMARKS]
    if unknown:
        ap.error(f"unknown benchmark {', '.join(unknown)}; expected some of "
                 f"{', '.join(BENCHMARKS)}")  # fmt: skip
    out = Path(__file__).resolve().parents[1] / "docs" / "speed-run.md"
    kept = _sections(out.read_text(encoding="utf-8")) if a.only and out.exists() else {}
    results = {}
    page = ["# Speed, as `make bench` measured it", "",
            "<!-- generated: `make bench` (benchmarks/run.py) -->", "",
            f"Python {platform.python_version()}, {os.cpu_count()} cores; medians of repeated "
            "loops; every ratio measured in the same run. [Speed](speed.md) explains them.", ""]
    for name, module in BENCHMARKS.items():
        if name not in names:
            if name in kept:  # an earlier run's section, as it was
                page += [f"## {name}", *kept[name]]
                last = next((x for x in reversed(kept[name]) if x.strip()), "")
                results[name] = last.endswith("goals met)")
            continue
        RECORD.clear()
        t0 = time.perf_counter()
        results[name] = module.main()
        took = time.perf_counter() - t0
        page += [f"## {name}", "", *RECORD, f"({took:.0f} s; goals "
                 f"{'met' if results[name] else 'MISSED'})", ""]  # fmt: skip
    missed = [name for name, ok in results.items() if not ok]
    print("all goals met" if not missed else f"goals missed in: {', '.join(missed)}")
    page.append("All goals met." if not missed else f"Goals missed in: {', '.join(missed)}.")
    out.write_text("\n".join(page) + "\n", encoding="utf-8")
    print(f"wrote {out.name}")
    return 1 if missed else 0


if __name__ == "__main__":
    raise SystemExit(main())
