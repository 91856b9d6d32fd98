"""The Dynamic Window Approach (Fox, Burgard & Thrun, 1997) for a holonomic disc:
velocity sampling scored on the range reading."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from copi.baselines._common import Steered, hit_points, unit
from copi.errors import InvalidArgumentError
from copi.online import Observation, Task

__all__ = ["DWA"]


class DWA(Steered):
    """Sample velocities (``headings`` directions plus the desired one, times four speeds,
    plus standing still); predict each as a straight motion over ``horizon`` steps; keep
    those whose swept disc stays ``margin`` clear of every hit point of the reading; take
    the best by progress towards the aim point + ``clearance_weight`` × clearance (capped
    at 3) / 3 + 0.1 × speed. With none admissible, the one with most clearance.

    Level ``sensor`` (every hit is an obstacle); hand-written; ``margin`` and
    ``clearance_weight`` are tuned. The agent's speed changes freely within a step, so the
    dynamic window is the whole disc of speeds up to 1.

    Parameters
    ----------
    margin : float
        Least clearance an admissible motion keeps, agent steps.
    clearance_weight : float
        Weight of clearance against progress.
    horizon : float
        Steps over which a motion is predicted.
    headings : int
        Sampled directions.
    """

    name = "dwa"

    def __init__(
        self,
        *,
        margin: float = 0.3,
        clearance_weight: float = 0.3,
        horizon: float = 2.0,
        headings: int = 32,
    ) -> None:
        for key, v in (("margin", margin), ("clearance_weight", clearance_weight)):
            if not (math.isfinite(v) and v >= 0):
                raise InvalidArgumentError(f"{key} must be a finite number >= 0; got {v!r}")
        if not (math.isfinite(horizon) and horizon >= 1):
            raise InvalidArgumentError(f"horizon must be a finite number >= 1; got {horizon!r}")
        self.margin = float(margin)
        self.clearance_weight = float(clearance_weight)
        self.horizon = float(horizon)
        a = 2 * np.pi * np.arange(int(headings)) / int(headings)
        self._dirs = np.column_stack([np.cos(a), np.sin(a)])
        self._speeds = np.array([0.25, 0.5, 0.75, 1.0])

    def reset(self, task: Task) -> None:
        super().reset(task)

    def steer(
        self, obs: Observation, desired: NDArray[np.float64], reach: float
    ) -> NDArray[np.float64]:
        u, _ = unit(desired)
        if not u.any():
            return np.zeros(2)
        aim = u * (reach if math.isfinite(reach) else self.max_range)
        dirs = np.vstack([self._dirs, u])
        vel = (dirs[:, None, :] * self._speeds[None, :, None]).reshape(-1, 2)
        vel = np.vstack([vel, np.zeros((1, 2))])
        pts = hit_points(np.asarray(obs.ranges, dtype=np.float64), self.cos, self.sin,
                         self.max_range)  # fmt: skip
        if len(pts):
            # Distance from each hit point to each predicted segment 0 -> horizon * v.
            seg = vel * self.horizon
            L2 = (seg * seg).sum(1)
            t = (pts @ seg.T) / np.where(L2 > 0, L2, 1.0)[None, :]
            t = np.clip(t, 0.0, 1.0)
            near = t[..., None] * seg[None, :, :]
            d = np.sqrt(((pts[:, None, :] - near) ** 2).sum(-1)).min(0)
            clear = d - self.radius
        else:
            clear = np.full(len(vel), np.inf)
        progress = np.hypot(*aim) - np.hypot(*(aim[None, :] - vel).T)
        speed = np.hypot(*vel.T)
        score = progress + self.clearance_weight * np.minimum(clear, 3.0) / 3.0 + 0.1 * speed
        ok = clear >= self.margin
        if ok.any():
            score = np.where(ok, score, -np.inf)
            best = int(np.argmax(score))
        else:
            best = int(np.argmax(clear))
        v = vel[best]
        return v
