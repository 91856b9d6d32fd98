"""What the baselines share: hit points of a reading, and the steered base class."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.core import Agent, Observation, Sensing, Task
from copi.geometry import ring_angles
from copi.online import Steering

__all__ = ["Steered", "hit_points", "segment_distance", "unit"]


def unit(v: NDArray[np.float64]) -> tuple[NDArray[np.float64], float]:
    """(v / |v|, |v|); the zero vector stays zero."""
    n = math.hypot(v[0], v[1])
    return (v / n if n > 0 else np.zeros(2)), n


def hit_points(
    ranges: NDArray[np.float64],
    cos: NDArray[np.float64],
    sin: NDArray[np.float64],
    max_range: float,
) -> NDArray[np.float64]:
    """The points the rays hit (those shorter than the range), relative to the agent, (h, 2)."""
    hit = ranges < max_range
    return np.column_stack([ranges[hit] * cos[hit], ranges[hit] * sin[hit]])


def segment_distance(
    points: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Least distance from ``points`` (h, 2) to each segment a[i] -> b[i], shape (k,);
    inf when there are no points.

    Examples
    --------
    >>> segment_distance(np.array([[1.0, 1.0]]), np.zeros((1, 2)), np.array([[2.0, 0.0]]))
    array([1.])
    """
    if not len(points):
        return np.full(len(a), np.inf)
    seg = b - a
    L2 = (seg * seg).sum(1)
    rel = points[:, None, :] - a[None, :, :]
    t = np.clip((rel * seg[None]).sum(-1) / np.where(L2 > 0, L2, 1.0)[None, :], 0.0, 1.0)
    near = a[None, :, :] + t[..., None] * seg[None, :, :]
    return np.sqrt(((points[:, None, :] - near) ** 2).sum(-1)).min(0)


class Steered(Agent):
    """A local method driven by :class:`Steering` (the route at ``map``, the goal at
    ``sensor``): subclasses turn (observation, desired direction, reach) into a velocity."""

    name = "steered"
    sensing: Sensing = "sensor"
    steers_itself = True  # its own Steering: the same direction the runner would hand it
    explain = False
    """Keep each decision's candidates and their scores in :attr:`last_candidates`
    (``copi watch`` sets it; off, a decision costs nothing more)."""
    last_candidates: tuple[NDArray[np.float64], NDArray[np.float64], str] | None = None
    """(candidate velocities (k, 2), their scores (k,), what a score measures): higher is
    better, -inf a candidate the method refused; the last decision's, with ``explain``."""

    def _explained(self, candidates: Any, scores: Any, what: str) -> None:
        if self.explain:
            self.last_candidates = (np.array(candidates, dtype=np.float64).reshape(-1, 2),
                                    np.array(scores, dtype=np.float64).ravel(), what)  # fmt: skip

    def reset(self, task: Task) -> None:
        self.task = task
        if not hasattr(self, "steering"):  # kept: a lifelong run keeps its map
            self.steering = Steering()
        self.steering.reset(task)
        angles = ring_angles(task.n_rays)
        self.cos = np.cos(angles)
        self.sin = np.sin(angles)
        self.max_range = task.max_range
        self.radius = task.agent_radius

    def act(self, obs: Observation) -> NDArray[np.float64]:
        desired, reach = self.steering.aim(obs)
        obs = self.steering.observe(obs)
        self.last_direction = np.asarray(desired, dtype=np.float64)
        """The global direction of the last decision (copi watch shows it)."""
        return self.steer(obs, self.last_direction, float(reach))

    def steer(
        self, obs: Observation, desired: NDArray[np.float64], reach: float
    ) -> NDArray[np.float64]:
        raise NotImplementedError

    def finish(self, outcome: str) -> None:
        """The task ended (``outcome``): tells the global strategy."""
        self.steering.finish(outcome)
