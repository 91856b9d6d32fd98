"""Task-independent exploration: random walks through random worlds (paper §IV)."""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from multiprocessing import get_context

import numpy as np
from numpy.typing import NDArray

from copi._validation import positive_int
from copi.world import (
    RandomWalk,
    RangeSensor,
    Simulator,
    WorldParams,
    check_family,
    random_world,
    sample_world,
)

__all__ = ["Exploration", "explore"]


@dataclass(frozen=True)
class Exploration:
    """Sensor readings gathered by random exploration, in world order."""

    readings: NDArray[np.float64]
    """Ring-sensor readings after each step, shape (n_worlds * steps, n_rays)."""
    moves: NDArray[np.float64]
    """The displacement the agent made in the step that led to each reading, (n, 2)."""
    world: NDArray[np.int64]
    """Index of the world each reading comes from, shape (n,)."""

    @property
    def n_samples(self) -> int:
        return int(self.readings.shape[0])


def _explore_one(
    seed: int,
    k: int,
    steps: int,
    params: WorldParams,
    sensor: RangeSensor,
    agent_radius: float,
    family: str = "star",
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    rng = np.random.default_rng([seed, k])
    if family == "star":
        world = random_world(rng, params=params)
    else:
        world = sample_world(family, rng)
    sim = Simulator.from_world(world, rng, agent_radius=agent_radius, sensor=sensor)
    walk = RandomWalk(seed=rng)
    readings = np.empty((steps, sensor.n_rays))
    moves = np.empty((steps, 2))
    blocked = False
    for t in range(steps):
        before = sim.position.copy()
        blocked = sim.step(walk(blocked)).blocked
        readings[t] = sim.ranges
        moves[t] = sim.position - before
    return readings, moves


def explore(
    n_worlds: int = 100,
    steps: int = 300,
    *,
    seed: int = 0,
    workers: int = 1,
    params: WorldParams | None = None,
    sensor: RangeSensor | None = None,
    agent_radius: float = 0.3,
    family: str = "star",
    progress: Callable[[int], None] | None = None,
) -> Exploration:
    """Move an agent randomly about ``n_worlds`` random worlds for ``steps`` steps each,
    among moving obstacles, recording its sensor (the paper: 100 worlds x 300 steps).

    The worlds are the paper's (``family="star"``, drawn with ``params``) or any world
    family's (:func:`copi.world.sample_world`): capabilities to be used in rooms or grid
    maps are best learnt in such worlds, still without any task.

    World k draws everything from ``default_rng([seed, k])``, so the readings are the same
    whatever the number of ``workers`` (processes) and their order.

    Examples
    --------
    >>> ex = explore(2, 5, seed=1)
    >>> ex.readings.shape, ex.world.tolist()
    ((10, 32), [0, 0, 0, 0, 0, 1, 1, 1, 1, 1])
    """
    for name, value in (("n_worlds", n_worlds), ("steps", steps), ("workers", workers)):
        positive_int(value, name)
    params = params or WorldParams()
    sensor = sensor or RangeSensor()
    check_family(family)
    parts: list[tuple[NDArray[np.float64], NDArray[np.float64]]] = []
    if workers == 1:
        for k in range(n_worlds):
            parts.append(_explore_one(seed, k, steps, params, sensor, agent_radius, family))
            if progress is not None:
                progress(k)
    else:
        with ProcessPoolExecutor(workers, mp_context=get_context("spawn")) as pool:
            futures = [
                pool.submit(_explore_one, seed, k, steps, params, sensor, agent_radius, family)
                for k in range(n_worlds)
            ]
            for k, fut in enumerate(futures):
                parts.append(fut.result())
                if progress is not None:
                    progress(k)
    return Exploration(
        readings=np.concatenate([p[0] for p in parts]),
        moves=np.concatenate([p[1] for p in parts]),
        world=np.repeat(np.arange(n_worlds), steps),
    )
