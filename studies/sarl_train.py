"""Train SARL, CrowdNav's crowd-navigation peer, on copi's episodes (docs/rl.md).

``python studies/sarl_train.py --out results/sarl [--rl-episodes N] [--seed S]``: imitation
of the reference planner at level oracle on training episodes (seed 2), then CrowdNav's
reinforcement learning; the network that did best on validation episodes (seed 1) is
written to OUT/sarl-crowd.npz, its learning curve to OUT/sarl-crowd.json. ``--install``
copies the weights where copi ships them (method ``sarl``).
"""

from __future__ import annotations

import argparse
import shutil
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from copi.baselines import SARL_SHIPPED as SHIPPED  # noqa: E402
from copi.rl import SARLConfig, train_sarl, write_sarl  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/sarl")
    ap.add_argument("--family", default="crowd")
    ap.add_argument("--demonstrator", default="model-oracle")
    ap.add_argument("--demo-episodes", type=int, default=300)
    ap.add_argument("--il-epochs", type=int, default=50)
    ap.add_argument("--rl-episodes", type=int, default=1000)
    ap.add_argument("--epsilon", default="0.5,0.1,400", help="first, last, episodes")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--install", action="store_true")
    args = ap.parse_args(argv)
    e0, e1, span = args.epsilon.split(",")
    config = SARLConfig(family=args.family, demonstrator=args.demonstrator,
                        demo_episodes=args.demo_episodes,
                        il_epochs=args.il_epochs, rl_episodes=args.rl_episodes,
                        epsilon=(float(e0), float(e1), int(span)), seed=args.seed)  # fmt: skip
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    name = f"sarl-{args.family}" + (f"-s{args.seed}" if args.seed else "")
    t0 = time.perf_counter()
    demos = out / f"demos-{args.family}-{args.demonstrator}-{args.demo_episodes}.npz"
    weights, curve = train_sarl(config, log=lambda s: print(s, flush=True), demos=demos)
    weights.info["command"] = "python studies/sarl_train.py " + " ".join(sys.argv[1:])
    path = write_sarl(weights, curve, out / f"{name}.npz")
    print(f"{path} ({time.perf_counter() - t0:.0f} s; best validation "
          f"{weights.info['validation']:.1%})")
    if args.install:
        SHIPPED.mkdir(exist_ok=True)
        shutil.copy(path, SHIPPED / path.name)
        shutil.copy(out / f"{name}.json", SHIPPED / f"{name}.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
