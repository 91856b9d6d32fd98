"""Train every deep-RL policy copi reports, two at a time (one per core), resumably.

    python studies/rl_train_all.py --steps 2000000 --seeds 0 --out results/rl --install
    python studies/rl_train_all.py --peer first --steps 2000000 --seeds 0 --install
    python studies/rl_train_all.py --peer sac --only star-map,crowd-map --steps 1000000 \
        --seeds 0 --install
    python studies/rl_train_all.py --peer il --steps 1000000 --seeds 0 --install
    python studies/rl_train_all.py --peer clone --seeds 0 --install
    python studies/rl_train_all.py --peer curriculum --seeds 0 --install

Two peers. The second (the default, ``--peer second``): one policy per family at level
``map``, seeing what that level gives (``copi-local-v3``: the hits the static map does
not explain, three readings stacked, its own velocity) with ``copi rl train``'s defaults,
the setting chosen by ``--tune`` (the settings of :data:`TUNING_SECOND` on star at map,
400k steps, validation seed 1). The first (``--peer first``): ``copi-local-v2`` (the
ranges and their change, the same at every level) on a mix of sensor and map episodes;
configurations ``mix`` (all five families), one per family and ``chauffeur`` (the game's
evader), with :data:`TUNING`'s ``lr1e-3``.

The third (``--peer sac``): the second's observation and reward, learnt by SAC
(:data:`SAC`), policies ``sac-F-map``. The fourth (``--peer il``): the second's, warm-started
by imitating compass-guard (:data:`IMITATION`), policies ``ppo-il-F-map``. The fifth
(``--peer clone``): no RL, a classifier of compass-guard's moves (:data:`CLONE`), policies
``clone-F-map``. The sixth (``--peer curriculum``): the second's, its episodes growing
from static worlds to crowds (:data:`CURRICULUM`).

Each run is ``copi rl train`` with checkpoints, so an interrupted script resumes. The
seed-0 policies are then copied into ``src/copi/data/rl`` by ``--install``, the other
seeds' into ``src/copi/data/rl/seeds``.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

FAMILIES = ("star", "polygon", "indoor", "maps", "crowd")
CONFIGS: dict[str, list[str]] = {
    "mix": ["--families", ",".join(FAMILIES)],
    **{f: ["--families", f] for f in FAMILIES},
    "chauffeur": ["--task", "chauffeur"],
}
TUNING = {
    "noisy": ["--log-std", "0"],
    "base": ["--log-std", "-1"],
    "calm": ["--log-std", "-2"],
    "lr1e-3": ["--log-std", "-1", "--lr", "1e-3"],
    "wide": ["--log-std", "-1", "--net", "128,128"],
}
"""The settings tried on the mix (``--tune``; every learning curve is success on fixed
episodes of validation seed 1): SB3's default exploration noise (noisy, log std 0), less
(base, -1; calm, -2), and with base's noise a larger learning rate or wider layers."""
FIRST = ["--observation", "copi-local-v2", "--levels", "sensor,map", "--frames", "2",
         "--proximity", "0", "--ent", "0", "--net", "64,64", "--n-steps", "256",
         "--batch-size", "256", "--raw-reward"]
"""The first peer's settings apart from :data:`TUNING`'s (its defaults when it was
trained)."""
SECOND = {**{f"{f}-{lv}": ["--families", f, "--levels", lv] for lv in ("map", "sensor")
             for f in FAMILIES},
          "chauffeur-sensor": ["--task", "chauffeur", "--levels", "sensor"]}
"""The second peer's configurations: one policy per family and level (``F-map``, and
``F-sensor``: the level that gives no static reading), and the chauffeur's evader at the
game's level (``chauffeur-sensor``)."""
TUNING_SECOND = {
    "default": [],
    "raw-reward": ["--raw-reward"],
    "no-proximity": ["--proximity", "0"],
    "frames-2": ["--frames", "2"],
    "frames-5": ["--frames", "5"],
    "contact-30": ["--contact", "30"],
    "wide": ["--net", "256,256"],
    "first-peer": ["--lr", "1e-3", "--log-std", "-1", "--ent", "0", "--net", "64,64",
                   "--n-steps", "256", "--batch-size", "256", "--proximity", "0",
                   "--raw-reward"],
}
"""The settings tried for the second peer on star at map (``--tune``): copi rl train's
defaults (lr 3e-4, 8 envs x 512 steps, batches of 512, entropy 0.005, log std -0.5,
128-128 tanh layers, 3 readings, proximity penalty 0.5, contact 10, the reward scaled by
its running spread), then one change each: the raw reward, no proximity penalty, 2 or 5
readings, a contact cost of 30, wider layers, and the first peer's settings."""
IMITATION = {f"il-{f}-map": ["--families", f, "--levels", "map", "--imitate", "compass-guard"]
             for f in FAMILIES}
"""The imitation warm start (``--peer il``): the second peer's training from a clone of
compass-guard (the hand-written method of the same level, DAgger's two rounds after its
2,000 episodes), then PPO with copi rl train's defaults; policies ``ppo-il-F-map``. The
network decides alone: nothing hand-written runs beside it."""
CLONE = {f"{f}-map": ["--algo", "clone", "--imitate", "compass-guard", "--families", f,
                      "--levels", "map", "--episodes-per-family", "50000", "--net", "256,256"]
         for f in FAMILIES}  # fmt: skip
"""The clone (``--peer clone``): compass-guard's moves at map classified (a step along
each ray of the frame, or none), its 2,000 episodes then DAgger's two rounds, from a
family's pool of 50,000 training episodes (from the pool of 1,000 PPO trains on, the clone
remembered its episodes: docs/rl.md), 256-256 tanh layers; policies ``clone-F-map``.
No RL steps and no checkpoints (minutes a family)."""
CURRICULUM = {
    "cur-crowd-map": ["--families", "crowd", "--levels", "map",
                      "--curriculum", "star:400000,polygon:1000000"],
    "curp-crowd-map": ["--families", "crowd", "--levels", "map",
                       "--curriculum", "polygon:1000000"],
}
"""The curriculum (``--peer curriculum``): the second peer's training in crowds (copi rl
train's defaults, 2M steps) whose episodes start in easier worlds: star worlds (an open
star-shaped room, 10 to 15 discs at 0.6) to 400k steps, polygon worlds (polygonal
obstacles, the same discs) to 1M, then crowds (the polygon worlds with 25 to 40 discs at
0.8); or polygon worlds alone to 1M. The one of higher validation success (seed 1, the
mean of the curve's last three points: 21.1 against 17.2 %) is the method
``ppo-cur-crowd-map`` (:data:`CURRICULUM_KEPT`)."""
CURRICULUM_KEPT = ["cur-crowd-map"]
SAC = ["--algo", "sac", "--batch-size", "256"]
"""The SAC peer's settings beside copi rl train's defaults (8 environments, one gradient
step after each step of them, a buffer of 100k transitions, 10k random steps first):
SB3's batch of 256."""
SHIPPED = Path(__file__).resolve().parents[1] / "src" / "copi" / "data" / "rl"
DOCS = Path(__file__).resolve().parents[1] / "docs"


def _run(name: str, args: list[str], out: Path, steps: int) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    policy = out / f"{name}.npz"
    if policy.is_file() and (out / f"{name}.json").is_file():
        return json.loads((out / f"{name}.json").read_text())
    rl = [] if "clone" in args else ["--steps", str(steps), "--checkpoints",
                                      str(out / f"{name}.ckpt")]  # fmt: skip
    cmd = [sys.executable, "-m", "copi", "rl", "train", "-o", str(policy), *rl, *args]
    t0 = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{name}: {done.stderr.strip().splitlines()[-1:]}")
    print(f"{name}: {time.perf_counter() - t0:.0f} s; {done.stdout.strip()}", flush=True)
    return json.loads((out / f"{name}.json").read_text())


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=2_000_000)
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--out", default="results/rl")
    ap.add_argument("--only", default=None, help="comma-separated configurations")
    ap.add_argument("--tune", action="store_true", help="the settings (seed 0)")
    ap.add_argument("--peer", choices=("first", "second", "sac", "il", "clone", "curriculum"),
                    default="second")  # fmt: skip
    # chosen by --tune (400k steps on the mix, validation seed 1: the highest mean of the
    # last three points of the learning curve; docs/rl.md has the table)
    ap.add_argument("--setting", default="lr1e-3", help="the setting of every run")
    ap.add_argument("--install", action="store_true", help="ship the seed-0 policies")
    ap.add_argument("--parallel", type=int, default=2)
    a = ap.parse_args()
    out = Path(a.out)
    jobs: list[tuple[str, list[str]]] = []
    second = a.peer == "second"
    if a.tune and a.peer == "sac":
        ap.error("--tune tries PPO's settings (--peer first or second); SAC is not tuned")
    if a.tune and second:
        jobs = [(f"tune2-{k}", [*SECOND["star-map"], *v, "--seed", "0",
                                "--validation-episodes", "100"])
                for k, v in TUNING_SECOND.items()
                if not a.only or k in a.only.split(",")]  # fmt: skip
    elif a.tune:
        jobs = [(f"tune-{k}", [*CONFIGS["mix"], *FIRST, *v, "--seed", "0"])
                for k, v in TUNING.items()]  # fmt: skip
    elif a.peer == "il":
        names = a.only.split(",") if a.only else list(IMITATION)
        jobs = [(f"ppo-{name}-s{seed}", [*IMITATION[name], "--seed", seed])
                for seed in a.seeds.split(",") for name in names]  # fmt: skip
    elif a.peer == "curriculum":
        names = a.only.split(",") if a.only else list(CURRICULUM)
        jobs = [(f"ppo-{name}-s{seed}", [*CURRICULUM[name], "--seed", seed])
                for seed in a.seeds.split(",") for name in names]  # fmt: skip
    elif a.peer == "clone":
        names = a.only.split(",") if a.only else list(CLONE)
        jobs = [(f"clone-{name}-s{seed}", [*CLONE[name], "--seed", seed])
                for seed in a.seeds.split(",") for name in names]  # fmt: skip
    elif second or a.peer == "sac":
        # SAC was trained for navigation only (its configurations named with --only)
        names = a.only.split(",") if a.only else [n for n in SECOND
                                                  if second or not n.startswith("chauffeur")]
        algo, extra = ("ppo", []) if second else ("sac", SAC)
        jobs = [(f"{algo}-{name}-s{seed}", [*SECOND[name], *extra, "--seed", seed])
                for seed in a.seeds.split(",") for name in names]  # fmt: skip
    else:
        names = a.only.split(",") if a.only else list(CONFIGS)
        for seed in a.seeds.split(","):
            for name in names:
                jobs.append((f"ppo-{name}-s{seed}",
                             [*CONFIGS[name], *FIRST, *TUNING[a.setting], "--seed",
                              seed]))  # fmt: skip
    with ThreadPoolExecutor(a.parallel) as pool:
        results = dict(zip([n for n, _ in jobs],
                           pool.map(lambda j: _run(j[0], j[1], out, a.steps), jobs),
                           strict=True))  # fmt: skip
    for name, r in results.items():
        last = r["curve"][-1]
        print(f"{name}: {r['steps']:,} steps, {r['seconds']:.0f} s ({r['steps_per_second']:,.0f}"
              f"/s), validation success {100 * last['success']:.1f} %")
    if a.install:
        configs = {"first": list(CONFIGS), "il": list(IMITATION), "clone": list(CLONE),
                   "curriculum": CURRICULUM_KEPT}.get(a.peer, list(SECOND))  # fmt: skip
        _install(out, configs, {"sac": "sac", "clone": "clone"}.get(a.peer, "ppo"))


def _install(out: Path, configs: list[str], algo: str = "ppo") -> None:
    """Ship the seed-0 policies, their commands told as run from the repository with
    ``--out results/rl`` (the directory of this machine's run is nobody else's)."""
    from copi.baselines import load_policy, save_policy

    SHIPPED.mkdir(parents=True, exist_ok=True)
    prefix = str(out).rstrip("/") + "/"
    for name in configs:
        src = out / f"{algo}-{name}-s0.npz"
        if not src.is_file():
            continue
        policy = load_policy(src)
        policy.info["command"] = policy.info.get("command", "").replace(prefix, "results/rl/")
        if policy.info.get("algorithm") == "sac":  # before its name was kept over the config's
            policy.info["algorithm"] = "SAC (Stable-Baselines3)"
        save_policy(policy, SHIPPED / f"{algo}-{name}.npz")
        summary = json.loads((out / f"{algo}-{name}-s0.json").read_text())
        summary["command"] = summary.get("command", "").replace(prefix, "results/rl/")
        (SHIPPED / f"{algo}-{name}.json").write_text(json.dumps(summary, indent=1) + "\n")
        figure = f"rl-curve-{name}.png" if algo == "ppo" else f"rl-curve-{algo}-{name}.png"
        shutil.copy(out / f"{algo}-{name}-s0.png", DOCS / figure)
    # the other seeds' policies: the spread over training seeds (rl_experiments)
    (SHIPPED / "seeds").mkdir(exist_ok=True)
    for src in sorted(out.glob(f"{algo}-*-s*.npz")):
        name, seed = src.stem.removeprefix(f"{algo}-").rsplit("-s", 1)
        if seed == "0" or name not in configs or not (out / f"{src.stem}.json").is_file():
            continue
        policy = load_policy(src)
        policy.info["command"] = policy.info.get("command", "").replace(prefix, "results/rl/")
        save_policy(policy, SHIPPED / "seeds" / src.name)
    print(f"installed into {SHIPPED}")


if __name__ == "__main__":
    main()
