"""What a world family's tasks are like: line of sight, detour, free-space width."""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass

import numpy as np

from copi._rng import Seed, as_generator
from copi.errors import InvalidArgumentError
from copi.planning._cspace import shortest_path
from copi.world import World, in_sight, sample_start_goal, sample_world

__all__ = ["FamilyStats", "family_stats", "mean_free_width"]


@dataclass(frozen=True)
class FamilyStats:
    """Statistics of ``n`` tasks of a world family (see :func:`family_stats`)."""

    family: str
    """The family's name."""
    n: int
    """Number of tasks (one world each)."""
    seed: int
    """Task k used ``numpy.random.default_rng([seed, k])``."""
    sight_share: float
    """Share of tasks whose goal is in straight sight of the start: the straight segment
    is free for the agent's disc among the static walls (:func:`copi.world.in_sight`)."""
    detour_median: float
    """Median over tasks of optimal path length / straight-line distance (>= 1)."""
    detour_p10: float
    """10th percentile of the same ratio."""
    detour_p90: float
    """90th percentile of the same ratio."""
    mean_free_width: float
    """Mean over worlds of :func:`mean_free_width`, in agent steps."""
    ms_per_world: float
    """Median wall time of drawing one world, in milliseconds."""
    unreachable: int
    """Tasks whose goal the planner could not reach (0 for a sound family)."""


def mean_free_width(world: World, seed: Seed = None, *, points: int = 256) -> float:
    """Mean width of a world's free space, in agent steps: four times the mean clearance
    (distance to the nearest wall) of points drawn uniformly in the free space.

    The factor makes it exact for a long corridor: across a strip of width w, clearance
    is uniform on [0, w / 2], with mean w / 4. A round room of diameter D reads 2D / 3,
    a square room of side a reads 2a / 3.

    Examples
    --------
    >>> corridor = World([[0, 0], [400, 0], [400, 3], [0, 3]])
    >>> round(mean_free_width(corridor, 0, points=20000), 1)
    3.0
    """
    if int(points) != points or points < 1:
        raise InvalidArgumentError(f"points must be a positive int; got {points!r}")
    rng = as_generator(seed)
    xmin, ymin, xmax, ymax = world.bounds
    found: list[np.ndarray] = []
    total = 0
    while total < points:
        pts = rng.uniform([xmin, ymin], [xmax, ymax], size=(2 * points, 2))
        pts = pts[world.contains(pts)]
        found.append(pts)
        total += len(pts)
    sample = np.concatenate(found)[:points]
    return 4.0 * float(np.mean(world.clearance(sample)))


def family_stats(
    family: str,
    n: int = 200,
    seed: int = 0,
    *,
    agent_radius: float = 0.3,
    data_dir: str | os.PathLike[str] | None = None,
) -> FamilyStats:
    """Measure ``n`` tasks of a world family.

    Task k draws world k, ``sample_world(family, rng)``, then its start and goal,
    ``sample_start_goal(world, rng)``, from ``rng = numpy.random.default_rng([seed, k])``
    (the same start and goal :meth:`copi.world.Simulator.from_world` draws from that
    generator). The optimal path is :func:`shortest_path` among the static walls for a disc
    of ``agent_radius``.

    Examples
    --------
    >>> s = family_stats("star", n=5)
    >>> s.n, s.unreachable, s.detour_p10 >= 1.0
    (5, 0, True)
    """
    if int(n) != n or n < 1:
        raise InvalidArgumentError(f"n must be a positive int; got {n!r}")
    sight, detour, width, times = [], [], [], []
    unreachable = 0
    for k in range(int(n)):
        rng = np.random.default_rng([seed, k])
        t0 = time.perf_counter()
        world = sample_world(family, rng, data_dir=data_dir)
        times.append(time.perf_counter() - t0)
        start, goal = sample_start_goal(world, rng, radius=agent_radius)
        sight.append(in_sight(world, start, goal, radius=agent_radius))
        plan = shortest_path(world, start, goal, radius=agent_radius)
        if plan.found:
            detour.append(plan.length / math.hypot(*(goal - start)))
        else:
            unreachable += 1
        width.append(mean_free_width(world, rng))
    d = np.array(detour) if detour else np.array([math.nan])
    return FamilyStats(
        family=family,
        n=int(n),
        seed=int(seed),
        sight_share=float(np.mean(sight)),
        detour_median=float(np.median(d)),
        detour_p10=float(np.percentile(d, 10)),
        detour_p90=float(np.percentile(d, 90)),
        mean_free_width=float(np.mean(width)),
        ms_per_world=1000.0 * float(np.median(times)),
        unreachable=unreachable,
    )
