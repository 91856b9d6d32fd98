"""The report of Experiment 1: summary table, Fig. 3 and Fig. 4, read back from results
files only (nothing is recomputed here)."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from copi._files import write_text
from copi.reports._figures import finish_figure, new_figure
from copi.reports._lifelong import write_lifelong_report
from copi.results import ResultsStore
from copi.world import World, draw_world

__all__ = ["Report", "summarize", "summarize_games", "warnings_for", "write_report"]

SUMMARY_COLUMNS = [
    ("method", "method"),
    ("sensing", "sensing"),
    ("where", "worlds"),
    ("episodes", "episodes"),
    ("success", "success"),
    ("contact", "collision"),
    ("timeout", "timeout"),
    ("excess_median", "median excess"),
    ("excess_mean", "mean excess"),
    ("excess_p90", "p90 excess"),
    ("decisions_per_s", "decisions / s"),
    ("decision_us", "µs / decision"),
    ("unfamiliar", "unfamiliar"),
    ("no_policy", "standing still"),
]

STILL_WARNING = 0.5
"""Above this share of steps with no motion (or of unfamiliar readings), a run is flagged."""


def warnings_for(method: str, s: dict[str, Any]) -> list[str]:
    """Plain warnings for a run whose agent mostly stood still or saw unfamiliar contexts
    (e.g. capabilities taken to a world unlike the ones they were learnt in)."""
    out = []
    if s.get("episodes", 0) and s.get("success") == 0.0:
        hints = []
        if s.get("timeout", 0.0) >= 0.5:
            hints.append("most episodes timed out: a method that cannot find its way "
                         "(copi-faithful has no escape: try the default learnt preset, "
                         "copi learn without --preset) or a step limit too low (--max-steps)")
        if s.get("contact", 0.0) >= 0.5:
            hints.append("most episodes ended in a collision: try a method that avoids "
                         "moving obstacles (copi-learnt, compass-guard, dwa)")
        out.append(f"{method}: no episode succeeded" + (f"; {'; '.join(hints)}" if hints else
                                                        ""))  # fmt: skip
    if s.get("no_policy", 0.0) > STILL_WARNING:
        out.append(
            f"{method} commanded no motion in {100 * s['no_policy']:.0f} % of steps: for "
            "copi's methods its contexts there map to templates with no policy, i.e. the "
            "worlds are unlike those the capabilities were learnt in (learn them in such "
            "worlds, or use copi-extended, whose guard escapes when no policy is offered)"
        )
    if s.get("unfamiliar", 0.0) > STILL_WARNING:
        out.append(
            f"{method} saw unfamiliar readings in {100 * s['unfamiliar']:.0f} % of steps: the "
            "capabilities were learnt in other kinds of worlds (try --continual, or learn "
            "in worlds like these)"
        )
    return out


def summarize(rows: list[Any]) -> dict[str, Any]:
    """Summary of one method's episodes. Excess statistics are over successful episodes
    (reached, no contact), as in the paper. Skipped episodes (no valid task in their
    world) count in no rate; ``skipped`` says how many there were."""
    skipped = sum(r.get("outcome") == "skipped" for r in rows)
    reason = next((r.get("reason") for r in rows if r.get("outcome") == "skipped"), None)
    rows = [r for r in rows if r.get("outcome") != "skipped"]
    n = len(rows)
    if n == 0:
        return {"episodes": 0, "skipped": skipped, "skip_reason": reason}
    success = np.array([r["success"] for r in rows], dtype=bool)
    excess = np.array(
        [r["excess"] for r in rows if r["success"] and r["excess"] is not None], dtype=float
    )
    dec = np.array([r["decision_us"] for r in rows if r["decision_us"] is not None], dtype=float)
    steps = np.array([r["steps"] for r in rows], dtype=float)
    # The median over episodes of each episode's mean decision time (as the benchmark and
    # the README quote it; a step-weighted mean lets a few long episodes dominate).
    mean_us = float(np.median(dec)) if len(dec) else math.nan
    return {
        "episodes": n,
        "success": float(success.mean()),
        "reached": float(np.mean([r["reached"] for r in rows])),
        "contact": float(np.mean([r["collided"] for r in rows])),
        "timeout": float(np.mean([r["timed_out"] for r in rows])),
        "excess_median": float(np.median(excess)) if len(excess) else math.nan,
        "excess_mean": float(excess.mean()) if len(excess) else math.nan,
        "excess_p90": float(np.percentile(excess, 90)) if len(excess) else math.nan,
        "decision_us": mean_us,
        "decisions_per_s": 1e6 / mean_us if mean_us > 0 else math.nan,
        "unfamiliar": float(np.mean([r["unfamiliar"] or 0.0 for r in rows])),
        "no_policy": float(sum(r["no_policy"] or 0 for r in rows) / max(steps.sum(), 1.0)),
        "no_optimum": int(sum(r["optimal_length"] is None for r in rows)),
        "skipped": skipped,
        "skip_reason": reason,
    }


def _fmt(key: str, value: Any) -> str:
    if isinstance(value, str):
        return value
    if key in ("episodes",):
        return str(value)
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "—"
    if key in ("success", "contact", "timeout", "unfamiliar", "no_policy") or key.startswith(
        "excess"
    ):
        return f"{100 * value:.1f} %"
    if key == "decisions_per_s":
        return f"{value:,.0f}"
    return f"{value:.2f}"


_OUTCOME_COLOURS = {"success": "#2ca02c", "collision": "#d62728", "timeout": "#666666"}


def _outcome_title(t: dict[str, Any]) -> tuple[str, str]:
    """A panel's title (episode, outcome, when) and its colour."""
    steps = len(t["path"]) - 1
    outcome = t.get("outcome")
    words = {
        "success": f"success in {steps} steps",
        "collision": f"collision at step {steps}",
        "timeout": f"timeout after {steps} steps",
    }.get(outcome or "", f"{steps} steps (outcome not recorded)")
    return f"episode {t['episode']}: {words}", _OUTCOME_COLOURS.get(outcome or "", "black")


def _fig3(trajectories: list[dict[str, Any]], out: Path, method: str) -> Path | None:
    """The first four recorded episodes: the agent's path in red from its start (ring),
    the obstacles' traces in blue with the discs where they were when the episode ended,
    the goal; each panel titled with its outcome, and a collision marked where it
    happened."""
    picks = trajectories[:4]
    if not picks:
        return None
    fig = new_figure(3.4 * len(picks), 3.9)
    for i, t in enumerate(picks):
        ax = fig.add_subplot(1, len(picks), i + 1)
        world = World.from_dict(t["world"])
        traces = np.asarray(t["traces"])
        path = np.asarray(t["path"])
        draw_world(
            ax, world, centers=traces[-1], radii=t["radii"], traces=traces, path=path,
            start=path[0], goal=t["goal"],
        )  # fmt: skip
        title, colour = _outcome_title(t)
        ax.set_title(title, fontsize=8.5, color=colour)
        if t.get("outcome") == "collision":
            ax.plot(*path[-1], marker="o", ms=13, mfc="none", mec="black", mew=1.4, zorder=8)
    fig.suptitle(
        f"Fig. 3 — {method}: the agent's path (red, from the ring) to the goal (star); "
        "obstacles' traces (blue), their discs drawn at their final positions; "
        "a black ring marks a collision",
        fontsize=8.5,
    )
    return finish_figure(fig, out / f"fig3_{_slug(method)}.png")


def _fig4(excess: dict[str, np.ndarray], out: Path) -> Path:
    """Histogram of path excess over the stationary optimum, in %, per method, its median
    marked in the method's colour (paper Fig. 4). Excesses above the 98th percentile of
    the pooled episodes go into one last bin, labelled with its threshold."""
    from matplotlib import colormaps

    fig = new_figure(7.0, 4.2)
    ax = fig.add_subplot()
    finite = {m: 100 * e[np.isfinite(e)] for m, e in excess.items()}
    pooled = np.concatenate([e for e in finite.values()] + [np.zeros(0)])
    hi = max(float(np.percentile(pooled, 98)) if len(pooled) else 0.0, 50.0)
    width = hi / 40
    bins = np.append(np.linspace(0, hi, 41), hi + width)  # the last bin: everything above
    plotted = False
    over: list[tuple[int, Any]] = []
    for k, (method, e) in enumerate(finite.items()):
        if not len(e):
            continue
        c = colormaps["tab10"](k % 10)
        clipped = np.minimum(e, hi + width / 2)
        ax.hist(clipped, bins=bins, color=c, alpha=0.35, histtype="stepfilled")
        ax.hist(clipped, bins=bins, color=c, lw=1.0, histtype="step",
                label=f"{method} ({len(e)} successful episodes)")  # fmt: skip
        med = float(np.median(e))
        ax.axvline(med, color=c, lw=1.5, ls="--", label=f"{method}: median {med:.1f} %")
        over.append((int((e > hi).sum()), c))
        plotted = True
    top = ax.get_ylim()[1]
    for k, (count, c) in enumerate(over):  # how many each method has in the last bin
        ax.text(hi + width / 2, top * (0.3 + 0.07 * k), str(count), color=c, fontsize=7,
                ha="center")  # fmt: skip
    ax.axvspan(hi, hi + width, color="#eeeeee", zorder=0)
    ticks = [t for t in ax.get_xticks() if 0 <= t < hi - width]
    ax.set_xticks([*ticks, hi + width / 2])
    ax.set_xticklabels([f"{t:.0f}" for t in ticks] + [f"> {hi:.0f}"])
    ax.set_xlim(0, hi + width)
    ax.set_xlabel("path excess over the stationary optimum, % (path / optimal − 1)")
    ax.set_ylabel("episodes")
    if plotted:
        ax.legend(fontsize=8)
    else:
        ax.text(0.5, 0.5, "no successful episode", transform=ax.transAxes, ha="center")
    return finish_figure(fig, out / "fig4_excess.png")


def summarize_games(rows: list[Any]) -> dict[str, Any]:
    """Summary of one Experiment 2 method's games."""
    n = len(rows)
    if n == 0:
        return {"games": 0}
    survival = np.array([r["survival"] for r in rows], dtype=float)
    return {
        "games": n,
        "capture": float(np.mean([r["captured"] for r in rows])),
        "collision": float(np.mean([r.get("outcome") == "collision" for r in rows])),
        "escaped": float(
            np.mean(
                [
                    r.get("outcome", "escaped" if not r["captured"] else "") == "escaped"
                    for r in rows
                ]
            )
        ),  # fmt: skip
        "survival_mean": float(survival.mean()),
        "survival_median": float(np.median(survival)),
        "contact_games": float(np.mean([r["contacts"] > 0 for r in rows])),
        "contacts_per_100": float(100 * sum(r["contacts"] for r in rows) / survival.sum()),
    }


def _fig5(runs: dict[str, list[dict[str, Any]]], out: Path) -> Path | None:
    """Three games, the stationary world above and the dynamic one below: the car's path
    in red, the evader's in blue (the paper's Fig. 5)."""
    rows = [
        ("static", runs.get("capability-static", [])),
        ("dynamic", runs.get("capability-dynamic", [])),
    ]
    rows = [(name, t[:3]) for name, t in rows if t]
    if not rows:
        return None
    cols = max(len(t) for _, t in rows)
    fig = new_figure(3.4 * cols, 3.4 * len(rows))
    for r, (name, trajs) in enumerate(rows):
        for c, t in enumerate(trajs):
            ax = fig.add_subplot(len(rows), cols, r * cols + c + 1)
            world = World.from_dict(t["world"])
            traces = np.asarray(t["traces"])
            draw_world(
                ax,
                world,
                centers=traces[-1] if traces.size else None,
                radii=t["radii"] if traces.size else None,
                traces=traces if traces.size else None,
                title=f"({'i' if name == 'static' else 'ii'}) game {t['episode']}"
                + (" — captured" if t["captured"] else " — escaped"),
            )
            car = np.asarray(t["pursuer"])
            ev = np.asarray(t["evader"])
            ax.plot(car[:, 0], car[:, 1], color="#d62728", lw=1.2)
            ax.plot(ev[:, 0], ev[:, 1], color="#1f4e99", lw=1.2)
            ax.plot(*car[0], "o", color="#d62728", ms=4)
            ax.plot(*ev[0], "o", color="#1f4e99", ms=4)
    fig.suptitle(
        "Fig. 5 — pursuer (red) and capability evader (blue): (i) stationary, (ii) dynamic",
        fontsize=9,
    )
    return finish_figure(fig, out / "fig5_pursuit.png")


def _slug(s: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in s).strip("_").lower() or "run"


def write_report(
    results: list[str | os.PathLike[str]], directory: str | os.PathLike[str]
) -> Report:
    """Write ``report.md`` and its figures for one or more results files."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    summaries: list[dict[str, Any]] = []
    excess: dict[str, np.ndarray] = {}
    figures: list[Path] = []
    runs_info: list[str] = []
    for path in results:
        with ResultsStore(path, readonly=True) as store:
            for run in store.runs():
                if run["experiment"] != "navigation":
                    continue
                rows = store.episodes(run["run_id"])
                cfg = run["config"]
                sensing = cfg.get("sensing", "map")
                # one method at two levels (or in two families) is two rows, two curves
                # and two Fig. 3 files, each named by its level and worlds
                world_file = cfg.get("world_file")
                short = (f"worlds of {Path(str(world_file)).name}" if world_file
                         else cfg.get("family", "star"))  # fmt: skip
                label = f"{run['method']} ({sensing}, {short})"
                s = summarize(rows)
                s["method"], s["sensing"], s["where"] = run["method"], sensing, short
                summaries.append(s)
                excess[label] = np.array(
                    [r["excess"] for r in rows if r["success"] and r["excess"] is not None],
                    dtype=float,
                )
                where = (
                    f"the worlds of {Path(str(world_file)).name if world_file else 'a world file'}"
                    f" (content {str(cfg['world_file_sha'])[:12]})"
                    if cfg.get("world_file_sha") else f"family {cfg.get('family', 'star')}"
                )  # fmt: skip
                guard = cfg.get("guard")
                runs_info.append(
                    f"- **{label}** (`{Path(path).name}`, run {run['run_id']}): {cfg['worlds']} "
                    f"episodes, seed {cfg['seed']}, {where}, "
                    f"sensing {cfg.get('sensing', 'map')}, "
                    f"guard {'the method’s' if guard is None else guard}, "
                    f"max steps {cfg['max_steps']}, contact ends episode "
                    f"{cfg.get('end_on_contact', False)}; copi {run['versions'].get('copi')}"
                    + (f"; {s['skipped']} episodes skipped (no valid task)" if s["skipped"] else "")
                )
                fig = _fig3(store.trajectories(run["run_id"], run["method"]), out, label)
                if fig is not None:
                    figures.append(fig)
    games: list[dict[str, Any]] = []
    game_traj: dict[str, list[dict[str, Any]]] = {}
    games_info: list[str] = []
    for path in results:
        with ResultsStore(path, readonly=True) as store:
            for run in store.runs():
                if run["experiment"] != "pursuit":
                    continue
                g = summarize_games(store.games(run["run_id"]))
                g["method"] = run["method"]
                games.append(g)
                game_traj[run["method"]] = store.trajectories(run["run_id"], run["method"])
                cfg = run["config"]
                games_info.append(
                    f"- **{run['method']}** (`{Path(path).name}`, run {run['run_id']}): "
                    f"{cfg['games']} games, seed {cfg['seed']}, evader {cfg['evader']}, "
                    f"{'moving' if cfg['dynamic'] else 'stationary'} obstacles, horizon "
                    f"{cfg['horizon']}, guard {cfg.get('guard')}, speed ratio "
                    f"{cfg.get('gamma')}, turn radius {cfg.get('turn_radius')}, capture "
                    f"radius {cfg.get('capture_radius')}, contact ends game "
                    f"{cfg.get('contact_ends', False)}, capabilities "
                    f"{str(cfg.get('capabilities_sha', ''))[:12] or '?'}; copi "
                    f"{run['versions'].get('copi')}"
                )
    lifelong: list[Path] = []
    for path in results:
        with ResultsStore(path, readonly=True) as store:
            has_lives = bool(store.lifelong())
        if has_lives:
            name = "lifelong.md" if not lifelong else f"lifelong-{len(lifelong) + 1}.md"
            lifelong.append(write_lifelong_report(path, out / name))
    if not summaries and not games and not lifelong:
        raise FileNotFoundError(f"no experiment runs in {', '.join(map(str, results))}")
    if summaries:
        figures.append(_fig4(excess, out))
    fig5 = _fig5(game_traj, out)
    summaries_md: dict[str, str] = {}
    lines = []
    if summaries:
        head, rest = _experiment1_lines(summaries, runs_info, figures)
        summaries_md["Experiment 1"] = "\n".join(head)
        lines += head + rest
    if games:
        head = [
            "# Experiment 2 — the homicidal chauffeur",
            "",
            "The evader plays the game's strategy; the capability evader instantiates it "
            "through the learnt capabilities (walls and moving obstacles avoided), the game "
            "evader uses it as its velocity. A contact with a moving obstacle ends the game "
            "as a loss for the evader (collision), as in navigation. Outcomes are exclusive: "
            "capture, collision, escape (the horizon survived). Survival in time steps until "
            "capture or collision (the horizon on escape).",
            "",
            "| method | games | capture | collision | escape | mean survival | median survival "
            "| games with contact | contacts / 100 steps |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for g in games:
            head.append(
                f"| {g['method']} | {g['games']} | {100 * g['capture']:.1f} % | "
                f"{100 * g['collision']:.1f} % | {100 * g['escaped']:.1f} % | "
                f"{g['survival_mean']:.1f} | {g['survival_median']:.1f} | "
                f"{100 * g['contact_games']:.1f} % | {g['contacts_per_100']:.2f} |"
            )
        summaries_md["Experiment 2"] = "\n".join(head)
        lines += [*head, "", "Runs:", *games_info, ""]
        if fig5 is not None:
            lines.append(f"![{fig5.stem}]({fig5.name})")
    for i, part in enumerate(lifelong):
        text = part.read_text(encoding="utf-8")
        summaries_md["Experiment 3" if i == 0 else f"Experiment 3 ({i + 1})"] = text.split(
            "\n\nGoals:"
        )[0]
        lines += ["", text]
    report = out / "report.md"
    write_text(report, "\n".join(lines) + "\n")
    return Report(report, summaries_md)


@dataclass(frozen=True)
class Report:
    """A written report: its file, and each experiment's summary (its table) as Markdown."""

    path: Path
    summaries: dict[str, str]

    def __fspath__(self) -> str:
        return str(self.path)

    def __str__(self) -> str:
        return str(self.path)


def _experiment1_lines(
    summaries: list[dict[str, Any]], runs_info: list[str], figures: list[Path]
) -> tuple[list[str], list[str]]:
    lines = [
        "# Experiment 1 — reaching goals in dynamic worlds",
        "",
        "Outcomes are exclusive: success (goal reached, no contact), collision (a contact "
        "with a moving obstacle, which ends the episode), timeout. Path excess = agent path "
        "length / optimal length − 1 over successful episodes, as in the paper's Fig. 4; the "
        "optimum is the shortest path to the goal's tolerance disc on the stationary "
        "snapshot at t = 0 (obstacles frozen). An agent may pass later where a disc stood "
        "at t = 0, so an excess can be (slightly) negative.",
        "",
        "| " + " | ".join(h for _, h in SUMMARY_COLUMNS) + " |",
        "|" + "---|" * len(SUMMARY_COLUMNS),
    ]
    for s in summaries:
        lines.append("| " + " | ".join(_fmt(k, s.get(k)) for k, _ in SUMMARY_COLUMNS) + " |")
    flagged = [w for s in summaries for w in warnings_for(str(s.get("method")), s)]
    if flagged:
        lines += ["", *[f"**Warning**: {w}." for w in flagged]]
    rest = ["", "Runs:", *runs_info, ""]
    rest += [f"![{f.stem}]({f.name})" for f in figures]
    rest.append("")
    return lines, rest
