"""Simple behaviours of the navigation agent that need no learning."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from copi._rng import Seed, as_generator
from copi._validation import FloatArray
from copi.world._simulator import Simulator
from copi.world._world import World

__all__ = ["RandomWalk", "random_walk_episodes"]


class RandomWalk:
    """A correlated random walk at constant speed: the exploratory motion of the paper's
    training phase (§IV, "the agent moved randomly about 100 environments").

    Each call turns the heading by N(0, turn_sd) radians and returns the velocity. When
    the agent was blocked by a wall on the last step, a fresh uniform heading is drawn, so
    the walk does not stay pressed against a wall.

    Examples
    --------
    >>> walk = RandomWalk(seed=0)
    >>> v = walk()
    >>> round(float(np.hypot(*v)), 6)
    1.0
    """

    def __init__(self, *, speed: float = 1.0, turn_sd: float = 0.5, seed: Seed = None) -> None:
        self.speed = float(speed)
        self.turn_sd = float(turn_sd)
        self.rng = as_generator(seed)
        self.heading = float(self.rng.uniform(0, 2 * math.pi))

    def __call__(self, blocked: bool = False) -> FloatArray:
        if blocked:
            self.heading = float(self.rng.uniform(0, 2 * math.pi))
        else:
            self.heading += float(self.rng.normal(0.0, self.turn_sd))
        return np.array([math.cos(self.heading), math.sin(self.heading)]) * self.speed


def random_walk_episodes(
    worlds: Sequence[World],
    *,
    seed: int = 0,
    steps: int = 150,
    progress: Callable[[int], None] | None = None,
) -> list[Simulator]:
    """Run a random-walk agent for ``steps`` steps in each world, recording everything.

    Episode k draws its task, obstacles and walk from ``default_rng([seed, k])``
    (docs/design.md, "Seeds"), so each episode is the same whichever others are run. The walk
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
