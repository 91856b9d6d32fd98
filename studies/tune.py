"""Tune every method's parameters on validation episodes (seed 1), disjoint from the
reported ones (seed 0), with the same budget of four settings per method.

    python studies/tune.py --episodes 100 --workers 2

Prints, per method, success and median excess of each setting, and the chosen one (the
highest success; within one point, the lower median excess). A chosen value lives in
one place: the default of the method's class (which the registry, ``copi list`` and the
reports read); the last column says whether the registered value is the chosen one, and
the script exits with status 1 when one is not. docs/tuning.md keeps the last table.
"""

from __future__ import annotations

import argparse
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from copi.experiments import ensure_capabilities
from copi.learning import Capabilities
from copi.methods import make_agent, method_spec
from copi.runs import Episode

GRID: dict[str, list[dict[str, float]]] = {
    "copi-extended": [{"guard": g} for g in (0.9, 1.05, 1.2, 1.4)],
    "compass-guard": [{"guard": g} for g in (0.9, 1.05, 1.2, 1.4)],
    "vfh": [
        {"threshold": 0.5, "safety": 0.5},
        {"threshold": 0.3, "safety": 0.8},
        {"threshold": 0.2, "safety": 1.0},
        {"threshold": 0.4, "safety": 1.2},
    ],
    "dwa": [
        {"margin": 0.6, "clearance_weight": 0.3},
        {"margin": 0.9, "clearance_weight": 0.3},
        {"margin": 0.9, "clearance_weight": 1.0},
        {"margin": 1.2, "clearance_weight": 1.0},
    ],
    "tangent-bug": [
        {"margin": 0.3, "follow": 1.2},
        {"margin": 0.5, "follow": 1.0},
        {"margin": 0.6, "follow": 1.5},
        {"margin": 0.9, "follow": 1.8},
    ],
    "replan": [{"inflate": v} for v in (0.3, 0.6, 1.0, 1.5)],
    # the learnt preset itself: its guard, and the weight of the learnt safety (alpha)
    "copi-learnt": [{"guard": 1.05, "alpha": 2.0}, {"guard": 1.2, "alpha": 2.0},
                    {"guard": 1.05, "alpha": 1.0}, {"guard": 1.05, "alpha": 4.0}],
    # the weight of the template safety priors in the learnt preset's ablations
    "copi-learnt-priors": [{"beta": v} for v in (0.25, 0.5, 1.0, 2.0)],
    "copi-learnt-motion": [{"beta": v} for v in (0.25, 0.5, 1.0, 2.0)],
    # copi-predictive: the weight of the learnt safety network and the planner's margins
    # (the rest as the model-oracle's, tuned at level oracle before). The horizon of the
    # three planners over futures (copi-predictive, tracked-mpc, model-oracle) is chosen
    # by studies/predictive_horizon.py on six times these episodes with two draws of the
    # futures, where two horizons a few points apart can be told apart
    "copi-predictive": [{"alpha": 1.0}, {"alpha": 0.0}, {"alpha": 2.0},
                        {"alpha": 1.0, "margin": 0.2}, {"alpha": 1.0, "escape": 0.2}],
    "navground-hrvo": [{"safety_margin": v} for v in (0.1, 0.3, 0.6, 1.0)],
    "navground-hl": [{"safety_margin": v} for v in (0.1, 0.3, 0.6, 1.0)],
}
SEED = 1
CAPS: dict[str, str] = {}


def _episode(args: tuple[str, int]) -> list[tuple[str, int, str, float]]:
    family, k = args
    episode = Episode.draw(family, k, SEED)
    optimal = episode.optimal
    out = []
    for method, settings in GRID.items():
        spec = method_spec(method)
        if not spec.available():
            continue
        level = "oracle" if spec.sensing == "oracle" else "map"
        caps = Capabilities.load(CAPS[spec.capabilities]) if spec.capabilities else None
        for i, p in enumerate(settings):
            res = episode.run(make_agent(method, caps, **p), sensing=level)
            ex = res.path_length / optimal - 1 if res.outcome == "success" else math.nan
            out.append((method, i, res.outcome, ex))
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--episodes", type=int, default=100)
    ap.add_argument("--families", default="star,polygon,indoor,maps,crowd")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--caps-dir", default="results/tuning")
    ap.add_argument("--out", default="docs/tuning.md")
    ap.add_argument("--methods", default=None, help="comma-separated subset of the grid")
    a = ap.parse_args()
    if a.methods:
        keep = a.methods.split(",")
        unknown = [m for m in keep if m not in GRID]
        if unknown or a.out == "docs/tuning.md":
            raise SystemExit(
                f"tune.py: unknown methods {unknown} (known: {', '.join(GRID)})"
                if unknown
                else "tune.py: --methods tunes a part: give --out (docs/tuning.md holds all)"
            )
        for m in list(GRID):
            if m not in keep:
                del GRID[m]
    presets = {p for m in GRID if (p := method_spec(m).capabilities) is not None}
    CAPS.update(ensure_capabilities(a.caps_dir, presets))
    items = [(f, k) for f in a.families.split(",") for k in range(a.episodes)]
    rows: list[tuple[str, int, str, float]] = []
    with ProcessPoolExecutor(a.workers) as pool:
        for i, r in enumerate(pool.map(_episode, items, chunksize=4)):
            rows += r
            print(f"\r{i + 1}/{len(items)}", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    lines = [
        f"# Tuning (validation seed {SEED}, families {a.families}, {a.episodes} episodes "
        "each, level map; oracle for oracle methods)",
        "",
        "<!-- generated: written whole by studies/tune.py -->",
        "",
        "| method | setting | success | collision | median excess | chosen | registered |",
        "|---|---|---|---|---|---|---|",
    ]
    stale = []
    for method, settings in GRID.items():
        stats = []
        for i, p in enumerate(settings):
            mine = [r for r in rows if r[0] == method and r[1] == i]
            if not mine:
                continue
            succ = np.mean([r[2] == "success" for r in mine])
            coll = np.mean([r[2] == "collision" for r in mine])
            ex = [r[3] for r in mine if r[2] == "success" and math.isfinite(r[3])]
            stats.append((i, p, succ, coll, float(np.median(ex)) if ex else math.inf))
        if not stats:
            continue
        top = max(s[2] for s in stats)
        best = min((s for s in stats if s[2] >= top - 0.01), key=lambda s: s[4])
        registered = method_spec(method).params
        for i, p, succ, coll, ex in stats:
            mark = "**yes**" if i == best[0] else ""
            now = "yes" if all(registered.get(k) == v for k, v in p.items()) else ""
            if mark and not now:
                stale.append(f"{method}: chosen {p}, registered {registered}")
            lines.append(f"| {method} | {p} | {100 * succ:.1f} % | {100 * coll:.1f} % | "
                         f"{100 * ex:.1f} % | {mark} | {now} |")  # fmt: skip
    text = "\n".join(lines) + "\n"
    Path(a.out).write_text(text, encoding="utf-8")
    print(text)
    if stale:
        print("tune.py: registered values differ from the chosen ones (change the class "
              "defaults):\n  " + "\n  ".join(stale), file=sys.stderr)
        raise SystemExit(1)


if __name__ == "__main__":
    main()
