"""A third-party package that extends copi with a method and a world family, the way a
user's own package would: one Agent class and one ``register_method`` call, one sampler
and one ``register_family`` call, and an entry point naming ``register`` in each of the
groups ``copi.methods`` and ``copi.families`` (see the ``.dist-info`` beside this
package; an installed package declares them in its ``pyproject.toml``)."""

from __future__ import annotations

import math

import numpy as np

from copi.core import Agent, Observation, Task
from copi.methods import register_method
from copi.world import ObstacleSpec, World, register_family


class Sidestep(Agent):
    """Follow the level's global direction; when the ray along it is short, step to the
    freer side. Level ``sensor`` (at ``map`` the direction follows the static route);
    hand-written, nothing learnt."""

    name = "sidestep"
    sensing = "sensor"

    def __init__(self, *, clearance: float = 1.5) -> None:
        self.clearance = float(clearance)

    def reset(self, task: Task) -> None:
        self.n = task.n_rays

    def act(self, obs: Observation) -> np.ndarray:
        u = np.asarray(obs.direction, dtype=np.float64)  # a unit vector, world axes
        if not u.any():
            return np.zeros(2)
        i = round(math.atan2(u[1], u[0]) / (2 * math.pi) * self.n) % self.n  # its ray
        if obs.ranges[i] < self.clearance:
            left, right = obs.ranges[(i + self.n // 4) % self.n], obs.ranges[i - self.n // 4]
            u = np.array([-u[1], u[0]]) if left >= right else np.array([u[1], -u[0]])
        return u * min(1.0, obs.reach)  # no farther than the point aimed at


def two_rooms(rng: np.random.Generator, *, name: str | None = None) -> World:
    """Two rooms joined by a door in a wall at a random height, a few slow discs."""
    w, h = float(rng.uniform(24, 32)), float(rng.uniform(14, 20))
    door = float(rng.uniform(3, h - 5))
    x = w / 2
    wall = [[x - 0.5, 0.5], [x + 0.5, 0.5], [x + 0.5, door], [x - 0.5, door]]
    top = [[x - 0.5, door + 2.5], [x + 0.5, door + 2.5], [x + 0.5, h - 0.5], [x - 0.5, h - 0.5]]
    return World(
        np.array([[0, 0], [w, 0], [w, h], [0, h]]), (np.array(wall), np.array(top)),
        name=name or "two-rooms", obstacles=ObstacleSpec(count=(3, 5), speed=0.4),
    )  # fmt: skip


def register() -> None:
    """What the entry points call."""
    register_method("sidestep", Sidestep, summary="follow the global direction, step aside "
                    "from a short ray (an example plugin; hand-written)")  # fmt: skip
    register_family("two-rooms", two_rooms, summary="two rooms and a door (an example plugin)")
