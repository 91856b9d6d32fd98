"""Simple behaviours of the navigation agent that need no learning."""

from __future__ import annotations

import math

import numpy as np

from copi._rng import Seed, as_generator
from copi._validation import FloatArray

__all__ = ["RandomWalk"]


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
