"""The benchmark's report: one table per family, paired differences against copi with
bootstrap confidence intervals, and a figure of success against median excess. Read back
from the results store only."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from copi._files import save_figure, write_text
from copi.experiments.figures import _figure
from copi.experiments.methods import METHODS
from copi.experiments.store import ResultsStore
from copi.online import SENSING_LEVELS

__all__ = ["PairedDifference", "paired_difference", "write_benchmark_report"]

REFERENCE = "copi-extended"
"""The copi mode every other row is paired against (at the same level; oracle rows
against its ``map`` row) — or, in a run without it, :data:`FALLBACK_REFERENCE` (a run of
the learnt preset's ablations)."""
FALLBACK_REFERENCE = "copi-learnt"


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


def _summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
    n = len(rows)
    out = np.array([r["outcome"] for r in rows])
    ex = np.array(
        [r["excess"] for r in rows if r["outcome"] == "success" and r["excess"] is not None],
        dtype=float,
    )
    dec = np.array([r["decision_us"] for r in rows], dtype=float)
    ttg = np.array([r["time_to_goal"] for r in rows if r["outcome"] == "success"], dtype=float)
    clear = np.array([r["min_clearance"] for r in rows if r["min_clearance"] is not None])
    turn = np.array(
        [r["smoothness"] / max(r["steps"], 1) for r in rows if r["outcome"] == "success"],
        dtype=float,
    )
    return {
        "n": n,
        "success": float((out == "success").mean()),
        "collision": float((out == "collision").mean()),
        "timeout": float((out == "timeout").mean()),
        "excess_median": float(np.median(ex)) if len(ex) else math.nan,
        "excess_p90": float(np.percentile(ex, 90)) if len(ex) else math.nan,
        "time_to_goal": float(np.median(ttg)) if len(ttg) else math.nan,
        "clearance": float(np.median(clear)) if len(clear) else math.nan,
        "turning": float(np.degrees(np.median(turn))) if len(turn) else math.nan,
        "decisions_per_s": 1e6 / float(np.median(dec)) if len(dec) else math.nan,
        "no_optimum": int(sum(r["optimal_length"] is None for r in rows)),
    }


def _pct(x: float) -> str:
    return "—" if not math.isfinite(x) else f"{100 * x:.1f} %"


def _diff(d: PairedDifference, scale: float = 100.0) -> str:
    if d.n == 0 or not math.isfinite(d.estimate):
        return "—"
    return f"{scale * d.estimate:+.1f} [{scale * d.low:+.1f}, {scale * d.high:+.1f}]"


def _by_episode(rows: list[dict[str, Any]]) -> dict[int, dict[str, Any]]:
    return {int(r["episode"]): r for r in rows}


def _pair(
    rows: list[dict[str, Any]], ref: list[dict[str, Any]]
) -> tuple[PairedDifference, PairedDifference]:
    a, b = _by_episode(rows), _by_episode(ref)
    common = sorted(set(a) & set(b))
    sa = [a[k]["outcome"] == "success" for k in common]
    sb = [b[k]["outcome"] == "success" for k in common]
    both = [
        k for k in common
        if a[k]["outcome"] == "success" and b[k]["outcome"] == "success"
        and a[k]["excess"] is not None and b[k]["excess"] is not None
    ]  # fmt: skip
    ea = [a[k]["excess"] for k in both]
    eb = [b[k]["excess"] for k in both]
    return (
        paired_difference(sa, sb),
        paired_difference(ea, eb, statistic="median"),
    )


def _figure_success_excess(
    table: dict[str, dict[tuple[str, str], dict[str, Any]]], out: Path
) -> Path:
    families = list(table)
    cols = min(3, len(families))
    rows_n = math.ceil(len(families) / cols)
    fig = _figure(4.2 * cols, 3.6 * rows_n + (0 if len(families) % cols else 1.2))
    axes = np.atleast_1d(fig.subplots(rows_n, cols, squeeze=False)).ravel()
    markers = {"sensor": "o", "map": "s", "oracle": "^"}
    names = list(METHODS)
    import matplotlib

    # One distinct colour per method (tab10, then tab20's odd entries), shape per level.
    tab10, tab20 = matplotlib.colormaps["tab10"], matplotlib.colormaps["tab20"]
    palette = [tab10(i) for i in range(10)] + [tab20(i) for i in range(1, 20, 2)]
    for ax, family in zip(axes, families, strict=False):
        for (method, level), s in table[family].items():
            if not math.isfinite(s["excess_median"]):
                continue
            c = palette[names.index(method) % len(palette)]
            ax.scatter(100 * s["excess_median"], 100 * s["success"], marker=markers[level],
                       color=c, s=36, edgecolor="black" if method.startswith("copi") else "none",
                       label=f"{method} ({level})", zorder=3)  # fmt: skip
        ax.set_title(family)
        ax.set_xlabel("median excess (%)")
        ax.set_ylabel("success (%)")
        ax.grid(alpha=0.3)
    for ax in axes[len(families) :]:
        ax.axis("off")
    seen: dict[str, Any] = {}
    for ax in axes[: len(families)]:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            seen.setdefault(lab, h)
    spare = axes[len(families)] if len(axes) > len(families) else None
    if seen and spare is not None:  # the legend fills the empty panel
        spare.legend(list(seen.values()), list(seen), loc="center", ncol=2, fontsize=7,
                     frameon=False, title="● sensor   ■ map   ▲ oracle", title_fontsize=8)
        fig.subplots_adjust(hspace=0.45, wspace=0.3)
    elif seen:
        fig.legend(list(seen.values()), list(seen), loc="lower center", ncol=4, fontsize=7,
                   frameon=False, bbox_to_anchor=(0.5, 0.0))
        fig.subplots_adjust(bottom=0.1 + 0.03 * math.ceil(len(seen) / 4), hspace=0.45,
                            wspace=0.3)  # fmt: skip
    target = out / "benchmark_success_excess.png"
    save_figure(fig, target)
    return target


def write_benchmark_report(
    results: str | os.PathLike[str], directory: str | os.PathLike[str]
) -> Path:
    """Write ``benchmark.md`` and its figure from a benchmark results file."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    groups: dict[str, dict[tuple[str, str], list[dict[str, Any]]]] = {}
    params: dict[str, Any] = {}
    strategies: set[str] = set()
    with ResultsStore(results, readonly=True) as store:
        for run in store.runs():
            if run["experiment"] != "benchmark":
                continue
            cfg = run["config"]
            # skipped episodes (no valid task in the world) are the same for every method
            rows = [r for r in store.episodes(run["run_id"]) if r["outcome"] != "skipped"]
            groups.setdefault(cfg["family"], {})[(cfg["method"], cfg["sensing"])] = rows
            params[cfg["method"]] = cfg.get("params", {})
            if cfg["sensing"] == "sensor":
                strategies.add(cfg.get("strategy", "greedy"))
    if not groups:
        raise FileNotFoundError(f"no benchmark runs in {results}")
    order = {m: i for i, m in enumerate(METHODS)}
    present = {m for g in groups.values() for m, _ in g}
    reference = (
        REFERENCE
        if REFERENCE in present or FALLBACK_REFERENCE not in present
        else FALLBACK_REFERENCE
    )
    from copi.experiments.benchmark import BENCHMARK_FAMILIES

    families = [f for f in BENCHMARK_FAMILIES if f in groups] + sorted(
        f for f in groups if f not in BENCHMARK_FAMILIES
    )
    table: dict[str, dict[tuple[str, str], dict[str, Any]]] = {}
    lines = [
        "# Benchmark — every method on the same episodes",
        "",
        "Outcomes are exclusive (success: goal reached with no contact; collision: a contact "
        "with a moving obstacle, which ends the episode; timeout: 3 × optimum + 100 steps, at "
        "most 1000). Excess = path length / optimum − 1 over successful episodes; the optimum "
        "is the shortest path to the goal's tolerance disc on the snapshot at t = 0 with the "
        "obstacles frozen. Sensing: `sensor` = ranges + goal relative to the agent; `map` = "
        "plus the static world; `oracle` = plus obstacle positions and velocities. "
        f"Δ columns: the method minus {reference} at the same level (oracle rows: minus its "
        "`map` row) on the same episodes, in points, with 95 % bootstrap intervals; Δ excess "
        "over the episodes both succeeded in. **copi loses** marks a row whose success is "
        f"higher than {reference}'s with an interval excluding zero. Steps to goal, "
        "clearance (the least surface distance to a moving obstacle over an episode, "
        "negative after a contact) and turning per step (the sum of turning angles between "
        "moves over the steps) are medians; steps and turning over successful episodes. "
        "At the `sensor` level every method's global strategy is "
        + " / ".join(
            {"greedy": "*greedy* (head for the goal)",
             "mapping": "*mapping* (a map built from the ranges, re-planned)"}[k]
            for k in sorted(strategies)
        )
        + "; at `map` and `oracle`, the static route.",
        "",
    ]
    for family in families:
        g = groups[family]
        keys = sorted(g, key=lambda k: (order.get(k[0], 99), SENSING_LEVELS.index(k[1])))
        table[family] = {k: _summary(g[k]) for k in keys}
        n = max(s["n"] for s in table[family].values())
        no_opt = max(s["no_optimum"] for s in table[family].values())
        lines += [
            f"## {family} ({n} episodes)",
            "",
            *(
                [f"{no_opt} episode{'s have' if no_opt > 1 else ' has'} no path on the frozen "
                 "snapshot (moving obstacles block every passage at t = 0): no excess is "
                 f"measured for {'them' if no_opt > 1 else 'it'}.", ""]
                if no_opt else []
            ),  # fmt: skip
            "| method | sensing | success | collision | timeout | median excess | p90 excess "
            "| steps to goal | clearance | turning / step | decisions / s | Δ success "
            "| Δ median excess | |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        for method, level in keys:
            s = table[family][(method, level)]
            ref_level = level if level != "oracle" else "map"
            ref = g.get((reference, ref_level))
            d_s = d_e = PairedDifference(math.nan, math.nan, math.nan, 0)
            if ref is not None and method != reference:
                d_s, d_e = _pair(g[(method, level)], ref)
            flag = ""
            if d_s.excludes_zero:
                flag = "**copi loses**" if d_s.estimate > 0 else "copi wins"
            lines.append(
                f"| {method} | {level} | {_pct(s['success'])} | {_pct(s['collision'])} | "
                f"{_pct(s['timeout'])} | {_pct(s['excess_median'])} | {_pct(s['excess_p90'])} | "
                f"{s['time_to_goal']:.0f} | {s['clearance']:.2f} | {s['turning']:.0f}° | "
                f"{s['decisions_per_s']:,.0f} | {_diff(d_s)} | "
                f"{_diff(d_e)} | {flag} |"
            )
        lines.append("")
    fig = _figure_success_excess(table, out)
    lines += [f"![success against median excess]({fig.name})", "", "## Methods", ""]
    lines += ["| method | needs | what it is | parameters |", "|---|---|---|---|"]
    seen = {m for f in groups for m, _ in groups[f]}
    for name, spec in METHODS.items():
        if name in seen:
            p = ", ".join(f"{k} = {v}" for k, v in params.get(name, spec.params).items()) or "—"
            lines.append(f"| {name} | {spec.sensing} | {spec.summary} | {p} |")
    report = out / "benchmark.md"
    write_text(report, "\n".join(lines) + "\n")
    return report
