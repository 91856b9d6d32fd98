"""Experiment 3's report: success and median excess early and late in each life, paired
differences of copi's causal map against every other method on the same late tasks
(95 % bootstrap intervals resampling whole lives, since the tasks of a life are not
independent), the issue's goals measured, and a figure against task index. Read back
from the results store only."""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

from copi._files import write_text
from copi.methods import LIFELONG_METHODS, LIFELONG_REFERENCE, MethodRun
from copi.reports._figures import finish_figure, new_figure
from copi.results import PairedDifference, ResultsStore, lives_difference, statistic

__all__ = [
    "lifelong_blocks",
    "lifelong_report_paths",
    "write_lifelong_report",
]

CAUSAL = LIFELONG_REFERENCE.label
"""The arm every other row is paired against."""
CONTINUAL = "copi-learnt-continual@sensor:causal"


def _label(r: Any) -> str:
    return MethodRun(r["method"], r["sensing"], r["strategy"]).label


def lifelong_blocks(tasks: int) -> tuple[range, range]:
    """The early and late tasks compared: 1-10 and the last 10 (41-50 of 50) when a life
    has 20 tasks or more, else its first and last fifth (one task at least)."""
    k = 10 if tasks >= 20 else max(1, tasks // 5)
    return range(0, k), range(tasks - k, tasks)


def _pct(x: float) -> str:
    return "–" if not math.isfinite(x) else f"{100 * x:.1f}"


def _diff(d: PairedDifference) -> str:
    if d.n == 0 or not math.isfinite(d.estimate):
        return "–"
    if not math.isfinite(d.low):
        return f"{100 * d.estimate:+.1f}"
    return f"{100 * d.estimate:+.1f} [{100 * d.low:+.1f}, {100 * d.high:+.1f}]"


def _by_life(rows: list[Any], tasks: range) -> dict[int, list[Any]]:
    out: dict[int, list[Any]] = {}
    for r in rows:
        if r["task"] in tasks:
            out.setdefault(int(r["life"]), []).append(r)
    return out


def _figure_lifelong(by_method: dict[str, list[Any]], tasks: int, out: Path) -> Path:
    fig = new_figure(14.0, 3.8)
    ax_s, ax_e, ax_u = fig.subplots(1, 3)
    width = max(1, tasks // 10)  # tasks per point
    for name, rows in by_method.items():
        xs, succ, exc, unf = [], [], [], []
        for start in range(0, tasks, width):
            block = [r for r in rows if start <= r["task"] < start + width]
            if not block:
                continue
            xs.append(start + 1 + (width - 1) / 2)
            succ.append(100 * statistic(block, "success"))
            exc.append(100 * statistic(block, "excess"))
            unf.append(100 * statistic(block, "unfamiliar"))
        style = "-" if name.startswith("copi") else "--"
        ax_s.plot(xs, succ, style, marker="o", ms=3, label=name)
        ax_e.plot(xs, exc, style, marker="o", ms=3, label=name)
        if name.startswith("copi"):
            ax_u.plot(xs, unf, style, marker="o", ms=3, label=name)
        else:
            ax_u.plot([], [], style, label=name)  # the same colours in every panel
    for ax, what in ((ax_s, "success (%)"), (ax_e, "median excess (%)"),
                     (ax_u, "unfamiliar readings (%)")):  # fmt: skip
        ax.set_xlabel(f"task index (mean of {width})" if width > 1 else "task index")
        ax.set_ylabel(what)
        ax.grid(alpha=0.3)
    ax_u.legend(fontsize=7, frameon=False)
    return finish_figure(fig, out)


def lifelong_report_paths(results: str | os.PathLike[str]) -> tuple[Path, Path]:
    """Where ``copi lifelong -o RESULTS`` writes its report and figure: RESULTS with the
    suffix ``.md`` and ``.png`` (check them with :func:`copi._files.check_outputs`: a
    store named ``x.md`` would be its own report)."""
    p = Path(results)
    return p.with_suffix(".md"), p.with_suffix(".png")


def write_lifelong_report(
    results: str | os.PathLike[str], markdown: str | os.PathLike[str]
) -> Path:
    """Write Experiment 3's report (``markdown``, and a figure beside it with the same
    name and ``.png``) from the ``lifelong`` table of ``results``."""
    with ResultsStore(results, readonly=True) as store:
        rows = [r for r in store.lifelong() if r["outcome"] != "skipped"]
        runs = {r["run_id"]: r for r in store.runs() if r["experiment"] == "lifelong"}
    target = Path(markdown)
    if not rows:
        write_text(target, "# Experiment 3 — lifelong\n\nNo lifelong results yet.\n")
        return target
    # One section per (family, seed, tasks): only runs of the same lives are compared.
    groups: dict[tuple[str, int, int], list[str]] = {}
    for rid, run in runs.items():
        cfg = run["config"]
        key = (str(cfg.get("family")), int(cfg.get("seed", 0)), int(cfg.get("tasks", 0)))
        groups.setdefault(key, []).append(rid)
    lines: list[str] = []
    for i, (_, rids) in enumerate(sorted(groups.items())):
        group_rows = [r for r in rows if r["run_id"] in rids]
        if not group_rows:
            continue
        fig = target.with_suffix(".png") if i == 0 else target.with_name(
            f"{target.stem}-{i + 1}.png"
        )
        lines += _section(group_rows, {rid: runs[rid] for rid in rids}, fig)
    write_text(target, "\n".join(lines) + "\n")
    return target


def _section(rows: list[Any], runs: dict[str, Any], figure: Path) -> list[str]:
    """The report of the runs of one family, seed and number of tasks."""
    counts: dict[str, int] = {}
    arm_of: dict[str, str] = {}
    for r in rows:
        arm_of.setdefault(r["run_id"], _label(r))
    for label in arm_of.values():
        counts[label] = counts.get(label, 0) + 1
    by_method: dict[str, list[Any]] = {}
    for r in rows:  # an arm run twice here (e.g. from saved maps) shows each run apart
        label = arm_of[r["run_id"]]
        label = label if counts[label] == 1 else f"{label} ({r['run_id'][:8]})"
        by_method.setdefault(label, []).append(r)
    order = [m for m in LIFELONG_METHODS if m in by_method] + sorted(
        m for m in by_method if m not in LIFELONG_METHODS
    )
    by_method = {m: by_method[m] for m in order}
    tasks = 1 + max(int(r["task"]) for r in rows)
    lives = len({int(r["life"]) for r in rows})
    per_arm = {m: len({int(r["life"]) for r in rs}) for m, rs in by_method.items()}
    extents = "" if len(set(per_arm.values())) == 1 else "; fewer for some rows: see lives"
    families = sorted({r["family"] for r in rows})
    early, late = lifelong_blocks(tasks)
    e_name = f"{early.start + 1}–{early.stop}"
    l_name = f"{late.start + 1}–{late.stop}"
    lines = [
        "# Experiment 3 — lifelong",
        "",
        f"Family {', '.join(families)}; {lives} worlds (lives{extents}), {tasks} successive "
        "tasks in "
        "each; every method meets the same tasks (task t starts at task t − 1's goal; "
        "obstacles drawn anew per task). A method keeps from task to task what its row "
        "says. Success and median excess (%) over tasks "
        f"{e_name} and {l_name} of every life; unfamiliar: share of decisions whose "
        "reading was unfamiliar.",
        "",
        f"| method | sensing | strategy | keeps | success {e_name} | success {l_name} "
        f"| excess {e_name} | excess {l_name} | unfamiliar {e_name} | unfamiliar {l_name} "
        "| µs/decision | lives |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    summary: dict[str, dict[str, float]] = {}
    for name, rs in by_method.items():
        keeps = {"causal": "causal map + grid", "mapping": "grid"}.get(rs[0]["strategy"],
                                                                        "nothing")  # fmt: skip
        if rs[0]["method"].endswith("-continual"):
            keeps += " + grown contexts"
        a = [r for r in rs if r["task"] in early]
        b = [r for r in rs if r["task"] in late]
        s = {
            "success_early": statistic(a, "success"), "success_late": statistic(b, "success"),
            "excess_early": statistic(a, "excess"), "excess_late": statistic(b, "excess"),
            "unfamiliar_early": statistic(a, "unfamiliar"),
            "unfamiliar_late": statistic(b, "unfamiliar"),
            "decision_us": statistic(rs, "decision_us"),
        }  # fmt: skip
        summary[name] = s
        unf = (
            (_pct(s["unfamiliar_early"]), _pct(s["unfamiliar_late"]))
            if name.startswith("copi")
            else ("–", "–")
        )
        bold = f"**{name}**" if name.startswith("copi") else name
        lines.append(
            f"| {bold} | {rs[0]['sensing']} | {rs[0]['strategy']} | {keeps} "
            f"| {_pct(s['success_early'])} | {_pct(s['success_late'])} "
            f"| {_pct(s['excess_early'])} | {_pct(s['excess_late'])} "
            f"| {unf[0]} | {unf[1]} | {s['decision_us']:.0f} | "
            f"{len({int(r['life']) for r in rs})} |"
        )
    if CAUSAL in by_method:
        ref = _by_life(by_method[CAUSAL], late)
        lines += [
            "",
            f"Paired on tasks {l_name} (same lives, same tasks): {CAUSAL} minus each method, "
            "Δ success (points) and Δ median excess (points, tasks both succeeded in), 95 % "
            "bootstrap intervals resampling lives. ▲/▽: the interval excludes zero "
            "(▲ copi better).",
            "",
            "| versus | Δ success | Δ median excess |",
            "|---|---|---|",
        ]
        for name, rs in by_method.items():
            if name == CAUSAL:
                continue
            other = _by_life(rs, late)
            ds = lives_difference(ref, other, "success")
            de = lives_difference(ref, other, "excess")
            mark_s = ("▲" if ds.estimate > 0 else "▽") if ds.excludes_zero else ""
            mark_e = ("▲" if de.estimate < 0 else "▽") if de.excludes_zero else ""
            lines.append(f"| {name} | {_diff(ds)} {mark_s} | {_diff(de)} {mark_e} |")
    lines += ["", *_goals(summary, by_method, late), ""]
    fig = _figure_lifelong(by_method, tasks, figure)
    lines += [f"![success and excess against task index]({fig.name})", ""]
    lines += ["Runs:", ""]
    for rid, run in sorted(runs.items(), key=lambda kv: arm_of.get(kv[0], kv[1]["method"])):
        cfg = run["config"]
        lines.append(
            f"- {arm_of.get(rid, run['method'])}: run {rid}, family {cfg.get('family')}, "
            f"seed {cfg.get('seed')}, "
            f"{cfg.get('tasks')} tasks, copi {cfg.get('code')}"
        )
    return lines + [""]


def _goals(
    s: dict[str, dict[str, float]], by_method: dict[str, list[Any]], late: range
) -> list[str]:
    """The issue's goals, measured (each says met or not, with its numbers)."""
    out = ["Goals:", ""]

    def verdict(ok: bool) -> str:
        return "met" if ok else "**not met**"

    c = s.get(CAUSAL)
    if c is not None:
        half = c["excess_late"] <= 0.5 * c["excess_early"]
        out.append(
            f"- {CAUSAL}: median excess late {_pct(c['excess_late'])} vs early "
            f"{_pct(c['excess_early'])} (goal: at most half): {verdict(half)}."
        )
        if "copi-learnt@map" in by_method:
            a, b, on = _late_on_common_lives(by_method[CAUSAL], by_method["copi-learnt@map"],
                                             late)  # fmt: skip
            out.append(
                f"- {CAUSAL} late success {_pct(a)} vs the learnt preset at the map level "
                f"{_pct(b)}{on} (goal: at least as high): {verdict(a >= b)}."
            )
        ref = _by_life(by_method[CAUSAL], late)
        beaten = []
        for name, rs in by_method.items():
            if rs[0]["strategy"] != "mapping":
                continue
            other = _by_life(by_method[name], late)
            ds = lives_difference(ref, other, "success")
            de = lives_difference(ref, other, "excess")
            win = (ds.excludes_zero and ds.estimate > 0) or (de.excludes_zero and de.estimate < 0)
            beaten.append((name, win))
        if beaten:
            ok = all(w for _, w in beaten)
            lost = ", ".join(n for n, w in beaten if not w) or "none"
            out.append(
                f"- {CAUSAL} beats every mapping method that keeps its grid on the late tasks "
                f"(success or median excess, interval excluding zero): {verdict(ok)} "
                f"(not beaten: {lost})."
            )
    g = s.get(CONTINUAL)
    if g is not None and c is not None and not g["unfamiliar_early"] > 0:
        out.append("- continual growth: no unfamiliar readings early in life, nothing to lower.")
    elif g is not None and c is not None:
        halved = g["unfamiliar_late"] <= 0.5 * g["unfamiliar_early"]
        a, b, on = _late_on_common_lives(by_method[CONTINUAL], by_method[CAUSAL], late)
        out.append(
            f"- continual growth: unfamiliar {_pct(g['unfamiliar_early'])} → "
            f"{_pct(g['unfamiliar_late'])} (goal: at least halved): {verdict(halved)}; late "
            f"success {_pct(a)} vs {_pct(b)} without growth{on} (goal: not lower): "
            f"{verdict(a >= b)}."
        )
    return out


def _late_on_common_lives(a: list[Any], b: list[Any], late: range) -> tuple[float, float, str]:
    """Late success of two methods over the lives both ran (a rate over 4 lives is not set
    against one over 1), and the words saying so when either ran others too."""
    common = {int(r["life"]) for r in a} & {int(r["life"]) for r in b}
    rate = [statistic([r for r in rows if r["task"] in late and int(r["life"]) in common],
                      "success") for rows in (a, b)]  # fmt: skip
    every = {int(r["life"]) for r in a} | {int(r["life"]) for r in b}
    on = "" if common == every else f" (on the {len(common)} lives both ran)"
    return rate[0], rate[1], on
