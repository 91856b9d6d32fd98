"""Small timing helpers shared by the benchmarks: medians of repeated loops, and what each
benchmark printed, kept as Markdown (``RECORD``) for the page ``make bench`` writes."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

from rich.console import Console
from rich.table import Table

RECORD: list[str] = []
"""Every table and line the benchmarks printed, as Markdown, in order (benchmarks/run.py
writes them to docs/speed-run.md)."""


def show(title: str, columns: list[str], rows: list[list[str]]) -> None:
    """Print a table (rich) and record it (Markdown, under the heading ``title``)."""
    table = Table(*columns, title=title)
    for r in rows:
        table.add_row(*r)
    Console(width=110).print(table)
    RECORD.extend([f"### {title}", "", "| " + " | ".join(columns) + " |",
                   "|" + "---|" * len(columns), *("| " + " | ".join(r) + " |" for r in rows),
                   ""])  # fmt: skip


def note(text: str) -> None:
    """Print a line and record it."""
    print(text)
    RECORD.extend([text.strip(), ""])


@dataclass(frozen=True)
class Timing:
    name: str
    seconds: float
    """Median wall time of one call, in seconds."""
    per: int = 1
    """Items handled by one call (e.g. scans in a batch): the per-item time is seconds / per."""

    @property
    def per_item(self) -> float:
        return self.seconds / self.per


def median_time(fn: Callable[[], object], *, number: int, repeat: int = 7) -> float:
    """Median over ``repeat`` runs of the mean time of ``number`` calls (after one warm-up)."""
    fn()
    runs = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        runs.append((time.perf_counter() - t0) / number)
    runs.sort()
    return runs[len(runs) // 2]


def report(title: str, rows: list[Timing], reference: str | None, goals: dict[str, float]) -> bool:
    """Print a table with per-item times, speed-up against ``reference`` (if any) and goal
    checks; returns whether every goal (name -> max seconds per item) was met."""
    ref = next((r for r in rows if r.name == reference), None)
    cols = ["method", "per item"] + ([f"× vs {reference}"] if ref else []) + ["goal"]
    ok = True
    cells = []
    for r in rows:
        goal = goals.get(r.name)
        verdict = ""
        if goal is not None:
            met = r.per_item <= goal
            ok &= met
            verdict = f"{'met' if met else 'MISSED'} (≤ {fmt(goal)})"
        speedup = [f"{ref.per_item / r.per_item:,.1f}"] if ref else []
        cells.append([r.name, fmt(r.per_item), *speedup, verdict])
    show(title, cols, cells)
    return ok


def fmt(seconds: float) -> str:
    if seconds >= 1:
        return f"{seconds:.2f} s"
    if seconds >= 1e-3:
        return f"{seconds * 1e3:.2f} ms"
    return f"{seconds * 1e6:.2f} µs"


