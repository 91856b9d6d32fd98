"""How far the reading's information goes in crowds: copi-learnt's safety network against
the model-oracle's own check of a move, judged on the states copi-learnt visits, and
copi's choice with either in its hands.

    python studies/safety_information.py --caps CAPS --episodes 200 \\
        --out results/safety-information.json

1. **Visited states.** copi-learnt (capabilities ``--caps``; ``--alpha``, ``--guard``)
   drives ``--episodes`` crowd episodes of seed ``--visit-seed`` (never reported) at
   level map. At each decision, every compass direction is probed with the ``escape``
   label on the episode's own future (:func:`copi.learning.probe_actions`), and
   given the oracle's probability of that label: the share of ``--futures`` futures,
   drawn from the true present with the true motion model (the simulator forked, its
   random generator reseeded), in which the direction's probe is safe. Printed: the
   held-out AUC of the network's P(safe) and of the oracle's probability against the
   labels. With ``--decompose``, the oracle's probability again with less knowledge
   (the same futures): only the discs some ray sees (``visible``), their headings
   unknown (drawn uniformly: ``no headings``), their headings known to within one
   step's turn (the true heading plus a draw of the walk's turn: ``headings within a
   turn``).
2. **Choice.** One choice rule (copi-learnt's scoring, simplified: cos(d, aim) + alpha
   log P over the guard's admitted directions, the most probably safe direction when
   the guard admits none) with P from the network or from the oracle's futures, on the
   validation crowd episodes (seed 1): what the network's errors cost.

Runs episodes in ``--workers`` processes; every future is seeded by (episode, step,
future), so the numbers do not depend on the worker count.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

_CAPS: dict[str, Any] = {}


def _setup(caps_path: str) -> Any:
    from copi.learning import Capabilities

    if caps_path not in _CAPS:
        _CAPS[caps_path] = Capabilities.load(caps_path)
    return _CAPS[caps_path]


def _moves() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    a = 2 * np.pi * np.arange(16) / 16
    unit = np.ascontiguousarray(np.column_stack([np.cos(a), np.sin(a)]))
    actions = np.vstack([unit, np.zeros((1, 2))])
    seconds = np.ascontiguousarray(np.vstack([unit, 0.5 * unit, np.zeros((1, 2))]))
    return unit, actions, seconds


KNOWLEDGE = ("visible", "no headings", "headings within a turn")
"""The oracle's knowledge taken apart (``--decompose``; see the module's docstring)."""


def _oracle_p(
    sim: Any, key: tuple[int, int], futures: int, keep: np.ndarray | None = None,
    headings: str = "true",
) -> np.ndarray:
    """Each action's share of ``futures`` futures (drawn from ``sim``'s present with the
    true motion model) in which its escape probe is safe; with ``keep``, only those
    discs, and their headings the true ones (``"true"``), unknown (``"none"``: drawn
    uniformly) or known to within one step's turn (``"turn"``)."""
    from copi.learning import fork_simulator, probe_actions

    _, actions, seconds = _moves()
    acc = np.zeros(len(actions))
    for j in range(futures):
        f = fork_simulator(sim)
        if keep is not None:
            f.centers = f.centers[keep].copy()
            f.radii = np.ascontiguousarray(f.radii[keep])
            f.headings = f.headings[keep].copy()
        f.rng = np.random.default_rng([*key, j])
        if headings == "none":
            f.headings = f.rng.uniform(0, 2 * np.pi, len(f.radii))
        elif headings == "turn":
            f.headings = f.headings + f.rng.normal(0, sim.turn_sd, len(f.radii))
        acc += probe_actions(f, actions, 3, "escape", seconds)
    return acc / futures


def _visible(sim: Any) -> np.ndarray:
    """Which discs some ray of the agent's reading sees (the reading changes without it)."""
    base = sim.sensor.scan(sim.world, sim.position, sim.centers, sim.radii)
    seen = np.zeros(len(sim.radii), dtype=bool)
    for d in range(len(sim.radii)):
        m = np.arange(len(sim.radii)) != d
        seen[d] = not np.array_equal(
            base, sim.sensor.scan(sim.world, sim.position, sim.centers[m], sim.radii[m])
        )
    return seen


def _visit(args: tuple[str, int, int, float, float, int, bool]) -> dict[str, Any]:
    """copi-learnt through one episode, each decision's state probed."""
    from copi.learning import probe_actions
    from copi.methods import make_agent
    from copi.runs import draw_episode, run_episode

    caps_path, k, seed, alpha, guard, futures, decompose = args
    caps = _setup(caps_path)
    sim = draw_episode("crowd", k, seed)
    agent = make_agent("copi-learnt", caps, alpha=alpha, guard=guard)
    _, actions, seconds = _moves()
    rows: dict[str, list[Any]] = {"s": [], "static": [], "label": [], "oracle": []}
    rows.update({name: [] for name in KNOWLEDGE})
    act = agent.act

    def probing(obs: Any) -> Any:
        rows["s"].append(obs.ranges.copy())
        rows["static"].append(obs.static.copy())
        rows["label"].append(probe_actions(sim, actions, 3, "escape", seconds))
        key = (k, len(rows["s"]))
        rows["oracle"].append(_oracle_p(sim, key, futures))
        if decompose:
            seen = _visible(sim)
            for name, headings in zip(KNOWLEDGE, ("true", "none", "turn"), strict=True):
                rows[name].append(_oracle_p(sim, key, futures, seen, headings))
        return act(obs)

    agent.act = probing  # type: ignore[method-assign]
    run_episode(agent, sim, sensing="map", max_steps=1000)
    return {key: np.array(v) for key, v in rows.items()}


def _choose(args: tuple[str, int, int, str, float, float, int]) -> bool:
    """One validation episode with the simplified rule, P from ``source``."""
    from copi.learning.kernels import safety_probabilities
    from copi.methods import make_agent
    from copi.online import kernels
    from copi.runs import draw_episode, run_episode

    caps_path, k, seed, source, alpha, guard, futures = args
    caps = _setup(caps_path)
    sim = draw_episode("crowd", k, seed)
    agent = make_agent("copi-learnt", caps, alpha=alpha, guard=guard)
    unit, _, _ = _moves()
    state: dict[str, Any] = {"prev": None, "t": 0}

    def act(obs: Any) -> np.ndarray:
        desired, reach = agent.steering.aim(obs, -1)
        obs = agent.steering.observe(obs)
        s = np.asarray(obs.ranges, dtype=np.float64)
        prev = s if state["prev"] is None else state["prev"]
        state["prev"] = s.copy()
        state["t"] += 1
        if source == "oracle":
            p = _oracle_p(sim, (k, state["t"]), futures)
        else:
            p = np.empty(17)
            seen = obs.static if agent.model.static_aware else np.full(len(s), np.inf)
            safety_probabilities(s, prev, seen, agent._net, 16, np.empty(8 * len(s)), p)
        norm = math.hypot(desired[0], desired[1])
        if norm == 0.0:
            return np.zeros(2)
        ok = np.zeros(16, dtype=np.bool_)
        kernels.guard_verdicts(s, obs.static, unit, desired[0], desired[1], reach, guard,
                                agent._cos, agent._sin, agent.max_range, ok)  # fmt: skip
        along = unit @ (np.asarray(desired) / norm)
        score = along + alpha * np.log(np.maximum(p[:16], 1e-9))
        d = int(np.argmax(np.where(ok, score, -np.inf))) if ok.any() else int(np.argmax(p[:16]))
        full = not math.isfinite(reach) or reach >= 1.0
        return unit[d] * (1.0 if full else max(along[d] * reach, 0.5 * reach))

    agent.act = act  # type: ignore[method-assign]
    return run_episode(agent, sim, sensing="map", max_steps=1000).outcome == "success"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--caps", required=True, help="capabilities of the learnt preset")
    ap.add_argument("--episodes", type=int, default=200)
    ap.add_argument("--visit-seed", type=int, default=5)
    ap.add_argument("--seed", type=int, default=1, help="the choice's episodes (validation)")
    ap.add_argument("--alpha", type=float, default=10.0)
    ap.add_argument("--guard", type=float, default=1.05)
    ap.add_argument("--futures", type=int, default=32)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--decompose", action="store_true",
                    help="the oracle's probability again with less knowledge")
    ap.add_argument("--skip-choice", action="store_true", help="the visited states only")
    ap.add_argument("--out", type=Path, default=None)
    a = ap.parse_args(argv)
    from sklearn.metrics import roc_auc_score

    from copi.learning import Probes, design_matrix, predict

    caps = _setup(a.caps)
    result: dict[str, Any] = {"caps": str(a.caps), "episodes": a.episodes,
                              "alpha": a.alpha, "guard": a.guard, "futures": a.futures}  # fmt: skip
    t0 = time.perf_counter()
    with ProcessPoolExecutor(a.workers) as ex:
        visits = list(ex.map(_visit, [(a.caps, k, a.visit_seed, a.alpha, a.guard, a.futures,
                                       a.decompose) for k in range(a.episodes)]))  # fmt: skip
    s = np.concatenate([v["s"] for v in visits])
    prev = np.concatenate([np.vstack([v["s"][:1], v["s"][:-1]]) for v in visits])
    static = np.concatenate([v["static"] for v in visits])
    label = np.concatenate([v["label"] for v in visits])
    oracle = np.concatenate([v["oracle"] for v in visits])
    seen = static if caps.safety.static_aware else np.full(s.shape, np.inf)
    x, y, _, _ = design_matrix(Probes(s, prev, label, seen), 16)
    both = 0 < y.sum() < len(y)  # an AUC needs safe and unsafe probes
    net_auc = float(roc_auc_score(y, predict(caps.safety.net[0], x))) if both else None
    oracle_auc = (
        float(roc_auc_score(label[:, :16].ravel(), oracle[:, :16].ravel())) if both else None
    )
    result.update(states=len(s), safe_share=float(label[:, :16].mean()),
                  network_auc=net_auc, oracle_auc=oracle_auc,
                  visit_seconds=time.perf_counter() - t0)  # fmt: skip
    print(f"{len(s)} visited states (crowd, seed {a.visit_seed}), safe share "
          f"{label[:, :16].mean():.3f}: AUC network {net_auc}, oracle {oracle_auc}")
    if a.decompose:
        for name in KNOWLEDGE:
            p = np.concatenate([v[name] for v in visits])
            auc = float(roc_auc_score(label[:, :16].ravel(), p[:, :16].ravel())) if both else None
            result[f"oracle_auc_{name.replace(' ', '_')}"] = auc
            print(f"  oracle, {name}: AUC {auc}")
    for guard in () if a.skip_choice else (a.guard, 0.0):
        for source in ("network", "oracle"):
            with ProcessPoolExecutor(a.workers) as ex:
                ok = list(ex.map(_choose, [(a.caps, k, a.seed, source, a.alpha, guard, a.futures)
                                           for k in range(a.episodes)]))  # fmt: skip
            result[f"successes_{source}_guard_{guard:g}"] = int(sum(ok))
            print(f"choice with P from the {source}, guard {guard:g}: {sum(ok)} of "
                  f"{a.episodes} crowd episodes (seed {a.seed})", flush=True)
    if a.out is not None:
        a.out.parent.mkdir(parents=True, exist_ok=True)
        a.out.write_text(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
