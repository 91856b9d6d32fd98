"""The demonstration run before the paper's reproduction: random walks in random worlds."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from copi.world import RandomWalk, Simulator, World

__all__ = ["random_walk_episodes"]


def random_walk_episodes(
    worlds: Sequence[World],
    *,
    seed: int = 0,
    steps: int = 150,
    progress: Callable[[int], None] | None = None,
) -> list[Simulator]:
    """Run a random-walk agent for ``steps`` steps in each world, recording everything.

    Episode k draws its task, obstacles and walk from ``default_rng([seed, k])``
    (DESIGN.md, "Seeds"), so each episode is the same whichever others are run. The walk
    ignores contacts: the point is to show the world, its obstacles and the sensor.
    """
    sims = []
    for k, world in enumerate(worlds):
        rng = np.random.default_rng([seed, k])
        sim = Simulator.from_world(world, rng, record=True)
        walk = RandomWalk(seed=rng)
        blocked = False
        for _ in range(steps):
            blocked = sim.step(walk(blocked)).blocked
        sims.append(sim)
        if progress is not None:
            progress(k)
    return sims
