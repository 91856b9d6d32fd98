"""How far ahead the planners over futures look: docs/predictive-horizon.md.

    python studies/predictive_horizon.py --episodes 600 --indoor-episodes 300 --draws 2

copi-predictive, tracked-mpc and the model-oracle share one planner
(:class:`copi.planning.futures.FuturesPlanner`), and a decision's cost grows with its
horizon ([what the planner costs](predictive-cost.md)). This study is their horizon's
tuning: each planner runs at every horizon of :data:`PLANNERS` on the same validation
episodes (seed 1, the families the planners are tuned on), every episode with
``--draws`` seeds of the futures (an episode counts the share of them it won), its
``act`` timed around each call; success is paired with the longest horizon's (the one
studies/tune.py had chosen, on 150 episodes a family with one draw, before this study)
on the same episodes (95 % bootstrap intervals). Each planner's choice is the horizon
with the most successes over both families.

A choice made on the seed it is tuned on flatters it (the best of several noisy arms is
chosen for its noise too), so each choice is run again beside the longest horizon on
episodes of a seed no table reports and nothing was tuned on (:data:`CHECK_SEED`). As
studies/tune.py does, the page says whether each registered horizon (its class's
default) is the chosen one, and the script exits with status 1 when one is not.
"""

from __future__ import annotations

import argparse
import inspect
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from copi.baselines import TrackedMPC  # noqa: E402
from copi.bounds import ModelOracle  # noqa: E402
from copi.learning import Capabilities  # noqa: E402
from copi.online import PredictiveAgent  # noqa: E402
from copi.results import paired_difference  # noqa: E402
from studies._common import (  # noqa: E402
    drawn_episodes,
    interval,
    predictive_capabilities,
    timed_acts,
    write_page,
)

SEED = 1
CHECK_SEED = 3
"""Episodes of a seed no table reports and no method was tuned on: the chosen settings'
check."""
_CLASSES = {"copi-predictive": PredictiveAgent, "tracked-mpc": TrackedMPC,
            "model-oracle": ModelOracle}  # fmt: skip
PLANNERS = {"copi-predictive": ("map", (20, 14, 12, 10)), "tracked-mpc": ("map", (14, 12, 10)),
            "model-oracle": ("oracle", (14, 12, 10))}  # fmt: skip
"""Each planner's level and horizons, the one studies/tune.py had chosen before first (the
reference of the page's differences)."""
REGISTERED = {m: inspect.signature(c).parameters["horizon"].default for m, c in _CLASSES.items()}
"""Each planner's registered horizon: its class's default."""
FAMILIES = ("crowd", "indoor")


def _agent(method: str, horizon: int, caps_path: str, draw: int) -> Any:
    if method == "copi-predictive":
        return PredictiveAgent(Capabilities.load(caps_path), horizon=horizon, seed=draw)
    if method == "tracked-mpc":
        return TrackedMPC(horizon=horizon, seed=draw)
    return ModelOracle(horizon=horizon, seed=draw)


def arm(method: str, horizon: int, family: str, seed: int, n: int, caps_path: str,
        draw: int) -> tuple[list[bool], list[float]]:  # fmt: skip
    """One planner at one horizon on the first ``n`` episodes of ``family`` at ``seed``,
    its futures drawn from the seed ``draw``: each episode's success and each decision's
    seconds."""
    agent = _agent(method, horizon, caps_path, draw)
    took = timed_acts(agent)
    level = PLANNERS[method][0]
    won = [e.run(agent, sensing=level).outcome == "success"
           for e in drawn_episodes(family, n, seed)]  # fmt: skip
    return won, took


def measure(jobs: list[tuple[str, int, str, int, int]], draws: int,
            caps_path: str) -> dict[tuple[str, int, str, int], dict[str, Any]]:  # fmt: skip
    """Every job (method, horizon, family, seed, episodes) with ``draws`` seeds of its
    futures, on two processes: per job, each episode's share of draws won and the median
    and mean ms of a decision (over every draw's decisions)."""
    with ProcessPoolExecutor(2) as pool:
        futs = {job: [pool.submit(arm, *job, caps_path, d) for d in range(draws)] for job in jobs}
        out = {}
        for (method, horizon, family, seed, _), fs in futs.items():
            res = [f.result() for f in fs]
            took = np.concatenate([r[1] for r in res])
            row = {"won": np.mean([r[0] for r in res], axis=0),
                   "ms": 1e3 * float(np.median(took)), "mean_ms": 1e3 * float(np.mean(took))}
            out[method, horizon, family, seed] = row
            print(method, horizon, family, seed, f"{100 * np.mean(row['won']):.1f} %",
                  f"{row['ms']:.2f} ms", flush=True)  # fmt: skip
        return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--episodes", type=int, default=600, help="crowd episodes (seed 1)")
    ap.add_argument("--indoor-episodes", type=int, default=300, help="indoor episodes (seed 1)")
    ap.add_argument("--draws", type=int, default=2, help="seeds of the futures per episode")
    ap.add_argument("--caps", default="results/tuning/capabilities-predictive.npz")
    ap.add_argument("--out", default="docs/predictive-horizon.md")
    a = ap.parse_args()
    if min(a.episodes, a.indoor_episodes, a.draws) < 1:
        ap.error("--episodes, --indoor-episodes and --draws must be at least 1")
    caps_path = str(predictive_capabilities(a.caps))
    n_of = {"crowd": a.episodes, "indoor": a.indoor_episodes}
    t0 = time.perf_counter()
    jobs = [(m, h, f, SEED, n_of[f]) for m, (_, hs) in PLANNERS.items() for f in FAMILIES
            for h in hs]  # fmt: skip
    got = measure(jobs, a.draws, caps_path)
    # each planner's choice: the horizon of most successes over both families (the
    # episodes summed), the longer one where two tie
    chosen = {}
    for m, (_, hs) in PLANNERS.items():
        total = {h: sum(float(np.sum(got[m, h, f, SEED]["won"])) for f in FAMILIES) for h in hs}
        chosen[m] = max(hs, key=lambda h: (total[h], h))
    checks = [(m, h, "crowd", CHECK_SEED, a.episodes) for m, (_, hs) in PLANNERS.items()
              if chosen[m] != hs[0] for h in (hs[0], chosen[m])]  # fmt: skip
    got.update(measure(checks, a.draws, caps_path) if checks else {})
    minutes = (time.perf_counter() - t0) / 60
    lines = [
        "# How far ahead the planners over futures should look",
        "",
        "<!-- generated: written whole by studies/predictive_horizon.py -->",
        "",
        f"`python studies/predictive_horizon.py --episodes {a.episodes} --indoor-episodes "
        f"{a.indoor_episodes} --draws {a.draws}` ({minutes:.0f} min on 2 cores). "
        "copi-predictive, tracked-mpc and the model-oracle plan with one planner, whose "
        "cost grows with its horizon ([what it costs](predictive-cost.md)); "
        "this is their horizon's tuning (studies/tune.py, which tunes the rest, had chosen "
        "the longest horizon of each row below from two values on 150 validation episodes "
        "a family with one draw of the futures). Each runs at every horizon below on the "
        f"same validation episodes (seed {SEED}: "
        f"{a.episodes} crowd, {a.indoor_episodes} indoor), every episode with {a.draws} "
        "seeds of its futures (an episode counts the share of them it won), its `act` "
        "timed around each call (median and mean over the decisions; the processes ran two "
        "at a time). Δ: success minus the longest horizon's on the same episodes, "
        "points, 95 % bootstrap interval. The model-oracle runs at level `oracle` (the "
        "true present and motion law), the others at `map`.",
        "",
        "| planner | horizon | " + " | ".join(
            f"{f}: success | {f}: Δ | {f}: ms (median / mean)" for f in FAMILIES) + " |",
        "|---|---|" + "---|---|---|" * len(FAMILIES),
    ]
    for m, (_, hs) in PLANNERS.items():
        for h in hs:
            cells = []
            for f in FAMILIES:
                g = got[m, h, f, SEED]
                d = paired_difference(g["won"], got[m, hs[0], f, SEED]["won"])
                cells.append(f"{100 * np.mean(g['won']):.1f} % | "
                             f"{'—' if h == hs[0] else interval(d)} | "
                             f"{g['ms']:.2f} / {g['mean_ms']:.2f}")  # fmt: skip
            mark = " (registered)" if h == REGISTERED[m] else ""
            lines.append(f"| {m} | {h}{mark} | " + " | ".join(cells) + " |")
    lines += ["", "## The choice, checked on other episodes", "",
              "Each planner's choice on these episodes: the horizon with the most successes "
              "over both families (the longer where two tie). A choice made on "
              "the episodes it is tuned on is flattered by their noise, so each choice that "
              "differs from the longest horizon runs again beside it on "
              f"{a.episodes} crowd episodes of seed {CHECK_SEED} (no table reports it and "
              f"nothing was tuned on it), {a.draws} draws each.", ""]
    lines += ["| planner | longest | chosen | seed 1 crowd: Δ | seed 1 indoor: Δ | "
              f"seed {CHECK_SEED} crowd: longest | chosen | Δ | registered |",
              "|---|---|---|---|---|---|---|---|---|"]
    for m, (_, hs) in PLANNERS.items():
        c = chosen[m]
        if c == hs[0]:
            lines.append(f"| {m} | {hs[0]} | {c} (the same) | — | — | — | — | — | "
                         f"{REGISTERED[m]} |")
            continue
        seed1 = [interval(paired_difference(got[m, c, f, SEED]["won"],
                                           got[m, hs[0], f, SEED]["won"])) for f in FAMILIES]
        r0, r1 = got[m, hs[0], "crowd", CHECK_SEED], got[m, c, "crowd", CHECK_SEED]
        lines.append(f"| {m} | {hs[0]} | {c} | {seed1[0]} | {seed1[1]} | "
                     f"{100 * np.mean(r0['won']):.1f} % | {100 * np.mean(r1['won']):.1f} % | "
                     f"{interval(paired_difference(r1['won'], r0['won']))} | "
                     f"{REGISTERED[m]} |")  # fmt: skip
    lines.append("")
    write_page(a.out, lines)
    stale = [m for m in PLANNERS if REGISTERED[m] != chosen[m]]
    if stale:
        print("predictive_horizon.py: registered horizons differ from the chosen ones "
              f"(change the class defaults): {', '.join(stale)}", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
