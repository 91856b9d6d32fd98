"""Speed of Experiment 2: homicidal-chauffeur games per second (one process)."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from benchmarks._timing import note
from copi.experiments.pursuit import PursuitConfig, run_game
from copi.learning import LearnParams, learn


def main() -> bool:
    tmp = Path(tempfile.mkdtemp())
    caps = learn(LearnParams(directions=16)).save(tmp / "caps.npz")
    for evader in ("capability", "game"):
        cfg = PursuitConfig(str(caps), evader=evader, dynamic=True, games=40).resolved()
        run_game(cfg, 0)  # warm up
        t0 = time.perf_counter()
        rows = [run_game(cfg, k) for k in range(40)]
        wall = time.perf_counter() - t0
        steps = sum(r.survival for r in rows)
        note(
            f"{evader} evader, dynamic worlds: {len(rows) / wall:.1f} games/s, "
            f"{steps / wall:,.0f} game steps/s (one process)"
        )
    return True


if __name__ == "__main__":
    raise SystemExit(0 if main() else 1)
