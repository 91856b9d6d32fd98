"""The Dynamic Window Approach (Fox, Burgard & Thrun, 1997) for a holonomic disc:
velocity sampling scored on the range reading."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from copi.baselines._common import Steered, segment_distance, unit
from copi.core import Observation
from copi.errors import InvalidArgumentError

__all__ = ["DWA"]


class DWA(Steered):
    """Sample velocities (``headings`` directions plus the desired one, times four speeds,
    plus standing still); predict each as a straight motion over ``horizon`` steps; keep
    those whose disc stays ``margin`` clear of every hit point of the reading from the end
    of this step to the end of the horizon (and whose step does not run into a hit); take
    the best by progress towards the aim point + ``clearance_weight`` × clearance (capped
    at 3) / 3 + 0.1 × speed. With none admissible, the one with most clearance.

    Level ``sensor``: every hit is an obstacle. At ``map`` the static reading tells the
    walls apart (as it does for copi's guard): a motion need only not run into a wall,
    and the margin and the clearance score count moving obstacles only. Hand-written;
    ``margin`` and ``clearance_weight`` are tuned. The agent's speed changes freely
    within a step, so the dynamic window is the whole disc of speeds up to 1.

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
        margin: float = 0.9,
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

    def steer(
        self, obs: Observation, desired: NDArray[np.float64], reach: float
    ) -> NDArray[np.float64]:
        u, _ = unit(desired)
        if not u.any():
            return np.zeros(2)
        # At least a step ahead: a route's corner can lie a hair away, where every motion
        # overshoots and standing still scored best for good (the goal itself ends the
        # episode within its tolerance, so aiming past it is harmless).
        aim = u * (max(reach, 1.0) if math.isfinite(reach) else self.max_range)
        dirs = np.vstack([self._dirs, u])
        vel = (dirs[:, None, :] * self._speeds[None, :, None]).reshape(-1, 2)
        vel = np.vstack([vel, np.zeros((1, 2))])
        ranges = np.asarray(obs.ranges, dtype=np.float64)
        hit = ranges < self.max_range
        if obs.static is not None:
            # At level map the static reading tells walls (which only stop the agent)
            # from moving obstacles, as it does for copi's guard.
            moving = hit & (ranges < np.asarray(obs.static) - 0.05)
        else:
            moving = hit
        wall = hit & ~moving
        # Where the agent will be once the obstacles have moved: from the end of this
        # step to the end of the horizon (measured from the current position, every
        # motion would score the same as soon as a disc came within the margin).
        clear = self._clearance(ranges, moving, vel, vel * self.horizon)
        # Walls only stop the agent: a step may not take it nearer to one than 0.02, or
        # than it already is (resting against a wall, it may slide along it).
        touch = self._clearance(ranges, wall, 0.25 * vel, vel)
        now = self._clearance(ranges, wall, np.zeros((1, 2)), np.zeros((1, 2)))[0]
        floor = min(0.02, now - 1e-9)
        progress = np.hypot(*aim) - np.hypot(*(aim[None, :] - vel).T)
        speed = np.hypot(*vel.T)
        score = progress + self.clearance_weight * np.minimum(clear, 3.0) / 3.0 + 0.1 * speed
        ok = (clear >= self.margin) & (touch >= floor)
        if ok.any():
            score = np.where(ok, score, -np.inf)
            best = int(np.argmax(score))
            self._explained(vel, score, "progress + clearance; -inf: not admissible")
        else:
            room = np.minimum(clear, touch + 1.0)
            best = int(np.argmax(room))
            self._explained(vel, room, "clearance (none admissible: the clearest is taken)")
        return vel[best]

    def _clearance(
        self,
        ranges: NDArray[np.float64],
        which: NDArray[np.bool_],
        a: NDArray[np.float64],
        b: NDArray[np.float64],
    ) -> NDArray[np.float64]:
        """Least distance from the agent's disc to the chosen hit points along each
        straight motion a -> b (rows), shape (k,) (inf with no such hit)."""
        pts = np.column_stack([ranges[which] * self.cos[which], ranges[which] * self.sin[which]])
        return segment_distance(pts, a, b) - self.radius
