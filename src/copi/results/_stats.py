"""Paired statistics of stored rows: a method against a reference on the same episodes
(or the same lives), with 95 % percentile bootstrap intervals, and one arm's summary.

Every comparison copi reports is paired: episode k of one method against episode k of
another (they met the same world, task and obstacles), so that the interval is that of
the difference, not of two rates each with its own noise."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "MIN_PAIRS",
    "PairedDifference",
    "format_difference",
    "lives_difference",
    "pair_episodes",
    "paired_difference",
    "statistic",
    "summarize_rows",
    "verdict",
]


MIN_PAIRS = 10
"""Fewer paired episodes than this give an estimate but no interval (a bootstrap of a
handful of pairs is degenerate)."""


@dataclass(frozen=True)
class PairedDifference:
    """A statistic of method A minus the same statistic of method B on the same episodes."""

    estimate: float
    low: float
    high: float
    """The 95 % percentile bootstrap interval (resampling episodes)."""
    n: int
    """Episodes the difference is over."""

    @property
    def excludes_zero(self) -> bool:
        return self.n > 0 and (self.low > 0 or self.high < 0)


def paired_difference(
    a: Any,
    b: Any,
    *,
    statistic: str = "mean",
    resamples: int = 2000,
    seed: int = 0,
) -> PairedDifference:
    """stat(a) − stat(b) over paired samples (episode i of a with episode i of b), with a
    95 % percentile bootstrap interval that resamples episodes (pairs) with replacement.

    ``statistic`` is ``"mean"`` (e.g. success as 0/1: the difference in success rate) or
    ``"median"`` (e.g. path excess on the episodes both methods succeeded in).

    Examples
    --------
    >>> d = paired_difference([1, 1, 0, 1], [0, 1, 0, 0])
    >>> d.estimate, d.n
    (0.5, 4)
    """
    x = np.asarray(a, dtype=np.float64)
    y = np.asarray(b, dtype=np.float64)
    if x.shape != y.shape or x.ndim != 1:
        raise ValueError(f"paired samples must be 1-d of one length; got {x.shape}, {y.shape}")
    n = len(x)
    if n == 0:
        return PairedDifference(math.nan, math.nan, math.nan, 0)
    fn: Any = {"mean": np.mean, "median": np.median}[statistic]
    est = float(fn(x) - fn(y))
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, n, size=(resamples, n))
    boot = fn(x[idx], axis=1) - fn(y[idx], axis=1)
    low, high = np.percentile(boot, [2.5, 97.5])
    return PairedDifference(est, float(low), float(high), n)


def _median(values: list[float]) -> float:
    return float(np.median(values)) if values else math.nan


def summarize_rows(rows: list[Any]) -> dict[str, Any]:
    """The benchmark's statistics of one arm's episodes (skipped ones left out)."""
    rows = [r for r in rows if r["outcome"] != "skipped"]
    n = len(rows)
    out = np.array([r["outcome"] for r in rows])
    won = [r for r in rows if r["outcome"] == "success"]
    ex = [r["excess"] for r in won if r["excess"] is not None]
    return {
        "n": n,
        "success": float((out == "success").mean()) if n else math.nan,
        "collision": float((out == "collision").mean()) if n else math.nan,
        "timeout": float((out == "timeout").mean()) if n else math.nan,
        "excess_median": _median(ex),
        "excess_p90": float(np.percentile(ex, 90)) if ex else math.nan,
        "time_to_goal": _median([r["time_to_goal"] for r in won if r["time_to_goal"] is not None]),
        "clearance": _median([r["min_clearance"] for r in rows if r["min_clearance"] is not None]),
        "turning": math.degrees(_median([r["smoothness"] / max(r["steps"], 1) for r in won
                                         if r["smoothness"] is not None])),  # fmt: skip
        "decisions_per_s": 1e6 / _median([r["decision_us"] for r in rows
                                          if r["decision_us"]]) if rows else math.nan,  # fmt: skip
        "no_optimum": int(sum(r["optimal_length"] is None for r in rows)),
    }


def _signed(x: float) -> str:
    """``x`` to one decimal with its sign, zero as +0.0 (never -0.0)."""
    return f"{round(x, 1) + 0.0:+.1f}"


def format_difference(d: PairedDifference, scale: float = 100.0) -> str:
    """``d`` as a report prints it: the estimate (times ``scale``: points for a rate) and
    its interval, or why there is none (too few pairs, all pairs alike)."""
    if d.n == 0 or not math.isfinite(d.estimate):
        return "—"
    est = _signed(scale * d.estimate)
    if d.n < MIN_PAIRS or not math.isfinite(d.low):
        return f"{est} (n = {d.n}, no interval)"
    if d.low == d.high:  # every resample the same: the pairs all differ alike
        return f"{est} (all {d.n} pairs alike)"
    return f"{est} [{_signed(scale * d.low)}, {_signed(scale * d.high)}]"


def pair_episodes(
    rows: list[Any], ref: list[Any]
) -> tuple[PairedDifference, PairedDifference]:
    """(success, median excess) of ``rows`` minus ``ref`` on the episodes both ran (the
    excess on those both succeeded in); skipped episodes left out."""
    a = {int(r["episode"]): r for r in rows if r["outcome"] != "skipped"}
    b = {int(r["episode"]): r for r in ref if r["outcome"] != "skipped"}
    common = sorted(set(a) & set(b))
    sa = [a[k]["outcome"] == "success" for k in common]
    sb = [b[k]["outcome"] == "success" for k in common]
    both = [
        k for k in common
        if a[k]["outcome"] == "success" and b[k]["outcome"] == "success"
        and a[k]["excess"] is not None and b[k]["excess"] is not None
    ]  # fmt: skip
    return (
        paired_difference(sa, sb),
        paired_difference([a[k]["excess"] for k in both], [b[k]["excess"] for k in both],
                          statistic="median"),  # fmt: skip
    )


def verdict(d_success: PairedDifference, d_excess: PairedDifference) -> str:
    """The row against the reference, in words, from whichever differences exclude zero
    (on too few pairs, none does)."""
    parts = []
    if d_success.excludes_zero and d_success.n >= MIN_PAIRS:
        parts.append("more successes" if d_success.estimate > 0 else "fewer successes")
    if d_excess.excludes_zero and d_excess.n >= MIN_PAIRS:
        parts.append("longer paths" if d_excess.estimate > 0 else "shorter paths")
    return "; ".join(parts)


def statistic(rows: list[Any], what: str) -> float:
    """Of task or episode rows: the success rate (``what="success"``), the median excess
    over the successes (``"excess"``), or the mean of column ``what`` where it is finite."""
    if not rows:
        return math.nan
    if what == "success":
        return float(np.mean([r["outcome"] == "success" for r in rows]))
    if what == "excess":
        ex = [r["excess"] for r in rows if r["outcome"] == "success" and r["excess"] is not None]
        return float(np.median(ex)) if ex else math.nan
    vals = [r[what] for r in rows if r[what] is not None and math.isfinite(r[what])]
    return float(np.mean(vals)) if vals else math.nan


def lives_difference(
    a: dict[int, list[Any]],
    b: dict[int, list[Any]],
    what: str,
    *,
    resamples: int = 2000,
    seed: int = 0,
) -> PairedDifference:
    """stat(a) - stat(b) over the lives both have (``what``: "success", the mean of
    success, or "excess", the median excess over the tasks both succeeded in), with a
    95 % percentile bootstrap interval resampling lives with replacement."""
    lives = sorted(set(a) & set(b))
    if not lives:
        return PairedDifference(math.nan, math.nan, math.nan, 0)

    def pair(ls: list[int]) -> tuple[list[Any], list[Any]]:
        xa: list[Any] = []
        xb: list[Any] = []
        for life in ls:
            ta = {r["task"]: r for r in a[life]}
            tb = {r["task"]: r for r in b[life]}
            for t in sorted(set(ta) & set(tb)):
                if what == "excess" and not (
                    ta[t]["outcome"] == "success" and tb[t]["outcome"] == "success"
                ):
                    continue
                xa.append(ta[t])
                xb.append(tb[t])
        return xa, xb

    xa, xb = pair(lives)
    est = statistic(xa, what) - statistic(xb, what)
    rng = np.random.default_rng(seed)
    boot = []
    for _ in range(resamples):
        ya, yb = pair(list(rng.choice(lives, size=len(lives), replace=True)))
        d = statistic(ya, what) - statistic(yb, what)
        if math.isfinite(d):
            boot.append(d)
    if not boot or not math.isfinite(est):
        return PairedDifference(est, math.nan, math.nan, len(xa))
    low, high = np.percentile(boot, [2.5, 97.5])
    return PairedDifference(est, float(low), float(high), len(xa))
