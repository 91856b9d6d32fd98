"""What copi-predictive's planner size costs and buys: docs/predictive-cost.md.

    python studies/predictive_cost.py --episodes 100

copi-predictive plans over ``samples`` futures of ``horizon`` steps drawn from its learnt
model (:class:`copi.online.PredictiveAgent`); a decision's time grows with both. Each
setting of :data:`SETTINGS` runs on the same validation episodes (seed 1, the families
copi-predictive was tuned on), in one process, its ``act`` timed around each call; success
is paired with the registered setting's on the same episodes. Nothing here changes the
registered method: it measures how far the 1 ms a decision its issue asks for is, and what
a smaller planner would give up. Its capabilities: the predictive preset's, learnt once
into ``--caps`` (``copi learn --preset predictive``).
"""

from __future__ import annotations

import argparse
import inspect
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from copi.learning import Capabilities  # noqa: E402
from copi.online import PredictiveAgent  # noqa: E402
from copi.results import paired_difference  # noqa: E402
from copi.runs import Episode  # noqa: E402
from studies._common import (  # noqa: E402
    drawn_episodes,
    interval,
    predictive_capabilities,
    timed_acts,
)

SETTINGS = [(32, 12, 1), (32, 20, 1), (32, 10, 1), (16, 12, 1), (8, 12, 1), (16, 10, 1),
            (16, 8, 1), (32, 12, 2), (32, 12, 4), (32, 12, 8)]
"""(samples, horizon, together): the registered setting first. ``together`` futures are
valued as one (:class:`copi.planning.futures.FuturesPlanner`): a way must clear the discs
of all of them, which makes hindsight's plans less clairvoyant and fewer to solve."""
FAMILIES = ("crowd", "indoor")
VALIDATION_SEED = 1


def run(caps: Capabilities, samples: int, horizon: int, together: int,
        episodes: list[Episode]) -> tuple[list[bool], list[float]]:  # fmt: skip
    """Each episode's success and each decision's seconds."""
    agent = PredictiveAgent(caps, samples=samples, horizon=horizon, together=together)
    took = timed_acts(agent)
    won = [e.run(agent, sensing="map").outcome == "success" for e in episodes]
    return won, took


PARTS = (
    ("following the bodies (tracker)", "copi.learning._tracking", "MotionTracker.update"),
    ("", "copi.learning._tracking", "MotionTracker.bodies"),
    ("drawing the futures", "copi.online._predictive", "sample_motion"),
    ("the safety network", "copi.online._predictive", "PredictiveAgent.move_costs"),
    ("the window's grids", "copi.planning.futures", "window"),
    ("valuing the window (hindsight)", "copi.planning.futures", "hindsight_values"),
    ("the first move's check", "copi.planning.futures", "escape_move"),
)
"""The parts of a decision :func:`breakdown` times: (row, module, name there; a row of
"" adds to the row above it)."""


def breakdown(caps: Capabilities, episodes: list[Episode]) -> dict[str, list[float]]:
    """Each part of the registered setting's decisions timed apart (seconds, one entry a
    decision): each of :data:`PARTS` wrapped in a timer where ``act`` finds it, for the
    length of this call only, and ``act`` itself around them ("everything", whose rest
    is the glue between the parts)."""
    import importlib

    took: dict[str, list[float]] = {"everything": []}
    saved = []
    agent = PredictiveAgent(caps)

    def timed(row: str, f):  # type: ignore[no-untyped-def]
        def g(*args, **kw):  # type: ignore[no-untyped-def]
            t0 = time.perf_counter()
            out = f(*args, **kw)
            took[row][-1] += time.perf_counter() - t0
            return out
        return g

    row = ""
    for label, module, name in PARTS:
        row = label or row
        took.setdefault(row, [])
        owner: Any = importlib.import_module(module)
        attr = name
        if "." in name:
            owner, attr = getattr(owner, name.split(".")[0]), name.split(".")[1]
        saved.append((owner, attr, getattr(owner, attr)))
        setattr(owner, attr, timed(row, getattr(owner, attr)))
    plain = agent.act

    def act(obs):  # type: ignore[no-untyped-def]
        for v in took.values():
            v.append(0.0)
        return timed("everything", plain)(obs)

    agent.act = act  # type: ignore[method-assign]
    try:
        for e in episodes:
            e.run(agent, sensing="map")
    finally:
        for owner, attr, f in saved:
            setattr(owner, attr, f)
    return took


def figure(rows: list[dict], out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(FAMILIES), figsize=(9, 3.6), sharey=False)
    for ax, fam in zip(axes, FAMILIES, strict=True):
        for r in rows:
            ms, ok = r[fam]["ms"], 100 * r[fam]["success"]
            ax.plot(ms, ok, "o", color="C0" if r["registered"] else "C1")
            tag = "" if r["together"] == 1 else f" /{r['together']}"
            ax.annotate(f"{r['samples']}×{r['horizon']}{tag}", (ms, ok), fontsize=7,
                        xytext=(4, 3), textcoords="offset points")  # fmt: skip
        ax.axvline(1.0, color="0.5", ls="--", lw=1)
        ax.set_xscale("log")
        ax.set_xticks([1, 2, 4, 8], ["1", "2", "4", "8"])
        ax.minorticks_off()
        ax.set_title(fam, fontsize=9)
        ax.set_xlabel("ms a decision (median; dashed: the 1 ms goal)")
        ax.set_ylabel("success on validation episodes (%)")
        ax.grid(alpha=0.3)
    fig.suptitle("copi-predictive: futures × horizon (/ valued together) against success "
                 "(blue: registered)",
                 fontsize=9)  # fmt: skip
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)


def main() -> None:
    defaults = inspect.signature(PredictiveAgent).parameters
    registered = tuple(defaults[k].default for k in ("samples", "horizon", "together"))
    if registered != SETTINGS[0]:
        raise SystemExit(f"predictive_cost.py: the registered setting is {registered}, "
                         f"the first of SETTINGS {SETTINGS[0]}: put it first")
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--episodes", type=int, default=100, help="validation episodes a family")
    ap.add_argument("--caps", default="results/tuning/capabilities-predictive.npz")
    ap.add_argument("--out", default="docs/predictive-cost.md")
    ap.add_argument("--parts-episodes", type=int, default=20,
                    help="validation episodes a family whose decisions are timed part by part")
    a = ap.parse_args()
    caps = Capabilities.load(predictive_capabilities(a.caps))
    episodes = {fam: drawn_episodes(fam, a.episodes, VALIDATION_SEED) for fam in FAMILIES}
    t_all = time.perf_counter()
    rows, base = [], {}
    for samples, horizon, together in SETTINGS:
        row: dict = {"samples": samples, "horizon": horizon, "together": together,
                     "registered": (samples, horizon, together) == SETTINGS[0]}  # fmt: skip
        for fam in FAMILIES:
            won, took = run(caps, samples, horizon, together, episodes[fam])
            if row["registered"]:
                base[fam] = won
            d = paired_difference(won, base[fam])
            row[fam] = {"success": float(np.mean(won)), "ms": 1e3 * float(np.median(took)),
                        "mean_ms": 1e3 * float(np.mean(took)), "delta": d}  # fmt: skip
        rows.append(row)
        print(samples, horizon, together, {f: (round(row[f]["success"], 3), round(row[f]["ms"], 2))
                                 for f in FAMILIES}, flush=True)  # fmt: skip
    parts = {fam: breakdown(caps, episodes[fam][: a.parts_episodes]) for fam in FAMILIES}
    minutes = (time.perf_counter() - t_all) / 60
    out = Path(a.out)
    figure(rows, out.with_suffix(".png"))
    lines = [
        "# What copi-predictive's planner costs",
        "",
        "<!-- generated: written whole by studies/predictive_cost.py -->",
        "",
        f"`python studies/predictive_cost.py --episodes {a.episodes}` ({minutes:.0f} min, "
        "one process). copi-predictive plans over *samples* futures of *horizon* steps "
        "drawn from its learnt model of what moves; each setting below ran on the same "
        f"validation episodes (seed {VALIDATION_SEED}, {a.episodes} a family, the families "
        "it was tuned on: [its tuning](tuning-predictive.md)), its `act` timed around each "
        "call in one process (median and mean over the decisions). Δ: success minus the "
        f"registered setting's ({SETTINGS[0][0]} futures of {SETTINGS[0][1]} steps, each valued "
        "alone) on the same "
        "episodes, points, 95 % bootstrap interval. *Together*: futures valued as one in "
        "the planner's hindsight (a way must clear the discs of all of them; the first "
        "move's check of contact still counts each future), less clairvoyant than each "
        "future solved alone and fewer solves. Nothing here changes the registered method: "
        "the page says how far a decision is from 1 ms and what a smaller planner gives up.",
        "",
        "| futures | horizon | together | " + " | ".join(
            f"{f}: success | {f}: Δ | {f}: ms (median / mean)" for f in FAMILIES) + " |",
        "|---|---|---|" + "---|---|---|" * len(FAMILIES),
    ]
    for r in rows:
        cells = []
        for fam in FAMILIES:
            c = r[fam]
            d = c["delta"]
            delta = "—" if r["registered"] else interval(d)
            cells.append(f"{100 * c['success']:.1f} % | {delta} | "
                         f"{c['ms']:.2f} / {c['mean_ms']:.2f}")  # fmt: skip
        mark = " (registered)" if r["registered"] else ""
        lines.append(f"| {r['samples']}{mark} | {r['horizon']} | {r['together']} | "
                     + " | ".join(cells) + " |")  # fmt: skip
    # the cheapest setting that lost no success in either family (the point estimates)
    level = [r for r in rows[1:] if all(r[f]["delta"].estimate >= 0 for f in FAMILIES)]
    cheap = min(level, key=lambda r: r[FAMILIES[0]]["ms"], default=None)
    fast = [r for r in rows if all(r[f]["ms"] <= 1.0 for f in FAMILIES)]
    lines += ["", (
        f"The cheapest setting with no fewer successes than the registered one in both "
        f"families: "
        f"{cheap['samples']} futures of {cheap['horizon']} steps"
        + ("" if cheap["together"] == 1 else f", {cheap['together']} valued together")
        + ", "
        f"{cheap[FAMILIES[0]]['ms']:.2f} ms a decision in {FAMILIES[0]} "
        f"({100 * cheap[FAMILIES[0]]['ms'] / rows[0][FAMILIES[0]]['ms']:.0f} % of the "
        "registered setting's)" if cheap else "Every smaller setting lost successes somewhere"
    ) + (f"; {len(fast)} setting(s) within 1 ms in both." if fast else
         "; none is within 1 ms in both families.") + " On 100 episodes a family an "
        "interval is wide (about ±9 points in crowd): a setting is adopted only after the "
        "tuning on both families is redone (studies/tune.py) and every page that cites "
        "copi-predictive is regenerated.", ""]
    lines += [f"![cost against success]({out.with_suffix('.png').name})", ""]
    lines += [
        "## Where a decision's time goes", "",
        f"The registered setting's decisions on the first {a.parts_episodes} of those "
        "episodes a family, each part timed apart (a timer around each of the functions "
        "`act` calls, `breakdown` in the script): the median over the decisions, and the "
        "part's share of all the decisions' time. *The rest*: what `act` does between the "
        "parts (reading the observation, Python's calls). The parts ran after the table "
        "above, in the same process; on a shared machine whose speed drifts, compare times "
        "within one run, not across runs.", "",
        "| part | " + " | ".join(f"{f}: ms (median) | {f}: share" for f in FAMILIES) + " |",
        "|---|" + "---|---|" * len(FAMILIES),
    ]
    labels = [lb for lb, _, _ in PARTS if lb] + ["the rest", "everything"]
    for lb in labels:
        cells = []
        for fam in FAMILIES:
            t = parts[fam]
            every = np.array(t["everything"])
            v = every - sum(np.array(t[k]) for k in t if k != "everything") if lb == "the rest" \
                else np.array(t[lb])
            cells.append(f"{1e3 * float(np.median(v)):.2f} | {100 * v.sum() / every.sum():.0f} %")
        lines.append(f"| {lb} | " + " | ".join(cells) + " |")
    lines.append("")
    out.write_text("\n".join(lines))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
