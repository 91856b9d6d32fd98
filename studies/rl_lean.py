"""copi at a hundredth of PPO's samples, like with like: docs/rl.md's section of that name.

    python studies/rl_lean.py --bench results/rl-lean --episodes 200

copi learnt at about 1/100 of one PPO run's 2M environment steps, in star worlds only
and with no task (:data:`LEAN_LEARNT`, :data:`LEAN_PREDICTIVE`: set by that budget, not
tuned), beside the second peer trained with the whole budget in each family, paired on
the benchmark's episodes (seed 0):

- learnt alone: ``copi-predictive`` (a learnt model of what moves and a planner over it,
  no hand-written guard) at 1/100 beside ``ppo-F-map`` (nothing hand-written);
- guarded: ``copi-learnt`` at 1/100 beside ``ppo-guard-F-map``, each filtered by
  compass-guard's hand-written guard;
- the cost: where ``ppo-F-map``'s learning curve (success on its 60 validation
  episodes, seed 1) first reaches copi-predictive at 1/100 on the same episodes.

Each family's episodes go into ``--bench/F.sqlite`` (resumable), the capabilities into
``--bench``; the section is written into ``--out`` in place of its last version (before
the section on the first peer's hundredth where there is none), and its figure beside.
:func:`lean_like_lines` is what ``studies/rl_experiments.py`` writes for it too.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from copi.baselines import packaged_policy  # noqa: E402
from copi.experiments import BenchmarkConfig, run_benchmark  # noqa: E402
from copi.learning import Capabilities, LearnParams, learn, simulated_steps  # noqa: E402
from copi.methods import make_agent, parse_methods  # noqa: E402
from copi.reports import read_benchmark  # noqa: E402
from copi.results import paired_difference, summarize_rows  # noqa: E402
from copi.rl import TrainConfig, validation_success  # noqa: E402
from studies._common import finish_cost_figure, kept_times, splice_section  # noqa: E402

FAMILIES = ("star", "polygon", "indoor", "maps", "crowd")
LEAN_LEARNT = {"directions": 16, "safety": True, "probe_families": "star", "worlds": 20,
               "probe_worlds": 8, "probe_steps": 60}  # fmt: skip
"""copi-learnt's capabilities at a hundredth of PPO's steps (docs/rl.md's first
hundredth: 20 exploration worlds instead of 100, 8 probing walks of 60 steps instead of
60 of 150, star worlds only)."""
LEAN_PREDICTIVE = {**LEAN_LEARNT, "safety_static": True, "predict": True,
                   "predict_worlds": 16, "predict_steps": 100}  # fmt: skip
"""copi-predictive's at the same budget: the same, and 16 walks of 100 steps for its
model of what moves instead of 80 of 200."""
SECTION = "## copi at a hundredth of PPO's samples, like with like (level map)"
NEXT = "## copi at a hundredth of PPO's samples (level map)"


def _key(params: dict) -> str:
    """A short digest of learning parameters: what is kept under it is theirs."""
    return hashlib.sha256(json.dumps(params, sort_keys=True).encode()).hexdigest()[:8]


def capabilities(bench: Path, name: str, params: dict) -> Path:
    """The capabilities learnt with ``params`` into ``bench`` (once; the seconds kept)."""
    path = bench / f"capabilities-{name}-{_key(params)}.npz"
    if not path.is_file():
        t0 = time.perf_counter()
        learn(LearnParams(**params)).save(path)
        took = time.perf_counter() - t0
        kept_times(bench / "timing.json", {f"{name}-learn": (took, round(took))})
    return path


def run(bench: Path, episodes: int, workers: int) -> dict[str, dict[tuple[str, str], list]]:
    """Each family's rows by (method, level): the copi methods at 1/100, the family's
    second peer (alone and guarded), the second peer learnt in star worlds (a new world
    for it too, in every family but star), straight and compass-guard."""
    caps = {"learnt": str(capabilities(bench, "learnt", LEAN_LEARNT)),
            "predictive": str(capabilities(bench, "predictive", LEAN_PREDICTIVE))}  # fmt: skip
    rows: dict[str, dict[tuple[str, str], list]] = {}
    for fam in FAMILIES:
        methods = (f"copi-predictive@map,copi-learnt@map,ppo-{fam}-map@map,"
                   f"ppo-guard-{fam}-map@map,straight@map,compass-guard@map"
                   + (",ppo-star-map@map" if fam != "star" else ""))  # fmt: skip
        config = BenchmarkConfig(methods=tuple(parse_methods(methods)), families=(fam,),
                                 episodes=episodes, capabilities=caps)  # fmt: skip
        store = bench / f"{fam}.sqlite"
        run_benchmark(config, store, workers=workers)
        groups, _, _ = read_benchmark(store)
        rows[fam] = {(arm.method, arm.sensing): r for arm, r in groups[fam].items()}
    return rows


def _won(rows: list) -> dict[int, bool]:
    return {int(r["episode"]): r["outcome"] == "success" for r in rows
            if r["outcome"] != "skipped"}  # fmt: skip


def _delta(a: dict[int, bool], b: dict[int, bool], who_a: str, who_b: str) -> tuple[str, str]:
    common = sorted(set(a) & set(b))
    d = paired_difference([a[k] for k in common], [b[k] for k in common])
    text = f"{100 * d.estimate:+.1f} [{100 * d.low:+.1f}, {100 * d.high:+.1f}]"
    if not d.excludes_zero:
        return text, "neither (interval holds 0)"
    return text, f"**{who_a}**" if d.estimate > 0 else f"**{who_b}**"


def _pct(x: float) -> str:
    return "—" if not math.isfinite(x) else f"{100 * x:.1f} %"


def validation(bench: Path, path: Path) -> dict[str, float]:
    """copi-predictive at 1/100 on each ``ppo-F-map``'s validation episodes (kept in
    ``bench``: a rerun does not replay them)."""
    kept = bench / f"validation-{path.stem}.json"  # by the capabilities' parameters
    done = json.loads(kept.read_text()) if kept.is_file() else {}
    caps = Capabilities.load(path)
    for fam in FAMILIES:
        name = f"ppo-{fam}-map"
        if name in done:
            continue
        info = json.loads(packaged_policy(name).with_suffix(".json").read_text())
        c = info["config"]
        cfg = TrainConfig(families=tuple(c["families"]), levels=tuple(c["levels"]),
                          observation=c["observation"], frames=c["frames"])  # fmt: skip
        agent = make_agent("copi-predictive", caps)
        done[name] = validation_success(None, cfg, info.get("validation_episodes", 60),
                                        agent=agent)  # fmt: skip
        kept.write_text(json.dumps(done))
    return done


def figure(curves: dict[str, dict], copi_val: dict[str, float], samples: int, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(10, 4.6))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, (name, info) in enumerate(curves.items()):
        c = colors[i % len(colors)]
        curve = info["curve"]
        ax.plot([p["steps"] for p in curve], [100 * p["success"] for p in curve], "-", color=c,
                label=f"{name} (PPO)")  # fmt: skip
        ax.plot([samples], [100 * copi_val[name]], "D", ms=9, color=c, markeredgecolor="k",
                label=f"copi-predictive at 1/100 on {name}'s episodes")  # fmt: skip
    finish_cost_figure(
        fig, ax, out,
        xlabel="learning samples (environment steps; copi: its walks and probes, no task)",
        title="Learnt alone: the second peer's curves against copi-predictive learnt at "
              "1/100 of its samples (seed 1 episodes)",
    )  # fmt: skip


def lean_like_lines(bench: Path, episodes: int, workers: int, figure_path: Path) -> list[str]:
    """docs/rl.md's section (see the module's docstring); runs what is not in ``bench``."""
    bench.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    rows = run(bench, episodes, workers)
    took = time.perf_counter() - t0
    times = kept_times(bench / "timing.json", {"bench": (took, round(took))})
    copi_val = validation(bench, capabilities(bench, "predictive", LEAN_PREDICTIVE))
    curves = {f"ppo-{f}-map": json.loads(packaged_policy(f"ppo-{f}-map").with_suffix(".json")
                                         .read_text()) for f in FAMILIES}  # fmt: skip
    cost = {k: simulated_steps(LearnParams(**p))["total"]
            for k, p in (("learnt", LEAN_LEARNT), ("predictive", LEAN_PREDICTIVE))}  # fmt: skip
    ppo = min(info["steps"] for info in curves.values())
    figure(curves, copi_val, cost["predictive"], figure_path)
    alone, guarded, new_world = [], [], []
    ahead_alone = ahead_guard = ahead_new = 0
    for fam in FAMILIES:
        r = rows[fam]
        won = {m: _won(r[m, "map"]) for m, _ in r}
        rate = {m: summarize_rows(r[m, "map"])["success"] for m, _ in r}
        peer, shield = f"ppo-{fam}-map", f"ppo-guard-{fam}-map"
        d, better = _delta(won["copi-predictive"], won[peer], "copi-predictive (1/100)", peer)
        ahead_alone += better.startswith("**copi")
        info = curves[peer]
        cross = next((p["steps"] for p in info["curve"] if p["success"] >= copi_val[peer]),
                     None)  # fmt: skip
        alone.append(
            f"| {fam} | {_pct(rate['straight'])} | {_pct(rate['compass-guard'])} | "
            f"{_pct(rate['copi-predictive'])} | {_pct(rate[peer])} | {d} | {better} | "
            f"{_pct(copi_val[peer])} | {_pct(info['kept_success'])} at "
            f"{info['kept_steps'] / 1e6:.1f}M / {_pct(info['curve'][-1]['success'])} | "
            f"{f'{cross:,} steps' if cross is not None else 'not within its 2M steps'} |"
        )
        if fam != "star":
            d, better = _delta(won["copi-predictive"], won["ppo-star-map"],
                               "copi-predictive (1/100)", "ppo-star-map")  # fmt: skip
            ahead_new += better.startswith("**copi")
            new_world.append(f"| {fam} | {_pct(rate['copi-predictive'])} | "
                             f"{_pct(rate['ppo-star-map'])} | {_pct(rate[peer])} | {d} | "
                             f"{better} |")  # fmt: skip
        d, better = _delta(won["copi-learnt"], won[shield], "copi-learnt (1/100)", shield)
        ahead_guard += better.startswith("**copi")
        guarded.append(f"| {fam} | {_pct(rate['compass-guard'])} | {_pct(rate['copi-learnt'])} | "
                       f"{_pct(rate[shield])} | {d} | {better} |")  # fmt: skip
    shown = {k: ", ".join(f"{a}={v!r}" for a, v in p.items())
             for k, p in (("learnt", LEAN_LEARNT), ("predictive", LEAN_PREDICTIVE))}  # fmt: skip
    learn_s = {k: times.get(f"{k}-learn", math.nan) for k in ("learnt", "predictive")}
    return [
        SECTION,
        "",
        f"`python studies/rl_lean.py --bench {bench} --episodes {episodes}` "
        f"({times['bench'] / 60:.0f} min, {workers} workers). copi learnt in star worlds alone, "
        "without any task, at about a hundredth of one second-peer run's "
        f"{ppo:,} environment steps: copi-predictive from `LearnParams({shown['predictive']})` "
        f"({cost['predictive']:,} simulated steps, 1/{ppo / cost['predictive']:.0f}; "
        f"{learn_s['predictive']:.0f} s), copi-learnt from `LearnParams({shown['learnt']})` "
        f"({cost['learnt']:,}, 1/{ppo / cost['learnt']:.0f}; {learn_s['learnt']:.0f} s); "
        "the settings are fixed by that budget, not tuned. Beside the second peer, trained "
        "with the whole budget in each family itself (every family but star is a new world "
        "for copi here, not for the peer). Learnt alone (no hand-written guard on the live "
        "reading; copi-predictive's planner, written by hand as SARL's one-step lookahead "
        "is, checks its moves against the known map's walls and the futures its learnt "
        "model drew):",
        "",
        "| family | straight | compass-guard | copi-predictive (1/100) | ppo-F-map (2M) | "
        "Δ copi-predictive − ppo-F-map | better | copi-predictive (1/100), validation | "
        "ppo-F-map, validation: kept / at the end | ppo-F-map first reaches copi at |",
        "|---|---|---|---|---|---|---|---|---|---|",
        *alone,
        "",
        f"copi-predictive at 1/100 ahead of ppo-F-map (interval above 0) in {ahead_alone} of "
        "5 families. The last three columns: success on each PPO run's own validation "
        "episodes (seed 1, 60 of its family; the policy kept, and shipped, is the curve's "
        "best point, which flatters it, as the best of twenty noisy points), and the first "
        "point of its learning curve (every 100k steps) at or above copi's there.",
        "",
        "A new world for both: `ppo-star-map` (the second peer trained in star worlds "
        "only, 2M steps) beside copi-predictive at 1/100 (star worlds only too) in the other "
        "families, learnt alone:",
        "",
        "| family | copi-predictive (1/100, star only) | ppo-star-map (2M, star only) | "
        "ppo-F-map (2M, in family) | Δ copi-predictive − ppo-star-map | better |",
        "|---|---|---|---|---|---|",
        *new_world,
        "",
        f"copi-predictive at 1/100 ahead of ppo-star-map (interval above 0) in {ahead_new} "
        "of the 4 other families.",
        "",
        "Guarded (compass-guard's hand-written guard filters both):",
        "",
        "| family | compass-guard (the guard alone) | copi-learnt (1/100) | ppo-guard-F-map (2M) "
        "| Δ copi-learnt − ppo-guard-F-map | better |",
        "|---|---|---|---|---|---|",
        *guarded,
        "",
        f"copi-learnt at 1/100 ahead of ppo-guard-F-map (interval above 0) in {ahead_guard} "
        "of 5 families.",
        "",
        f"![learning cost, like with like]({figure_path.name})",
        "",
    ]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bench", default="results/rl-lean")
    ap.add_argument("--episodes", type=int, default=200)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="docs/rl.md")
    a = ap.parse_args()
    out = Path(a.out)
    lines = lean_like_lines(Path(a.bench), a.episodes, a.workers,
                            out.parent / "rl-lean-like.png")  # fmt: skip
    splice_section(out, SECTION, lines, before=NEXT)
    print("\n".join(lines))
    print(f"wrote {out}")


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
