"""The benchmark's report: one table per family, paired differences against a reference
method with bootstrap confidence intervals, and a figure of success against median
excess. Read back from the results store only: any method or family the store holds is
reported, registered in this copi or not."""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from copi._files import write_text
from copi.core import SENSING_LEVELS
from copi.errors import CopiError, InvalidArgumentError
from copi.methods import MethodRun, method_names, method_spec
from copi.reports._figures import finish_figure, new_figure
from copi.results import (
    MIN_PAIRS,
    PairedDifference,
    ResultsStore,
    format_difference,
    pair_episodes,
    summarize_rows,
    verdict,
)
from copi.world import BENCHMARK_FAMILIES, family_spec

__all__ = ["DEFAULT_AGAINST", "read_benchmark", "write_benchmark_report"]

DEFAULT_AGAINST = "copi-learnt"
"""The method every row is paired against unless ``--against`` names another (in a run
without it: the first method of the run in the registry's order); the report states it."""


_STRATEGY_WORDS = {
    "greedy": "*greedy* (head for the goal)",
    "mapping": "*mapping* (a map built from the ranges, re-planned)",
    "causal": "*causal* (a map and a causal map learnt from experience)",
}


def _pct(x: float) -> str:
    return "—" if not math.isfinite(x) else f"{100 * x:.1f} %"


def _num(x: float, fmt: str) -> str:
    return "—" if not math.isfinite(x) else format(x, fmt)


def _is_bound(method: str) -> bool:
    """Whether ``method`` is a registered bound (a ceiling, not a method)."""
    try:
        return method_spec(method).bound
    except CopiError:
        return False


def _order(arm: MethodRun, known: dict[str, int]) -> tuple[int, str, int, str]:
    return (known.get(arm.method, len(known)), arm.method, SENSING_LEVELS.index(arm.sensing),
            arm.strategy)  # fmt: skip


_NO_DIFF = PairedDifference(math.nan, math.nan, math.nan, 0)


def _reference_arm(reference: str, arm: MethodRun) -> MethodRun:
    """The reference's arm a row is paired with: the same level and strategy; oracle and
    future rows with its ``map`` row."""
    level = arm.sensing if arm.sensing in ("sensor", "map") else "map"
    return MethodRun(reference, level,  # type: ignore[arg-type]
                     arm.strategy if level == "sensor" else "route")  # fmt: skip


def _label(method: str, reference: str) -> str:
    if _is_bound(method):
        return f"*{method}* (bound)"
    return f"**{method}**" if method == reference else method


def _overview(
    families: list[str],
    table: dict[str, dict[MethodRun, dict[str, Any]]],
    diffs: dict[str, dict[MethodRun, tuple[PairedDifference, PairedDifference] | None]],
    reference: str,
    known: dict[str, int],
) -> list[str]:
    """The report's first tables, one row per arm and one column per family: success with
    its median excess, marked against the reference, then the paired Δ success itself
    (the analysis pages quote these; every cell is read from the family tables' data)."""
    arms = sorted({a for f in families for a in table[f]}, key=lambda a: _order(a, known))
    head = "| method | sensing | strategy | " + " | ".join(map(_family_title, families)) + " |"
    rule = "|---|---|---|" + "---|" * len(families)
    success = [head, rule]
    delta = [head, rule]
    most = {f: max((s["n"] for s in table[f].values()), default=0) for f in families}
    for arm in arms:
        cells, deltas = [], []
        for family in families:
            s = table[family].get(arm)
            pair = diffs[family].get(arm)
            if s is None:
                cells.append("")
                deltas.append("")
                continue
            mark = ""
            if pair is not None and pair[0].excludes_zero and pair[0].n >= MIN_PAIRS:
                mark = " ▲" if pair[0].estimate > 0 else " ▽"
            ex = s["excess_median"]
            fewer = f", n = {s['n']}" if s["n"] != most[family] else ""  # not every episode
            cells.append(f"{_num(100 * s['success'], '.1f')}{mark} ({_num(100 * ex, '.0f')})"
                         f"{fewer}")  # fmt: skip
            deltas.append("reference" if pair is None else format_difference(pair[0]))
        label = f"| {_label(arm.method, reference)} | {arm.sensing} | {arm.strategy} | "
        success.append(label + " | ".join(cells) + " |")
        delta.append(label + " | ".join(deltas) + " |")
    return [
        "## Overview",
        "",
        f"Success in % (median excess in %; n = N where a row ran fewer episodes of the "
        f"family than the others); ▲ / ▽: more / fewer successes than {reference} at "
        "the same level and strategy (oracle and future rows: its `map` row), the paired 95 % "
        "interval excluding zero. Each family's table below gives n, the other outcomes and "
        "the intervals.",
        "",
        *success,
        "",
        "### Δ success against " + reference,
        "",
        f"The row's success minus {reference}'s on the same episodes, in points, with 95 % "
        "bootstrap intervals.",
        "",
        *delta,
        "",
        *_said(families, table, diffs, reference),
    ]


def _said(
    families: list[str],
    table: dict[str, dict[MethodRun, dict[str, Any]]],
    diffs: dict[str, dict[MethodRun, tuple[PairedDifference, PairedDifference] | None]],
    reference: str,
) -> list[str]:
    """What the tables say, in words, read from their data (never typed): per family,
    the row with the most successes, and the rows with more or fewer successes than the
    reference at their level, the paired interval excluding zero; then, method by
    method, the families where it has more, fewer or as many successes as the reference
    (the analysis pages quote these sections instead of comparing by hand)."""
    out = ["### What the tables say", ""]
    for family in families:
        rows = table[family]
        best = max(rows, key=lambda a: rows[a]["success"])
        more: list[str] = []
        fewer: list[str] = []
        for arm, pair in diffs[family].items():
            if pair is None or not pair[0].excludes_zero or pair[0].n < MIN_PAIRS:
                continue
            (more if pair[0].estimate > 0 else fewer).append(
                f"{arm.method} ({arm.sensing}, {format_difference(pair[0])})")
        out += [
            f"**{_family_title(family)}**: most successes {best.method} at {best.sensing} "
            f"({100 * rows[best]['success']:.1f} %); more than {reference}: "
            f"{'; '.join(more) or 'none'}; fewer: {'; '.join(fewer) or 'none'}.",
            "",
        ]
    out += ["### Method by method", ""]
    for arm in sorted({a for f in families for a, pr in diffs[f].items() if pr is not None},
                      key=lambda a: (a.method, SENSING_LEVELS.index(a.sensing), a.strategy)):
        more, fewer, level, thin = [], [], [], []
        for family in families:
            pair = diffs[family].get(arm)
            if pair is None:
                continue
            d = pair[0]
            if d.n < MIN_PAIRS:
                thin.append(_family_title(family))
            elif not d.excludes_zero:
                level.append(_family_title(family))
            else:
                (more if d.estimate > 0 else fewer).append(
                    f"{_family_title(family)} ({format_difference(d)})")
        parts = [f"more successes than {reference} in {'; '.join(more) or 'no family'}",
                 f"fewer in {'; '.join(fewer) or 'no family'}",
                 f"level (the interval holds zero) in {', '.join(level) or 'no family'}"]
        if thin:
            parts.append(f"too few paired episodes in {', '.join(thin)}")
        out += [f"**{arm.method}** at {arm.sensing} ({arm.strategy}): {'; '.join(parts)}.", ""]
    return out


def _family_title(family: str) -> str:
    return f"worlds of {family[5:]}" if family.startswith("file:") else family


def _figure_success_excess(table: dict[str, dict[MethodRun, dict[str, Any]]], out: Path) -> Path:
    families = list(table)
    cols = min(3, len(families))
    rows_n = math.ceil(len(families) / cols)
    extra = 0 if len(families) % cols else 1.2
    fig = new_figure(4.2 * cols, 3.6 * rows_n + extra + (1.4 if cols == 1 else 0))
    axes = np.atleast_1d(fig.subplots(rows_n, cols, squeeze=False)).ravel()
    markers = {"sensor": "o", "map": "s", "oracle": "^", "future": "*"}
    names = sorted({a.method for t in table.values() for a in t}, key=lambda m: (
        method_names().index(m) if m in method_names() else 99, m))  # fmt: skip
    import matplotlib

    # One distinct colour per method (tab10, then tab20's odd entries), shape per level.
    tab10, tab20 = matplotlib.colormaps["tab10"], matplotlib.colormaps["tab20"]
    palette = [tab10(i) for i in range(10)] + [tab20(i) for i in range(1, 20, 2)]
    for ax, family in zip(axes, families, strict=False):
        for arm, s in table[family].items():
            if not math.isfinite(s["excess_median"]):
                continue
            c = palette[names.index(arm.method) % len(palette)]
            bound = _is_bound(arm.method)
            ax.scatter(100 * s["excess_median"], 100 * s["success"],
                       marker=markers.get(arm.sensing, "D"), s=70 if bound else 36,
                       facecolor="none" if bound else c,
                       edgecolor=c if bound else (
                           "black" if arm.method.startswith("copi") else "none"),
                       linewidths=1.4 if bound else 1.0,
                       label=arm.label + (" (bound)" if bound else ""), zorder=3)  # fmt: skip
        ax.set_title(_family_title(family))
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
    title = "● sensor   ■ map   ▲ oracle   ★ future   (hollow: a bound, not a method)"
    if seen and spare is not None:  # the legend fills the empty panel
        spare.legend(list(seen.values()), list(seen), loc="center", ncol=2, fontsize=7,
                     frameon=False, title=title, title_fontsize=8)  # fmt: skip
        fig.subplots_adjust(hspace=0.45, wspace=0.3)
    elif seen:  # below the panels, inside the figure (bbox_inches keeps it whole)
        ncol = 2 if cols == 1 else 4
        fig.legend(list(seen.values()), list(seen), loc="lower center", ncol=ncol, fontsize=7,
                   frameon=False, title=title, title_fontsize=8,
                   bbox_to_anchor=(0.5, 0.0))  # fmt: skip
        fig.subplots_adjust(bottom=0.12 + 0.05 * math.ceil(len(seen) / ncol), hspace=0.45,
                            wspace=0.3)  # fmt: skip
    return finish_figure(fig, out / "benchmark_success_excess.png", tight=False,
                         bbox_inches="tight")  # fmt: skip


def physical_metrics(family: str, rows: dict[MethodRun, list[Any]],
                     arms: list[MethodRun]) -> list[str]:  # fmt: skip
    """For a family in physical units (CrowdNav's scenarios): its rows in CrowdNav's
    metrics, as its papers report them (rates, not percentages; the navigation time in
    seconds, over the successful episodes, "—" where none succeeded; the discomfort
    frequency, the share of all steps closer to a human than the discomfort distance).
    Nothing for other families."""
    try:
        own = family_spec(family).episode
    except CopiError:  # a family of another package, not installed here
        return []
    if own is None or own.seconds_per_step is None:
        return []
    metres = own.metres_per_step or 1.0
    out = [f"CrowdNav's metrics (a step is {own.seconds_per_step:g} s and {metres:g} m; "
           f"discomfort: closer than {(own.discomfort or 0) * metres:g} m):", "",
           "| method | sensing | n | success rate | collision rate | timeout rate "
           "| navigation time (s) | discomfort frequency |",
           "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for arm in arms:
        rs = rows[arm]
        n = len(rs)
        won = [r.steps * own.seconds_per_step for r in rs if r.outcome == "success"]
        steps = sum(r.steps for r in rs)
        close = sum(r.close_steps or 0 for r in rs)
        out.append(
            f"| {arm.method} | {arm.sensing} | {n} "
            f"| {sum(r.outcome == 'success' for r in rs) / n:.2f} "
            f"| {sum(r.outcome == 'collision' for r in rs) / n:.2f} "
            f"| {sum(r.outcome == 'timeout' for r in rs) / n:.2f} "
            f"| {f'{sum(won) / len(won):.2f}' if won else '—'} "
            f"| {f'{close / steps:.3f}' if steps else '—'} |"
        )
    return [*out, ""]


def read_benchmark(results: str | os.PathLike[str]) -> tuple[
    dict[str, dict[MethodRun, list[Any]]], dict[str, dict[str, Any]], dict[str, Any]
]:  # fmt: skip
    """(family -> arm -> rows, method -> parameters, family -> a run's config) of every
    benchmark run in ``results`` (skipped episodes, the same for every method, left out)."""
    groups: dict[str, dict[MethodRun, list[Any]]] = {}
    params: dict[str, dict[str, Any]] = {}
    configs: dict[str, Any] = {}
    with ResultsStore(results, readonly=True) as store:
        for run in store.runs():
            if run.experiment != "benchmark":
                continue
            cfg = run.config
            rows = store.episodes(run.run_id)
            if not rows:
                continue
            first = rows[0]
            arm = MethodRun(first.method, first.sensing, first.strategy)  # type: ignore[arg-type]
            groups.setdefault(cfg["family"], {})[arm] = rows
            params[first.method] = cfg.get("params", {})
            configs.setdefault(cfg["family"], cfg)
    return groups, params, configs


def write_benchmark_report(
    results: str | os.PathLike[str],
    directory: str | os.PathLike[str],
    *,
    against: str | None = None,
) -> Path:
    """Write ``benchmark.md`` and its figure from a benchmark results file; the paired
    differences are each row minus ``against`` (default :data:`DEFAULT_AGAINST`)."""
    groups, params, configs = read_benchmark(results)
    if not groups:
        raise FileNotFoundError(f"no benchmark runs in {results}")
    known = {m: i for i, m in enumerate(method_names())}
    present = {a.method for g in groups.values() for a in g}
    if against is not None and against not in present:
        raise InvalidArgumentError(
            f"--against {against}: no run of it in {results} (it holds "
            f"{', '.join(sorted(present))})"
        )
    reference = against or (
        DEFAULT_AGAINST if DEFAULT_AGAINST in present
        else min(present, key=lambda m: (known.get(m, len(known)), m))
    )  # fmt: skip
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    families = [f for f in BENCHMARK_FAMILIES if f in groups] + sorted(
        f for f in groups if f not in BENCHMARK_FAMILIES
    )
    strategies = sorted({a.strategy for g in groups.values() for a in g if a.sensing == "sensor"})
    words = " / ".join(_STRATEGY_WORDS.get(k, f"*{k}*") for k in strategies)
    chosen = "named with --against" if against else (
        "the default" if reference == DEFAULT_AGAINST
        else f"the first method of the run ({DEFAULT_AGAINST}, the default, did not run)"
    )  # fmt: skip
    table: dict[str, dict[MethodRun, dict[str, Any]]] = {}
    lines = [
        "# Benchmark — every method on the same episodes",
        "",
        "Outcomes are exclusive (success: goal reached with no contact; collision: a contact "
        "with a moving obstacle, which ends the episode; timeout: 3 × optimum + 100 steps, at "
        "most 1000). Excess = path length / optimum − 1 over successful episodes; the optimum "
        "is the shortest path to the goal's tolerance disc on the snapshot at t = 0 with the "
        "obstacles frozen (an agent may pass where a disc stood, so an excess can be slightly "
        "negative). Sensing: `sensor` = ranges + goal relative to the agent; `map` = "
        "plus the static world; `oracle` = plus obstacle positions and velocities; "
        "`future` = plus the obstacles' whole future (the clairvoyant bound only); "
        "strategy: the global direction every method at the level follows"
        + (f" ({words} at `sensor`)" if words else "")
        + ", the static route at `map` and `oracle`.",
        "",
        f"**Reference: {reference}** ({chosen}). Δ columns: the row minus {reference} at the "
        "same level and strategy (oracle and future rows: minus its `map` row) on the same "
        "episodes, in "
        "points, with 95 % bootstrap intervals (none on fewer than "
        f"{MIN_PAIRS} pairs); Δ excess over the episodes both succeeded in. *Versus* says "
        "which differences exclude zero: more or fewer successes, shorter or longer paths "
        f"than {reference}. n: the row's episodes. Steps to goal, clearance (the least "
        "surface distance to a moving obstacle over an episode, negative after a contact) "
        "and turning per step are medians; steps and turning over successful episodes. "
        "A row marked *(bound)* is a ceiling, not a method: `clairvoyant`, the share of "
        "episodes solvable at all (its plan replayed through the simulator; its path length "
        "is no yardstick, as the optimum is known only in retrospect). `model-oracle` is a "
        "reference planner, not a bound: it knows the present and the obstacles' motion "
        "model, not their future, and methods that know less match it in most families.",
        "",
    ]
    diffs: dict[str, dict[MethodRun, tuple[PairedDifference, PairedDifference] | None]] = {}
    for family in families:
        g = groups[family]
        arms = sorted(g, key=lambda a: _order(a, known))
        table[family] = {a: summarize_rows(g[a]) for a in arms}
        diffs[family] = {}
        for arm in arms:
            ref_arm = _reference_arm(reference, arm)
            ref = g.get(ref_arm)
            diffs[family][arm] = (
                None if arm == ref_arm else pair_episodes(g[arm], ref) if ref is not None
                else (_NO_DIFF, _NO_DIFF)
            )  # fmt: skip
    if len(families) > 1:
        lines += _overview(families, table, diffs, reference, known)
    else:  # one family: its table is the overview; what it says, in words, still
        lines += ["## Overview", "", *_said(families, table, diffs, reference)]
    for family in families:
        g = groups[family]
        arms = list(table[family])
        counts = {s["n"] for s in table[family].values()}
        n = max(counts)
        extent = f"{n} episodes" if len(counts) == 1 else f"up to {n} episodes; n per row"
        no_opt = max(s["no_optimum"] for s in table[family].values())
        lines += [
            f"## {_family_title(family)} ({extent})",
            "",
            *(
                [f"{no_opt} episode{'s have' if no_opt > 1 else ' has'} no path on the frozen "
                 "snapshot (moving obstacles block every passage at t = 0): no excess is "
                 f"measured for {'them' if no_opt > 1 else 'it'}.", ""]
                if no_opt else []
            ),  # fmt: skip
            "| method | sensing | strategy | n | success | collision | timeout | median excess "
            "| p90 excess | steps to goal | clearance | turning / step | decisions / s "
            f"| Δ success | Δ median excess | versus {reference} |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        for arm in arms:
            s = table[family][arm]
            pair = diffs[family][arm]
            d_s, d_e = pair if pair is not None else (_NO_DIFF, _NO_DIFF)
            label = _label(arm.method, reference)
            lines.append(
                f"| {label} | {arm.sensing} | {arm.strategy} | {s['n']} | {_pct(s['success'])} "
                f"| {_pct(s['collision'])} | {_pct(s['timeout'])} | {_pct(s['excess_median'])} "
                f"| {_pct(s['excess_p90'])} | {_num(s['time_to_goal'], '.0f')} "
                f"| {_num(s['clearance'], '.2f')} | {_num(s['turning'], '.0f')}° "
                f"| {_num(s['decisions_per_s'], ',.0f')} | {format_difference(d_s)} "
                f"| {format_difference(d_e)} "
                f"| {'reference' if pair is None else verdict(d_s, d_e)} |"
            )
        lines.append("")
        lines += physical_metrics(family, g, arms)
    fig = _figure_success_excess(table, out)
    lines += [f"![success against median excess]({fig.name})", "", "## Methods", ""]
    lines += ["| method | needs | what it is | parameters |", "|---|---|---|---|"]
    shown = sorted(present, key=lambda m: (known.get(m, len(known)), m))
    for name in shown:
        p = ", ".join(f"{k} = {v}" for k, v in params.get(name, {}).items()) or "—"
        needs: str
        try:
            spec = method_spec(name)
            needs, summary = spec.sensing, spec.summary or "—"
        except CopiError:  # a method of another package, not installed here
            needs, summary = "?", "(not registered in this copi: its package is not installed)"
        lines.append(f"| {name} | {needs} | {summary} | {p} |")
    report = out / "benchmark.md"
    write_text(report, "\n".join(lines) + "\n")
    return report
