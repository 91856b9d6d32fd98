"""copi against deep RL: in family, a new world, a new task, and what each learner costs.

    python studies/rl_experiments.py --bench results/rl-bench --episodes 200 \\
        --games 200 --out docs/rl.md

Every number is paired on the same episodes (the benchmark's seed 0; the policies were
trained on training seeds and tuned on validation seed 1, see ``studies/rl_train_all.py``):

- *in family*: ``ppo-F`` (PPO trained on family F only) on F, beside ``copi-learnt``,
  ``compass-guard``, ``dwa`` and ``ppo`` (trained on the mix of all five);
- *a new world*: ``copi-learnt`` with capabilities learnt in ``star`` worlds alone (its
  exploration and its probes; the preset's default probes four families) and
  ``ppo-star``, both tested on every other family;
- *a new task*: the homicidal chauffeur's evader (Experiment 2): copi's learnt agent with
  its capabilities unchanged, ``ppo`` (its navigation policy under the game's direction)
  and ``ppo-chauffeur`` (PPO trained for the game with the same step budget), same games;
- *cost*: each learner's samples and wall time, and where PPO's learning curve (success
  on the validation episodes) crosses copi-learnt's success on the same episodes.
- against the second peer: the new task at the game's level (``studies/rl_new_task.py``)
  and copi at a hundredth of its samples, learnt alone and guarded
  (``studies/rl_lean.py``); each script also splices its section into the page alone.

Everything runs through copi's runners into result stores in ``--bench`` (resumable: an
interrupted run goes on where it stopped): the benchmark (``benchmark.sqlite``), copi
learnt otherwise (``variant-NAME.sqlite``), the other training seeds' policies
(``seeds.sqlite``) and the games (``chauffeur.sqlite``; ``chauffeur-lean.sqlite`` for copi
learnt at a hundredth of PPO's samples, the same evader with other capabilities).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from copi._files import file_sha  # noqa: E402
from copi.baselines import PPOAgent, packaged_policy  # noqa: E402
from copi.experiments import (  # noqa: E402
    BenchmarkConfig,
    PursuitConfig,
    ensure_capabilities,
    pursue,
    run_benchmark,
)
from copi.learning import Capabilities, LearnParams, learn, simulated_steps  # noqa: E402
from copi.methods import (  # noqa: E402
    make_agent,
    method_names,
    method_spec,
    parse_methods,
    register_method,
)
from copi.reports import read_benchmark  # noqa: E402
from copi.results import ResultsStore, paired_difference, summarize_rows  # noqa: E402
from copi.rl import TrainConfig, validation_success  # noqa: E402
from studies._common import finish_cost_figure, kept_times  # noqa: E402
from studies.rl_lean import lean_like_lines  # noqa: E402
from studies.rl_new_task import lines as new_task_lines  # noqa: E402

FAMILIES = ("star", "polygon", "indoor", "maps", "crowd")
DOCS = Path(__file__).resolve().parents[1] / "docs"


SAC_FAMILIES = tuple(f for f in FAMILIES if f"sac-{f}-map" in method_names()
                     and method_spec(f"sac-{f}-map").available())
"""The families SAC was trained on (its policies shipped)."""
IL_FAMILIES = tuple(f for f in FAMILIES if f"ppo-il-{f}-map" in method_names()
                    and method_spec(f"ppo-il-{f}-map").available())
"""The families the imitation warm start was trained on (its policies shipped)."""
CLONE_FAMILIES = tuple(f for f in FAMILIES if f"clone-{f}-map" in method_names()
                       and method_spec(f"clone-{f}-map").available())
"""The families a clone was trained on (its policies shipped)."""
CURRICULUM_FAMILIES = tuple(f for f in FAMILIES if f"ppo-cur-{f}-map" in method_names()
                            and method_spec(f"ppo-cur-{f}-map").available())
"""The families a curriculum was trained for (its policies shipped)."""
METHODS = ["copi-learnt", "compass-guard", "dwa", "straight", "ppo", "ppo-guard",
           *[f"ppo-{f}" for f in FAMILIES], "copi-predictive@map",
           *[f"ppo-{f}-map" for f in FAMILIES], *[f"ppo-guard-{f}-map" for f in FAMILIES],
           *[f"sac-{f}-map" for f in SAC_FAMILIES], *[f"ppo-il-{f}-map" for f in IL_FAMILIES],
           *[f"clone-{f}-map" for f in CLONE_FAMILIES],
           *[f"ppo-cur-{f}-map" for f in CURRICULUM_FAMILIES],
           *[f"ppo-{f}-sensor@sensor" for f in FAMILIES if f"ppo-{f}-sensor" in method_names()
             and method_spec(f"ppo-{f}-sensor").available()],
           *(["sarl@oracle"] if method_spec("sarl").available() else [])]
"""The first peer (``ppo``, ``ppo-F``: the ranges and their change, sensor and map mixed),
the second (``ppo-F-map``: map's reading, one policy per level) and the second algorithm
(``sac-F-map``: the same observation, learnt by SAC), each beside the copi method that,
like it, has or has not a hand-written guard."""
GOAL_TO_GUARD = {"star": -5, "maps": -5, "polygon": -10, "indoor": -10, "crowd": 0}
"""How far below compass-guard the second peer may stand in each family (points) and
still count as a peer that learnt (the bar set before it was trained)."""


def _learnt(rate: dict, fam: str, peer: str) -> bool:
    """Whether ``peer`` met the goal of a peer that learnt in family ``fam``: at least 30
    points above straight, and no further below compass-guard than :data:`GOAL_TO_GUARD`."""
    at = rate[fam, peer, "map"]
    return (100 * (at - rate[fam, "straight", "map"]) >= 30
            and 100 * (at - rate[fam, "compass-guard", "map"]) >= GOAL_TO_GUARD[fam])


EVADERS = ["learnt", "compass-guard", "ppo", "ppo-guard", "ppo-chauffeur", "game"]


def _pct(x: float) -> str:
    return "—" if not math.isfinite(x) else f"{100 * x:.1f} %"


def _success(rows: list) -> dict[int, bool]:
    return {int(r["episode"]): r["outcome"] == "success" for r in rows
            if r["outcome"] != "skipped"}  # fmt: skip


def _compare(
    a: dict[int, bool], b: dict[int, bool], who_a: str, who_b: str
) -> tuple[str, str, bool]:
    """a − b in points on the common episodes with its interval, who is better (named only
    where the interval excludes 0), and whether a is."""
    common = sorted(set(a) & set(b))
    d = paired_difference([a[k] for k in common], [b[k] for k in common])
    text = f"{100 * d.estimate:+.1f} [{100 * d.low:+.1f}, {100 * d.high:+.1f}]"
    if not d.excludes_zero:
        return text, "neither (interval holds 0)", False
    return text, f"**{who_a}**" if d.estimate > 0 else f"**{who_b}**", d.estimate > 0


def benchmark(bench: Path, episodes: int, workers: int) -> None:
    """Every method of :data:`METHODS` on the benchmark's episodes, into
    ``bench/benchmark.sqlite``."""
    arms = tuple(parse_methods(",".join(METHODS)))
    presets = {p for r in arms if (p := method_spec(r.method).capabilities)}
    config = BenchmarkConfig(methods=arms, families=FAMILIES, episodes=episodes,
                             capabilities=ensure_capabilities(bench, presets))  # fmt: skip
    run_benchmark(config, bench / "benchmark.sqlite", workers=workers)


def second_peer_lines(succ: dict, rate: dict) -> list[str]:
    """The second peer's section: like with like at level map (learnt alone beside learnt
    alone, guarded beside guarded), and whether it learnt (against straight and the
    hand-written guard)."""
    lines = [
        "## Like with like: the second peer (level map)",
        "",
        "`ppo-F-map`: PPO trained on family F at level map only, seeing what copi-learnt "
        "sees there (the reading, the hits the static map does not explain, three readings "
        "stacked, its own last velocity, the route's direction: `copi-local-v3`), with a "
        "proximity penalty and its settings chosen among eight on validation seed 1 "
        "(`python studies/rl_train_all.py --tune`, the table below). Learnt alone: "
        "`copi-predictive` (a learnt model of what moves and a planner over it, no "
        "hand-written guard) beside `ppo-F-map`. Guarded: `copi-learnt` (learnt choice, "
        "compass-guard's hand-written guard as a filter) beside `ppo-guard-F-map` (the "
        "same guard as a shield). `compass-guard` is the guard alone, `straight` the "
        "route's direction with no avoidance.",
        "",
        "| family | straight | compass-guard | copi-predictive | ppo-F-map | Δ copi-predictive "
        "− ppo-F-map | better | Δ ppo-F-map − straight | Δ ppo-F-map − compass-guard | "
        "learnt (goal) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    met = 0
    for fam in FAMILIES:
        peer = f"ppo-{fam}-map"
        p, c = succ.get((fam, peer, "map")), succ.get((fam, "copi-predictive", "map"))
        st, cg = succ.get((fam, "straight", "map")), succ.get((fam, "compass-guard", "map"))
        if p is None or c is None or st is None or cg is None:
            continue
        d, better, _ = _compare(c, p, "copi-predictive", peer)
        d_st = _compare(p, st, "", "")[0]
        d_cg = _compare(p, cg, "", "")[0]
        ok = _learnt(rate, fam, peer)
        met += ok
        bar = f"straight + 30, compass-guard {GOAL_TO_GUARD[fam]:+d}"
        lines.append(
            f"| {fam} | {_pct(rate[fam, 'straight', 'map'])} | "
            f"{_pct(rate[fam, 'compass-guard', 'map'])} | "
            f"{_pct(rate[fam, 'copi-predictive', 'map'])} | {_pct(rate[fam, peer, 'map'])} | "
            f"{d} | {better} | {d_st} | {d_cg} | {'met' if ok else '**missed**'} ({bar}) |"
        )
    lines += [
        "",
        f"The second peer met its goal in {met} of 5 families (at least 30 points above "
        "straight, and within 5 points of compass-guard in star and maps, 10 in polygon and "
        "indoor, at or above it in crowd; from the rates).",
        "",
        "| family | compass-guard (the guard alone) | copi-learnt (guarded) | ppo-guard-F-map "
        "(guarded) | Δ copi-learnt − ppo-guard-F-map | better |",
        "|---|---|---|---|---|---|",
    ]
    for fam in FAMILIES:
        peer = f"ppo-guard-{fam}-map"
        p, c = succ.get((fam, peer, "map")), succ.get((fam, "copi-learnt", "map"))
        if p is None or c is None:
            continue
        d, better, _ = _compare(c, p, "copi-learnt", peer)
        lines.append(
            f"| {fam} | {_pct(rate[fam, 'compass-guard', 'map'])} | "
            f"{_pct(rate[fam, 'copi-learnt', 'map'])} | {_pct(rate[fam, peer, 'map'])} | "
            f"{d} | {better} |"
        )
    lines += [
        "",
        "A new world for the second peer: `ppo-star-map` (learnt in star worlds only) on "
        "the other families, beside the family's own `ppo-F-map`.",
        "",
        "| family | ppo-star-map | ppo-F-map | Δ ppo-F-map − ppo-star-map |",
        "|---|---|---|---|",
    ]
    for fam in FAMILIES[1:]:
        own, star = succ.get((fam, f"ppo-{fam}-map", "map")), succ.get((fam, "ppo-star-map", "map"))
        if own is None or star is None:
            continue
        lines.append(f"| {fam} | {_pct(rate[fam, 'ppo-star-map', 'map'])} | "
                     f"{_pct(rate[fam, f'ppo-{fam}-map', 'map'])} | "
                     f"{_compare(own, star, '', '')[0]} |")  # fmt: skip
    return [*lines, ""]


def _shipped(name: str) -> tuple[dict, str]:
    """The run that trained shipped policy ``name`` (its .json beside the weights) and
    its steps and minutes as a cell ("—" when not shipped)."""
    path = SEEDS.parent / f"{name}.json"
    info = json.loads(path.read_text()) if path.is_file() else {}
    return info, f"{info['steps']:,} in {info['seconds'] / 60:.0f} min" if info else "—"


def _arms_at_map(succ: dict, fam: str, *peers: str) -> dict[str, dict[int, bool]] | None:
    """Each episode's success at map in family ``fam`` of ``peers`` and of the methods every
    peer's section stands beside (straight, compass-guard, copi-predictive); None when one
    of them did not run there."""
    arms = {k: succ.get((fam, k, "map")) for k in (*peers, "straight", "compass-guard",
                                                    "copi-predictive")}  # fmt: skip
    return None if any(v is None for v in arms.values()) else arms  # type: ignore[return-value]


def sac_lines(succ: dict, rate: dict) -> list[str]:
    """The second algorithm's section: SAC beside PPO on the same observation, both beside
    straight, compass-guard and copi-predictive, on the same episodes."""
    rows = []
    for fam in SAC_FAMILIES:
        sac, ppo = f"sac-{fam}-map", f"ppo-{fam}-map"
        arms = _arms_at_map(succ, fam, sac, ppo)
        if arms is None:
            continue
        _, took = _shipped(sac)
        ok = _learnt(rate, fam, sac)
        rows.append(
            f"| {fam} | {_pct(rate[fam, 'straight', 'map'])} | "
            f"{_pct(rate[fam, 'compass-guard', 'map'])} | "
            f"{_pct(rate[fam, 'copi-predictive', 'map'])} | {_pct(rate[fam, ppo, 'map'])} | "
            f"{_pct(rate[fam, sac, 'map'])} | {_compare(arms[sac], arms[ppo], sac, ppo)[0]} | "
            f"{_compare(arms['copi-predictive'], arms[sac], 'copi-predictive', sac)[0]} | "
            f"{_compare(arms[sac], arms['straight'], '', '')[0]} | {took} | "
            f"{'met' if ok else '**missed**'} |"
        )
    if not rows:
        return []
    return [
        "## The second algorithm: SAC (level map)",
        "",
        "`sac-F-map`: SAC (Stable-Baselines3; off-policy, a replay buffer of 100k "
        "transitions, its entropy tuned to a target, batches of 256, one gradient step "
        "after each step of its 8 environments, 10k random steps first) on family F at "
        "level map, seeing what `ppo-F-map` sees and rewarded alike "
        "(`python studies/rl_train_all.py --peer sac --only F-map --seeds 0`; not tuned: "
        "SB3's settings for SAC beside copi rl train's). Nothing hand-written. Trained on "
        "the families the table shows; the others were not trained.",
        "",
        "| family | straight | compass-guard | copi-predictive | ppo-F-map | sac-F-map | "
        "Δ sac − ppo | Δ copi-predictive − sac | Δ sac − straight | steps | learnt (goal) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
        *rows,
        "",
        "The goal is the second peer's (at least 30 points above straight; within 5 points "
        "of compass-guard in star, at or above it in crowd).",
        "",
        *[f"![sac-{f}-map](rl-curve-sac-{f}-map.png)" for f in SAC_FAMILIES
          if (DOCS / f"rl-curve-sac-{f}-map.png").is_file()],
        "",
    ]


def il_lines(succ: dict, rate: dict) -> list[str]:
    """The imitation warm start's section: PPO from a clone of compass-guard beside PPO
    from scratch, the demonstrator itself and copi-predictive, on the same episodes."""
    rows, clones, above, below = [], [], [], []
    for fam in IL_FAMILIES:
        il, ppo = f"ppo-il-{fam}-map", f"ppo-{fam}-map"
        arms = _arms_at_map(succ, fam, il, ppo)
        if arms is None:
            continue
        info, took = _shipped(il)
        rows.append(
            f"| {fam} | {_pct(rate[fam, 'straight', 'map'])} | "
            f"{_pct(rate[fam, 'compass-guard', 'map'])} | "
            f"{_pct(rate[fam, 'copi-predictive', 'map'])} | {_pct(rate[fam, ppo, 'map'])} | "
            f"{_pct(rate[fam, il, 'map'])} | {_compare(arms[il], arms[ppo], il, ppo)[0]} | "
            f"{_compare(arms[il], arms['compass-guard'], '', '')[0]} | "
            f"{_compare(arms['copi-predictive'], arms[il], 'copi-predictive', il)[0]} | "
            f"{_compare(arms[il], arms['straight'], '', '')[0]} | {took} | "
            f"{'met' if _learnt(rate, fam, il) else '**missed**'} |"
        )
        _, who, better = _compare(arms[il], arms[ppo], il, ppo)
        if "neither" not in who:
            (above if better else below).append(fam)
        if info.get("curve") and info["curve"][0]["steps"] == 0:
            first = info["curve"][0]["success"]
            kept = info.get("kept_steps", info["steps"])
            states = info.get("imitation", {}).get("states")
            clones.append(f"{fam} {_pct(first)} ({states:,} states; kept: the policy of "
                          f"{kept:,} steps, {_pct(info.get('kept_success', math.nan))})"
                          if states else f"{fam} {_pct(first)}")  # fmt: skip
    if not rows:
        return []
    same = [f for f in IL_FAMILIES if f not in above + below]
    verdict = (f"Against PPO from scratch on the same episodes: above it in "
               f"{', '.join(above) or 'no family'}, below it in {', '.join(below) or 'no family'}"
               f", within noise (the interval holds 0) in {', '.join(same) or 'no family'}. ")
    return [
        "## Imitation, then PPO (level map)",
        "",
        "`ppo-il-F-map`: the second peer's training warm-started by imitation "
        "(`copi rl train --imitate compass-guard`; `python studies/rl_train_all.py --peer "
        "il --steps 1000000 --seeds 0`): its actor first clones compass-guard, the "
        "hand-written method of the same level (2,000 episodes it drives, then two rounds "
        "of DAgger, 1,000 episodes each driven by the clone and labelled by compass-guard), "
        "then PPO with copi rl train's defaults. At run time the network decides alone: "
        "what is hand-written is its teacher, not a filter.",
        "",
        "| family | straight | compass-guard (its teacher) | copi-predictive | ppo-F-map | "
        "ppo-il-F-map | Δ il − ppo | Δ il − compass-guard | Δ copi-predictive − il | "
        "Δ il − straight | steps | learnt (goal) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
        *rows,
        "",
        verdict + "The goal is the second peer's (at least 30 points above straight, and "
        "within 5 points of compass-guard in star and maps, 10 in polygon and indoor, at or "
        "above it in crowd). Steps: two runs at a time on the 2 cores. Validation success "
        "(seed 1, 60 episodes; the policy kept is the best of eleven such points, so its "
        "own number flatters it) of the clone before any step of PPO: "
        + "; ".join(clones) + ". Tried on star before this run (validation seed 1, 100 "
        "episodes, the clone alone): more DAgger rounds (5), wider layers (256-256), more "
        "passes (50), a loss weighted toward moves away from the route: 72 to 83 % each, "
        "no better than the defaults' 82 %. The clones fail by contact with moving "
        "obstacles where compass-guard turns by one compass step. Every demonstration comes "
        "from the training environment's pool of 1,000 episodes a family (PPO's too).",
        "",
        *[f"![ppo-il-{f}-map](rl-curve-il-{f}-map.png)" for f in IL_FAMILIES
          if (DOCS / f"rl-curve-il-{f}-map.png").is_file()],
        "",
    ]


def clone_lines(succ: dict, rate: dict) -> list[str]:
    """The clone's section: a classifier of compass-guard's moves beside its teacher, PPO
    (from scratch and warm-started) and copi-predictive, on the same episodes."""
    rows, rounds = [], []
    for fam in CLONE_FAMILIES:
        cl, ppo, il = f"clone-{fam}-map", f"ppo-{fam}-map", f"ppo-il-{fam}-map"
        arms = _arms_at_map(succ, fam, cl, ppo, il)
        if arms is None:
            continue
        info, _ = _shipped(cl)
        took = f"{info['seconds'] / 60:.0f} min" if info else "—"
        rows.append(
            f"| {fam} | {_pct(rate[fam, 'straight', 'map'])} | "
            f"{_pct(rate[fam, 'compass-guard', 'map'])} | "
            f"{_pct(rate[fam, 'copi-predictive', 'map'])} | {_pct(rate[fam, ppo, 'map'])} | "
            f"{_pct(rate[fam, il, 'map'])} | {_pct(rate[fam, cl, 'map'])} | "
            f"{_compare(arms[cl], arms['compass-guard'], '', '')[0]} | "
            f"{_compare(arms[cl], arms[ppo], cl, ppo)[0]} | "
            f"{_compare(arms[cl], arms[il], cl, il)[0]} | "
            f"{_compare(arms['copi-predictive'], arms[cl], 'copi-predictive', cl)[0]} | "
            f"{took} | {'met' if _learnt(rate, fam, cl) else '**missed**'} |"
        )
        if info.get("curve"):
            rounds.append(f"{fam} " + " / ".join(_pct(c["success"]) for c in info["curve"])
                          + f" ({info['states']:,} states)")  # fmt: skip
    if not rows:
        return []
    return [
        "## A clone of compass-guard (level map; no RL)",
        "",
        "`clone-F-map`: no reward and no RL step, a classifier of compass-guard's moves "
        "(`copi rl train --algo clone --imitate compass-guard`; `python "
        "studies/rl_train_all.py --peer clone --seeds 0`). A move of compass-guard is a step "
        "along one of its 16 directions, which in the policy's frame (turned by whole rays) "
        "is one of the 32 rays: the network (256-256 tanh layers, what `ppo-F-map` sees) "
        "scores 33 moves, a step along each ray or none, by cross-entropy, and takes the "
        "best; near the goal the step's length is compass-guard's rule, hand-written. Its "
        "demonstrations: 2,000 episodes compass-guard drives, then two rounds of DAgger "
        "(1,000 episodes each driven by the clone, labelled by compass-guard), drawn from a "
        "pool of 50,000 training episodes a family (the pool chosen on validation seed 1 "
        "before this run; from PPO's default pool of 1,000, `--episodes-per-family 1000`, "
        "star's clone reached 86.7 / 81.7 / 85.0 % of the validation episodes after its "
        "three rounds, against 91.7 / 81.7 / 91.7 % from 50,000: 60 episodes, within noise "
        "of each other). At run time the network decides alone: the hand-written method is "
        "its teacher, not a filter, and the table names it so.",
        "",
        "| family | straight | compass-guard (its teacher) | copi-predictive | ppo-F-map | "
        "ppo-il-F-map | clone-F-map | Δ clone − compass-guard | Δ clone − ppo | "
        "Δ clone − ppo-il | Δ copi-predictive − clone | time | learnt (goal) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
        *rows,
        "",
        "The goal is the second peer's (at least 30 points above straight, and within 5 "
        "points of compass-guard in star and maps, 10 in polygon and indoor, at or above it "
        "in crowd); a clone is not the PPO or SAC the goal names. It is the strongest "
        "learnt-only peer copi has, and copi's own learnt decision without a guard, "
        "copi-predictive, is above it in every family (its column). Validation success "
        "(seed 1, 60 episodes) "
        "after each round (the demonstrator's, DAgger's first, DAgger's second; the best "
        "kept): " + "; ".join(rounds) + ". Time: two families at a time on the 2 cores.",
        "",
        *[f"![clone-{f}-map](rl-curve-clone-{f}-map.png)" for f in CLONE_FAMILIES
          if (DOCS / f"rl-curve-clone-{f}-map.png").is_file()],
        "",
    ]


def curriculum_lines(succ: dict, rate: dict) -> list[str]:
    """The curriculum's section: PPO whose episodes grow from static worlds to crowds
    beside PPO from scratch, the clone, compass-guard and copi-predictive."""
    rows, curves = [], []
    for fam in CURRICULUM_FAMILIES:
        cur, ppo, cl = f"ppo-cur-{fam}-map", f"ppo-{fam}-map", f"clone-{fam}-map"
        arms = _arms_at_map(succ, fam, cur, ppo, cl)
        if arms is None:
            continue
        info, took = _shipped(cur)
        stages = " → ".join(f"{f} to {end / 1e6:g}M" for f, end in
                            info.get("config", {}).get("curriculum", []))  # fmt: skip
        rows.append(
            f"| {fam} | {stages} → {fam} | {_pct(rate[fam, 'straight', 'map'])} | "
            f"{_pct(rate[fam, 'compass-guard', 'map'])} | "
            f"{_pct(rate[fam, 'copi-predictive', 'map'])} | {_pct(rate[fam, cl, 'map'])} | "
            f"{_pct(rate[fam, ppo, 'map'])} | {_pct(rate[fam, cur, 'map'])} | "
            f"{_compare(arms[cur], arms[ppo], cur, ppo)[0]} | "
            f"{_compare(arms[cur], arms['straight'], '', '')[0]} | "
            f"{_compare(arms[cur], arms['compass-guard'], '', '')[0]} | "
            f"{_compare(arms['copi-predictive'], arms[cur], 'copi-predictive', cur)[0]} | "
            f"{took} | {'met' if _learnt(rate, fam, cur) else '**missed**'} |"
        )
        if info.get("curve"):
            curves.append(f"{fam}: kept the policy of {info['kept_steps']:,} steps "
                          f"({_pct(info['kept_success'])}), "
                          f"{_pct(info['curve'][-1]['success'])} at the end")  # fmt: skip
    if not rows:
        return []
    return [
        "## A curriculum: from star worlds to crowds (level map)",
        "",
        "`ppo-cur-F-map`: the second peer's training (copi rl train's defaults, 2M steps) "
        "whose episodes start in easier worlds and end in the family's own "
        "(`copi rl train --curriculum FAMILY:STEP,...`; `python studies/rl_train_all.py "
        "--peer curriculum --seeds 0`); validated on the family's own episodes throughout. "
        "Two curricula were trained and the one of higher validation success (seed 1) "
        "kept: star worlds (an open room, 10 to 15 discs at 0.6 of the agent's speed) to "
        "400k steps, polygon worlds (obstacles, the same discs) to 1M, then crowds (25 to "
        "40 discs at 0.8); and polygon worlds alone to 1M, then crowds. Nothing "
        "hand-written.",
        "",
        "| family | stages | straight | compass-guard | copi-predictive | clone-F-map | "
        "ppo-F-map | ppo-cur-F-map | Δ cur − ppo | Δ cur − straight | Δ cur − compass-guard | "
        "Δ copi-predictive − cur | steps | learnt (goal) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
        *rows,
        "",
        CURRICULUM_NOTE + " Validation (seed 1, 60 episodes every 100k steps): "
        + "; ".join(curves) + ".",
        "",
        *[f"![ppo-cur-{f}-map](rl-curve-cur-{f}-map.png)" for f in CURRICULUM_FAMILIES
          if (DOCS / f"rl-curve-cur-{f}-map.png").is_file()],
        "",
    ]


CURRICULUM_NOTE = (
    "On the reported episodes the curriculum is within noise of PPO from scratch and "
    "below the clone; the goal is missed as far as before. On validation it had stood "
    "above PPO from scratch (the mean of the curve's last three points 21.1 % against "
    "16.7 %; the polygon-only curriculum's 17.2 %, so not kept): with 60 episodes a point "
    "(one is 1.7 points) that lead was within noise, and it did not carry over. Time: two "
    "runs at a time on the 2 cores."
)
"""What the curricula's runs showed (their validation curves, the one not kept)."""


def sensor_lines(succ: dict, rate: dict) -> list[str]:
    """The second peer at level sensor (no static reading, the goal's direction), where it
    was trained, beside the methods at that level, on the same episodes."""
    rows = []
    for fam in FAMILIES:
        me = succ.get((fam, f"ppo-{fam}-sensor", "sensor"))
        if me is None:
            continue
        arms = {m: succ.get((fam, m, "sensor")) for m in ("straight", "compass-guard",
                                                           "copi-learnt")}  # fmt: skip
        if any(v is None for v in arms.values()):
            continue
        at = rate[fam, f"ppo-{fam}-sensor", "sensor"]
        rows.append(
            f"| {fam} | {_pct(rate[fam, 'straight', 'sensor'])} | "
            f"{_pct(rate[fam, 'compass-guard', 'sensor'])} | "
            f"{_pct(rate[fam, 'copi-learnt', 'sensor'])} | "
            f"{_pct(rate.get((fam, f'ppo-{fam}-map', 'map'), math.nan))} | {_pct(at)} | "
            f"{_compare(me, arms['straight'], '', '')[0]} | "
            f"{_compare(me, arms['compass-guard'], '', '')[0]} | "
            f"{_compare(arms['copi-learnt'], me, '', '')[0]} |"
        )
    if not rows:
        return []
    return [
        "## One policy per level: the second peer at sensor",
        "",
        "`ppo-F-sensor`: the second peer's training (`copi-local-v3`, copi rl train's "
        "defaults) at level sensor only: no static reading, so the hits the map does not "
        "explain are not told apart, and the goal's direction instead of the route's "
        "(`python studies/rl_train_all.py --only F-sensor --seeds 0`). Beside the methods "
        "at the same level on the same episodes, and its own family's map-level policy; "
        "trained where the table shows only.",
        "",
        "| family | straight | compass-guard | copi-learnt | ppo-F-map (map) | ppo-F-sensor | "
        "Δ ppo-F-sensor − straight | Δ ppo-F-sensor − compass-guard | Δ copi-learnt − "
        "ppo-F-sensor |",
        "|---|---|---|---|---|---|---|---|---|",
        *rows,
        "",
    ]


SARL_BESIDE = (("tracked-mpc", "map"), ("model-oracle", "oracle"), ("copi-predictive", "map"),
               ("compass-guard", "map"), ("navground-hrvo", "oracle"), ("straight", "map"))
"""What SARL stands beside: the goal's tracked-mpc, the reference planner at its own
level, copi's learnt planner, the guard, navground's best peer at oracle, and straight."""


def sarl_lines(succ: dict, rate: dict) -> list[str]:
    """CrowdNav's peer: SARL at oracle, trained on crowd, in every family beside what
    plans or guards, on the same episodes."""
    if not any(m == "sarl" for _, m, _ in succ):
        return []
    shipped = SEEDS.parent / "sarl" / "sarl-crowd.json"
    info = json.loads(shipped.read_text()).get("info", {}) if shipped.is_file() else {}
    rows = []
    for fam in FAMILIES:
        me = succ.get((fam, "sarl", "oracle"))
        if me is None:
            continue
        cells = []
        for m, lv in SARL_BESIDE:
            other = succ.get((fam, m, lv))
            cells.append("—" if other is None else
                         f"{_pct(rate[fam, m, lv])} ({_compare(me, other, '', '')[0]})")
        rows.append(f"| {fam} | {_pct(rate[fam, 'sarl', 'oracle'])} | " + " | ".join(cells)
                    + " |")
    crowd = succ.get(("crowd", "sarl", "oracle"))
    goal = ""
    if crowd is not None and ("crowd", "tracked-mpc", "map") in succ:
        d, _, better = _compare(crowd, succ["crowd", "tracked-mpc", "map"], "", "")
        met = rate["crowd", "sarl", "oracle"] >= rate["crowd", "tracked-mpc", "map"]
        goal = (f"The goal (sarl at oracle in crowd at or above tracked-mpc): "
                f"{'met' if met else '**missed**'}, {_pct(rate['crowd', 'sarl', 'oracle'])} "
                f"against {_pct(rate['crowd', 'tracked-mpc', 'map'])} ({d}).")
    cfg = info.get("config", {})
    curve = json.loads(shipped.read_text()).get("curve", []) if shipped.is_file() else []
    kept = next((c["episodes"] for c in curve if c["validation"] == info.get("validation")),
                None)  # fmt: skip
    which = ("the network after imitation alone: RL did not improve it on validation"
             if kept == 0 else f"the network after {kept} episodes of RL")
    how = (f"{cfg.get('demo_episodes', '?')} demonstrations of {cfg.get('demonstrator', '?')}, "
           f"then {cfg.get('rl_episodes', '?')} episodes of CrowdNav's RL; best validation "
           f"{_pct(info.get('validation', math.nan))} (seed 1, "
           f"{cfg.get('validation_episodes', '?')} crowd episodes: {which}), "
           f"{info.get('seconds', 0) / 60:.0f} min on one core once the demonstrations "
           "were recorded") if info else "—"
    return [
        "## CrowdNav's peer: SARL (level oracle)",
        "",
        "`sarl`: CrowdNav's SARL (Chen et al. 2019): a value network attending over the "
        "discs it is told of (positions and velocities: level oracle) with the static "
        "reading beside the robot's own state, each of 81 moves (5 speeds in 16 directions, "
        "and standing still) scored by the reward of its step plus the discounted value of "
        "the state one step on, every disc carried on at its velocity. Trained as CrowdNav "
        "trains it: imitation of a demonstrator's returns (here copi's reference planner, "
        "model-oracle, instead of ORCA), then RL with targets from a target network and "
        "epsilon-greedy episodes, on crowd's training episodes; the network that did best "
        f"on validation episodes kept ({how}; `python studies/sarl_train.py --out "
        "results/sarl --install`). Learnt: the value; hand-written: the reward, the "
        "one-step lookahead and the frame (what SARL's paper writes by hand too). What "
        "differs from CrowdNav's SARL: the static reading beside the robot's state and no "
        "move into a wall (its scenarios have no walls); the reward, in agent steps, adds "
        "progress along the route and a time cost to the goal's bonus (1), the contact's "
        "penalty (1, CrowdNav's 0.25) and a proximity penalty (up to 0.5 within 1 step); "
        "a discount of 0.95 a step (CrowdNav's 0.974); Adam instead of SGD; narrower "
        "layers; and far fewer episodes of RL (hundreds, CrowdNav's 10,000), epsilon "
        "from 0.3 to 0.05 over 300. The imitation's length (26 passes) was chosen on "
        "validation seed 1 in crowd (longer fits did worse there) and kept in circle "
        "crossing; nothing was tuned on the "
        "reported episodes. Each cell: success, then sarl's minus the method's on the "
        "same episodes.",
        "",
        "| family | sarl (oracle) | " + " | ".join(f"{m} ({lv})" for m, lv in SARL_BESIDE)
        + " |",
        "|---|---|" + "---|" * len(SARL_BESIDE),
        *rows,
        "",
        goal,
        "",
        "The same network and recipe trained in CrowdNav's own scenario (`sarl-crowdnav`: "
        "circle crossing, imitating CrowdNav's ORCA robot) is set beside SARL's published "
        "number in [CrowdNav's scenarios](crowdnav.md), which checks this SARL against "
        "CrowdNav's. Their validation curves (success after imitation, then every 100 "
        "episodes of RL; the best kept):",
        "",
        *[f"![{n}](rl-curve-{n}.png)" for n in ("sarl-crowd", "sarl-circle-crossing")
          if (DOCS / f"rl-curve-{n}.png").is_file()],
        "",
    ]


def tuning_lines(out: Path) -> list[str]:
    """The second peer's tuning table, from the runs of ``rl_train_all.py --tune`` in
    ``out`` (absent runs are left out)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from rl_train_all import TUNING_SECOND

    rows = []
    for name, flags in TUNING_SECOND.items():
        path = out / f"tune2-{name}.json"
        if not path.is_file():
            continue
        info = json.loads(path.read_text())
        curve = info["curve"]
        last3 = float(np.mean([c["success"] for c in curve[-3:]]))
        rows.append(f"| {name} | `{' '.join(flags) or '(the defaults)'}` | {info['steps']:,} | "
                    f"{100 * curve[-1]['success']:.1f} % | {100 * last3:.1f} % |")  # fmt: skip
    if not rows:
        return []
    return [
        "Settings tried for the second peer (`python studies/rl_train_all.py --tune --out "
        "results/rl`: star at map, training seed 0, validation success on 100 episodes of "
        "seed 1; the defaults were kept unless a change stood above them by more than the "
        "noise of 100 episodes, about 6 points):",
        "",
        "| setting | flags beside the defaults | steps | last validation | "
        "mean of the last three |",
        "|---|---|---|---|---|",
        *rows,
        "",
    ]


def won(store: Path) -> dict[tuple[str, str, str], dict[int, bool]]:
    """Success per episode of every (family, method, level) of a benchmark store."""
    groups, _, _ = read_benchmark(store)
    return {(fam, arm.method, arm.sensing): _success(rows)
            for fam, arms in groups.items() for arm, rows in arms.items()}  # fmt: skip


STAR_ONLY = {"directions": 16, "safety": True, "probe_families": "star"}
"""copi-learnt learnt in star worlds alone, its probing walks too (the preset's default
also probes crowd, polygon and indoor worlds)."""
LEAN = {**STAR_ONLY, "worlds": 20, "probe_worlds": 8, "probe_steps": 60}
"""The same at a hundredth of PPO's 2M environment steps: 20 exploration worlds instead
of 100, 8 probing walks of 60 steps instead of 60 of 150 (18,720 simulated steps). Set by
that budget, not tuned."""


def variant(bench: Path, name: str, params: dict, episodes: int, workers: int,
            levels: tuple[str, ...] = ("map", "sensor")) -> tuple[dict, dict, Path]:  # fmt: skip
    """copi-learnt with capabilities learnt with ``LearnParams(**params)`` on the
    benchmark's episodes: success per (family, level), its rate, and the capabilities
    file (learnt once into ``bench``; the episodes in ``bench/variant-NAME.sqlite``)."""
    path = bench / f"capabilities-learnt-{name}.npz"
    if not path.is_file():
        t0 = time.perf_counter()
        learn(LearnParams(**params)).save(path)
        took = time.perf_counter() - t0
        kept_times(bench / "rl-timing.json", {f"{name}-learn": (took, round(took))})
    config = BenchmarkConfig(
        methods=tuple(parse_methods(",".join(f"copi-learnt@{lv}" for lv in levels))),
        families=FAMILIES, episodes=episodes, capabilities={"learnt": str(path)},
    )  # fmt: skip
    store = bench / f"variant-{name}.sqlite"
    run_benchmark(config, store, workers=workers)
    succ = {(fam, level): w for (fam, _, level), w in won(store).items()}
    rate = {key: float(np.mean(list(w.values()))) for key, w in succ.items()}
    return succ, rate, path


SEEDS = Path(__file__).resolve().parents[1] / "src" / "copi" / "data" / "rl" / "seeds"
"""The policies of the other training seeds (``ppo-F-sS.npz``, S >= 1), shipped so that
the spread over seeds is measured without training (seed 0's are the benchmark's)."""


def _seed_policies() -> dict[str, tuple[str, int]]:
    """Each shipped training seed's policy registered as a method of its own
    (``ppo-F-sS``: its weights read from the file, as :class:`PPOAgent` reads any, and
    their content part of every run's identity): {method: (configuration, seed)}."""
    out = {}
    for path in sorted(SEEDS.glob("ppo-*-s*.npz")):
        config, seed = path.stem.removeprefix("ppo-").rsplit("-s", 1)
        # copi's own PPOAgent (no guard: played as trained), so that the identity of its
        # runs is its weights and parameters, not this script's code
        register_method(path.stem, PPOAgent, params={"weights": f"seeds/{path.stem}",
                                                     "guard": 0.0},
                        summary=f"PPO ({config}), training seed {seed}",
                        inputs=lambda p=path: {"weights_sha": file_sha(p)},
                        replace=True)  # fmt: skip
        out[path.stem] = (config, int(seed))
    return out


def seed_spread(bench: Path, episodes: int, games: int) -> dict[tuple[str, int, str], dict]:
    """Success per episode at level map of every shipped training seed's policy on the
    benchmark's episodes (in-family ones on their family, the mix's on each family) and
    survival per game of the chauffeur's: ``{(config, seed, family or "game"): {k: won}}``
    (seed 0's in-family and mix rows are in the benchmark's store); in
    ``bench/seeds.sqlite`` and ``bench/chauffeur.sqlite``, in this process (the seeds'
    methods are registered here only)."""
    policies = _seed_policies()
    store = bench / "seeds.sqlite"
    spread: dict[tuple[str, int, str], dict] = {}
    for fam in FAMILIES:
        names = [m for m, (c, _) in policies.items() if c in (fam, "mix", f"{fam}-map")]
        if names:
            config = BenchmarkConfig(methods=tuple(parse_methods(",".join(f"{m}@map"
                                                                          for m in names))),
                                     families=(fam,), episodes=episodes)  # fmt: skip
            run_benchmark(config, store)
    if store.is_file():
        for (fam, method, _), w in won(store).items():
            config, seed = policies[method]
            spread[config, seed, fam] = w
    for method, (config, seed) in policies.items():
        if config == "chauffeur":
            spread[config, seed, "game"] = play(bench / "chauffeur.sqlite", PursuitConfig(
                capabilities=None, evader=method, games=games, seed=0))  # fmt: skip
    return spread


def play(store: Path, config: PursuitConfig) -> dict[int, bool]:
    """Survival per game of ``config``'s evader, played into ``store``."""
    t0 = time.perf_counter()
    run = pursue(config, store)
    with ResultsStore(store, readonly=True) as s:
        rows = s.games(run)
    print(f"chauffeur, {config.method}: {np.mean([r.outcome == 'escaped' for r in rows]):.3f} "
          f"survival ({time.perf_counter() - t0:.0f} s)", flush=True)  # fmt: skip
    return {int(r.game): r.outcome == "escaped" for r in rows if r.game < config.games}


def play_games(bench: Path, caps: Path, games: int) -> dict[str, dict[int, bool]]:
    """Survival per game of each evader of :data:`EVADERS`."""
    return {e: play(bench / "chauffeur.sqlite",
                    PursuitConfig(capabilities=str(caps) if e != "game" else None, evader=e,
                                  games=games, seed=0))
            for e in EVADERS}  # fmt: skip


def copi_validation(caps_path: Path, policies: dict[str, dict]) -> dict[str, float]:
    """copi-learnt's success on each PPO configuration's validation episodes."""
    caps = Capabilities.load(caps_path)
    out = {}
    for name, info in policies.items():
        c = info["config"]
        cfg = TrainConfig(families=tuple(c["families"]), levels=tuple(c["levels"]),
                          task=c["task"], observation=c.get("observation", "copi-local-v2"),
                          frames=c.get("frames", 2))  # fmt: skip
        n = info.get("validation_episodes", 60)
        agent = make_agent("copi-learnt", caps)
        out[name] = validation_success(None, cfg, n, agent=agent)
    return out


def copi_cost(caps_path: Path) -> tuple[int, str]:
    c = simulated_steps(Capabilities.load(caps_path).params)
    return c["total"], (
        f"{c['exploration']:,} exploration steps, {c['walks']:,} steps of probing walks and at "
        f"most {c['probes']:,} counterfactual probe steps"
    )


def figure(policies: dict[str, dict], copi_val: dict[str, float], copi_samples: int,
           out: Path, lean: tuple[dict[str, float], int] | None = None) -> None:  # fmt: skip
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(11, 4.8))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, (name, info) in enumerate(sorted(policies.items())):
        curve = info["curve"]
        c = colors[i % len(colors)]
        ax.plot([p["steps"] for p in curve], [100 * p["success"] for p in curve], "-",
                color=c, label=f"{name} (PPO)")  # fmt: skip
        ax.plot([copi_samples], [100 * copi_val[name]], "*", ms=14, color=c,
                markeredgecolor="k", label=f"copi-learnt on {name}'s episodes")  # fmt: skip
        if lean is not None:
            ax.plot([lean[1]], [100 * lean[0][name]], "D", ms=8, color=c,
                    markeredgecolor="k")  # fmt: skip
    finish_cost_figure(
        fig, ax, out,
        xlabel="learning samples (environment steps; copi: exploration and probes, no task)",
        title="Learning cost: PPO's curves against copi-learnt (stars; diamonds: learnt at "
              "1/100 of PPO's samples), seed 1 episodes",
    )  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--bench", default="results/rl-bench")
    ap.add_argument("--episodes", type=int, default=200)
    ap.add_argument("--games", type=int, default=200)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="docs/rl.md")
    ap.add_argument("--policies", default="results/rl", help="where rl_train_all.py trained "
                    "(its tuning runs' curves)")
    a = ap.parse_args()
    bench = Path(a.bench)
    bench.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    benchmark(bench, a.episodes, a.workers)
    t_bench = time.perf_counter() - t0
    groups, _, _ = read_benchmark(bench / "benchmark.sqlite")
    caps = bench / "capabilities-learnt.npz"
    succ: dict[tuple[str, str, str], dict[int, bool]] = {}
    rate: dict[tuple[str, str, str], float] = {}
    for fam, arms in groups.items():
        for arm, rows in arms.items():
            succ[fam, arm.method, arm.sensing] = _success(rows)
            rate[fam, arm.method, arm.sensing] = summarize_rows(rows)["success"]
    policies = {}
    for name in ["mix", *FAMILIES, "chauffeur", *[f"{f}-map" for f in FAMILIES]]:
        path = packaged_policy(f"ppo-{name}").with_suffix(".json")
        if path.is_file():
            policies[f"ppo-{name}"] = json.loads(path.read_text())
    star_succ, star_rate, _ = variant(bench, "star-only", STAR_ONLY, a.episodes, a.workers)
    lean_succ, lean_rate, lean_caps = variant(bench, "lean", LEAN, a.episodes, a.workers,
                                              ("map",))
    # wall times of the runs that did the work (a rerun that only resumes keeps them)
    t1 = time.perf_counter()
    games = play_games(bench, caps, a.games)
    # copi learnt at 1/100 plays as the same evader: its own store
    lean_games = play(bench / "chauffeur-lean.sqlite",
                      PursuitConfig(capabilities=str(lean_caps), evader="learnt", games=a.games,
                                    seed=0))  # fmt: skip
    t_games = time.perf_counter() - t1
    seeds = seed_spread(bench, a.episodes, a.games)
    timing = kept_times(bench / "rl-timing.json",
                        {"bench": (t_bench, round(t_bench)), "games": (t_games, round(t_games))})
    took_lean = timing.get("lean-learn", math.nan)
    t_bench, t_games = timing["bench"], timing["games"]
    copi_val = copi_validation(caps, policies)
    samples, how = copi_cost(caps)

    lines = [
        "# copi against deep RL",
        "",
        "<!-- generated: written whole by studies/rl_experiments.py -->",
        "",
        f"`python studies/rl_experiments.py --bench {a.bench} --episodes {a.episodes} "
        f"--games {a.games}` ({t_bench / 60:.0f} min of benchmark, {t_games / 60:.0f} "
        "min of games, on 2 cores). Benchmark seed 0, episodes 0 .. "
        f"{a.episodes - 1} of each family; PPO trained on training seeds, its settings "
        "chosen on validation seed 1 (`studies/rl_train_all.py --tune`). Δ: paired "
        "differences in points with 95 % bootstrap intervals; the winner is named only "
        "where the interval excludes 0.",
        "",
        *second_peer_lines(succ, rate),
        *tuning_lines(Path(a.policies)),
        *sac_lines(succ, rate),
        *il_lines(succ, rate),
        *clone_lines(succ, rate),
        *curriculum_lines(succ, rate),
        *sensor_lines(succ, rate),
        *sarl_lines(succ, rate),
        "## The first peer, in family (level map, then sensor)",
        "",
        "copi-learnt: the learnt preset's capabilities, learnt once without any task (their "
        "exploration in star worlds, their probes in star, crowd, polygon and indoor worlds).",
        "",
        "| family | sensing | copi-learnt | compass-guard | dwa | straight | ppo (mix) | "
        "ppo-guard | ppo-F (in family) | Δ copi-learnt − ppo-F | better | Δ ppo-F − straight |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for level in ("map", "sensor"):
        for fam in FAMILIES:
            c = succ.get((fam, "copi-learnt", level))
            p = succ.get((fam, f"ppo-{fam}", level))
            if c is None or p is None:
                continue
            cells = [
                _pct(rate.get((fam, m, level), math.nan))
                for m in ("copi-learnt", "compass-guard", "dwa", "straight", "ppo", "ppo-guard",
                          f"ppo-{fam}")
            ]  # fmt: skip
            d, better, _ = _compare(c, p, "copi-learnt", f"ppo-{fam}")
            st = succ.get((fam, "straight", level))
            d_st = _compare(p, st, "", "")[0] if st is not None else "—"
            lines.append(
                f"| {fam} | {level} | "
                + " | ".join(cells)
                + f" | {d} | {better} | {d_st} |"
            )
    lines += [
        "",
        "Read PPO's rows with this in mind: trained on copi's observation (the ranges, "
        "their change, the global direction) with five settings tried on validation seed "
        "1, and a contact cost of 50 instead of 10 tried on star (no better), it learnt "
        "to follow the global direction at full speed and to swerve late, not to wait or "
        "back off: the last column compares it with `straight` (the direction, no "
        "avoidance). These rows show what the first peer reached in 2M steps without the "
        "static reading copi's methods read at map, not what deep RL can do: the second "
        "peer (the section above) is given that reading, one policy per level.",
        "",
        "## Training seeds (level map)",
        "",
        "Each policy trained with other seeds (the same command, `--seed S`; their weights "
        "ship in `src/copi/data/rl/seeds`), on the same episodes. Seed 0 is the policy of "
        "every other table; mean and standard deviation over the seeds trained; the last "
        "column: copi-learnt minus the seeds' mean (points). The mix's row is its mean "
        "success over the five families, the chauffeur's the survival in the games below.",
        "",
        "| policy | seeds | success per seed | mean ± sd | copi-learnt | copi-learnt − mean |",
        "|---|---|---|---|---|---|",
        *seed_rows(succ, seeds, games),
        "",
        "## A new world: both learnt on `star` only, tested on the others (level map, then sensor)",
        "",
        "copi-learnt here is learnt in star worlds alone, its probing walks included "
        "(`LearnParams(directions=16, safety=True, probe_families=\"star\")`; the preset's "
        "default probes star, crowd, polygon and indoor worlds), without any task.",
        "",
        "| family | sensing | copi-learnt (star only, no task) | ppo-star | ppo-F (in family) | "
        "Δ copi-learnt − ppo-star | better |",
        "|---|---|---|---|---|---|---|",
    ]
    wins_new = 0
    for level in ("map", "sensor"):
        for fam in FAMILIES[1:]:
            c = star_succ.get((fam, level))
            p = succ.get((fam, "ppo-star", level))
            if c is None or p is None:
                continue
            d, better, won = _compare(c, p, "copi-learnt", "ppo-star")
            wins_new += won and level == "map"
            lines.append(
                f"| {fam} | {level} | {_pct(star_rate[fam, level])} | "
                f"{_pct(rate[fam, 'ppo-star', level])} | "
                f"{_pct(rate.get((fam, f'ppo-{fam}', level), math.nan))} | {d} | "
                f"{better} |"
            )
    lines += [
        "",
        f"copi-learnt ahead of ppo-star (interval above 0) at map on {wins_new} of the "
        "4 other families.",
        "",
        f"## A new task: the homicidal chauffeur's evader ({a.games} games, seed 0, "
        "the same games for every evader)",
        "",
        "| evader | survival | Δ copi-learnt − it | better |",
        "|---|---|---|---|",
    ]
    base = games["learnt"]
    names = {"learnt": "copi-learnt (capabilities unchanged)", "game": "the game's direction "
             "itself (no avoidance)", "ppo": "ppo (navigation policy, game's direction)",
             "ppo-guard": "ppo-guard", "ppo-chauffeur": "ppo-chauffeur (trained for the game)",
             "compass-guard": "compass-guard"}  # fmt: skip
    for e in EVADERS:
        d, better, _ = _compare(base, games[e], "copi-learnt", e) if e != "learnt" else (
            "—", "", False)
        lines.append(
            f"| {names[e]} | {_pct(float(np.mean(list(games[e].values()))))} | {d} | {better} |"
        )
    # the same experiments against the second peer (their scripts splice them alone too)
    lines += ["", *new_task_lines(bench / "game", a.games)]
    lines += lean_like_lines(bench / "lean-like", a.episodes, a.workers,
                             Path(a.out).parent / "rl-lean-like.png")  # fmt: skip
    lines += lean_rows(took_lean, LEAN, lean_succ, lean_rate, lean_games, succ, rate, games,
                       policies)  # fmt: skip
    lines += [
        "",
        "## What each learner cost",
        "",
        f"copi-learnt: {samples:,} simulated steps ({how}), learnt once without any "
        "task and used unchanged in every family and in the game.",
        "",
        "| PPO policy | environment steps | wall time | steps / s | validation success "
        "at the end | mean success, steps 1.0-1.5M / 1.5-2.0M | copi-learnt on the same "
        "episodes | PPO first reaches copi at |",
        "|---|---|---|---|---|---|---|---|",
    ]
    moves: dict[str, float] = {}
    for name, info in sorted(policies.items()):
        curve = info["curve"]
        cv = copi_val[name]
        cross = next((p["steps"] for p in curve if p["success"] >= cv), None)
        halves = [[p["success"] for p in curve if lo < p["steps"] <= hi]
                  for lo, hi in ((1_000_000, 1_500_000), (1_500_000, 2_100_000))]  # fmt: skip
        late = " / ".join(_pct(float(np.mean(h))) if h else "—" for h in halves)
        if all(halves):
            moves[name] = 100 * (float(np.mean(halves[1])) - float(np.mean(halves[0])))
        lines.append(
            f"| {name} | {info['steps']:,} | {info['seconds'] / 60:.1f} min | "
            f"{info['steps_per_second']:,.0f} | {_pct(curve[-1]['success'])} | {late} | "
            f"{_pct(cv)} | "
            f"{f'{cross:,} steps' if cross else 'not within the budget'} |"
        )
    most = max(moves, key=lambda k: abs(moves[k])) if moves else None
    if most is not None:
        lines += ["", "How the curves flatten: from the first to the second half of the second "
                  "million steps, mean validation success moves by at most "
                  f"{abs(moves[most]):.1f} points ({most}; 60 episodes a point, one episode "
                  "is 1.7 points). The longest run took "
                  f"{max(i['seconds'] for i in policies.values()) / 60:.0f} min (runs two at a "
                  "time, one per core)."]  # fmt: skip
    lines += ["", "![learning cost](rl.png)", "",
              "The learning curves of the shipped policies (validation success against "
              "environment steps, as `copi rl train` draws them):", ""]
    for name in ["mix", *FAMILIES, "chauffeur", *[f"{f}-map" for f in FAMILIES]]:
        if (Path(a.out).parent / f"rl-curve-{name}.png").is_file():
            lines.append(f"![ppo-{name}](rl-curve-{name}.png)")
    lines.append("")
    out = Path(a.out)
    lean_val = copi_validation(lean_caps, policies)
    lean_samples = copi_cost(lean_caps)[0]
    figure(policies, copi_val, samples, out.with_suffix(".png"), (lean_val, lean_samples))
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")
    if "clairvoyant" in {arm.method for arms in groups.values() for arm in arms}:
        # the episodes the oracle ran (ceilings.py's --oracle-episodes)
        n_oracle = max((len(rows) for arms in groups.values() for arm, rows in arms.items()
                        if arm.method == "model-oracle"), default=0)  # fmt: skip
        page = out.parent / "benchmark-bounds.md"
        print(f"wrote {write_bounds_page(bench, a, page, n_oracle)}")
    else:  # a store of this script's methods alone: the bounds page is ceilings.py's
        print(f"{bench} holds no bounds (studies/ceilings.py): benchmark-bounds.md kept")


def seed_rows(succ: dict, seeds: dict[tuple[str, int, str], dict[int, bool]],
              games: dict[str, dict[int, bool]]) -> list[str]:  # fmt: skip
    """The rows of the training-seeds table (see :func:`seed_spread`)."""

    def rate(won: dict[int, bool]) -> float:
        return 100 * float(np.mean(list(won.values())))

    def row(name: str, per: dict[int, float], copi: float) -> str:
        rates = [per[s] for s in sorted(per)]
        mean = float(np.mean(rates))
        sd = float(np.std(rates, ddof=1)) if len(rates) > 1 else math.nan
        return (f"| {name} | {', '.join(map(str, sorted(per)))} | "
                f"{', '.join(f'{r:.1f} %' for r in rates)} | {mean:.1f} ± "
                f"{'—' if math.isnan(sd) else f'{sd:.1f}'} | {copi:.1f} % | {copi - mean:+.1f} |")

    rows = []
    for config in [*FAMILIES, *[f"{f}-map" for f in FAMILIES]]:
        fam = config.removesuffix("-map")
        first = succ.get((fam, f"ppo-{config}", "map"))
        if first is None:
            continue
        per = {0: rate(first), **{s: rate(w) for (c, s, f), w in seeds.items()
                                  if c == config and f == fam}}  # fmt: skip
        rows.append(row(f"ppo-{config}", per, rate(succ[(fam, "copi-learnt", "map")])))
    if all((f, "ppo", "map") in succ for f in FAMILIES):
        per = {0: float(np.mean([rate(succ[(f, "ppo", "map")]) for f in FAMILIES]))}
        for s in sorted({s for (c, s, _) in seeds if c == "mix"}):
            if all(("mix", s, f) in seeds for f in FAMILIES):
                per[s] = float(np.mean([rate(seeds["mix", s, f]) for f in FAMILIES]))
        copi = float(np.mean([rate(succ[(f, "copi-learnt", "map")]) for f in FAMILIES]))
        rows.append(row("ppo (mix)", per, copi))
    per = {0: rate(games["ppo-chauffeur"]),
           **{s: rate(w) for (c, s, _), w in seeds.items() if c == "chauffeur"}}  # fmt: skip
    rows.append(row("ppo-chauffeur (survival)", per, rate(games["learnt"])))
    return rows


def lean_rows(took: float, params: dict, lean_succ: dict, lean_rate: dict,
              lean_games: dict[int, bool], succ: dict, rate: dict, games: dict,
              policies: dict) -> list[str]:  # fmt: skip
    """The section on copi learnt at a hundredth of PPO's samples (see :data:`LEAN`)."""
    cost = simulated_steps(LearnParams(**params))["total"]
    ppo = min(info["steps"] for info in policies.values())
    shown = ", ".join(f"{k}={v!r}" for k, v in params.items())
    lines = [
        "",
        "## copi at a hundredth of PPO's samples (level map)",
        "",
        f"copi-learnt from `LearnParams({shown})`: {cost:,} simulated steps, "
        f"1/{ppo / cost:.0f} of one PPO run's {ppo:,} environment steps, learnt in "
        f"{took:.0f} s on one core, star worlds only and no task (the setting is fixed by "
        "that budget, not tuned). Against each family's "
        "own PPO (`ppo-F`), against PPO trained on star (`ppo-star`: another world for every "
        "family but star) and, in the game, against PPO trained for it:",
        "",
        "| family | copi (1/100) | ppo-F (in family) | Δ copi − ppo-F | within 5 points or "
        "better | ppo-star | Δ copi − ppo-star | better |",
        "|---|---|---|---|---|---|---|---|",
    ]
    ahead, close = 0, 0
    for fam in FAMILIES:
        c, own, star = (lean_succ.get((fam, "map")), succ.get((fam, f"ppo-{fam}", "map")),
                        succ.get((fam, "ppo-star", "map")))  # fmt: skip
        if c is None or own is None or star is None:
            continue
        d_own, _, _ = _compare(c, own, "copi", f"ppo-{fam}")
        gap = 100 * (lean_rate[fam, "map"] - rate[fam, f"ppo-{fam}", "map"])
        close += gap >= -5
        d_star, better, won = _compare(c, star, "copi", "ppo-star")
        if fam == "star":
            d_star, better = "— (its own world)", ""
        else:
            ahead += won
        lines.append(
            f"| {fam} | {_pct(lean_rate[fam, 'map'])} | "
            f"{_pct(rate[fam, f'ppo-{fam}', 'map'])} | {d_own} | "
            f"{'yes' if gap >= -5 else f'**no** ({gap:+.1f})'} | "
            f"{_pct(rate[fam, 'ppo-star', 'map'])} | {d_star} | {better} |"
        )
    game_rows = []
    for e in ("ppo-chauffeur", "ppo"):
        d, better, _ = _compare(lean_games, games[e], "copi", e)
        game_rows.append(f"| {e} | {_pct(float(np.mean(list(games[e].values()))))} | {d} | "
                         f"{better} |")  # fmt: skip
    lines += [
        "",
        f"Within 5 points of (or above) in-family PPO on {close} of 5 families; ahead of "
        f"ppo-star (interval above 0) on {ahead} of the 4 other families.",
        "",
        f"In the chauffeur game ({len(lean_games)} games), copi (1/100) survives "
        f"{_pct(float(np.mean(list(lean_games.values()))))}:",
        "",
        "| evader | survival | Δ copi (1/100) − it | better |",
        "|---|---|---|---|",
        *game_rows,
    ]
    return lines


def write_bounds_page(bench: Path, a: argparse.Namespace, page: Path, n_oracle: int) -> Path:
    """The store's whole benchmark report (every method, the bounds, the RL peers) as the
    docs page ``page``, its figure beside it: the page the README and the analysis pages
    quote from. ``n_oracle``: the episodes model-oracle ran in the store."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))
    from benchmark_page import write_page

    command = (
        f"`python studies/ceilings.py --bench {a.bench} --episodes {a.episodes} "
        f"--oracle-episodes {n_oracle}` and `python studies/rl_experiments.py --bench "
        f"{a.bench} --episodes {a.episodes} --games {a.games}` (seed 0; model-oracle on the "
        f"first {n_oracle} episodes)"
    )
    what = (f"{a.episodes} episodes, with the clairvoyant bound, the reference planners and "
            "the RL peers")
    return write_page(bench, page, what, command)


if __name__ == "__main__":
    main()
