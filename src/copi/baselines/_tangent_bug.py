"""TangentBug (Kamon, Rivlin & Rimon, IJRR 1998) on the range ring: the classic method for
reaching a goal in an unknown static world with a range sensor."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from copi.baselines._common import Steered, hit_points, segment_distance, unit
from copi.core import Observation, Task
from copi.errors import InvalidArgumentError

__all__ = ["TangentBug"]


def _rotate(v: NDArray[np.float64], angle: float) -> NDArray[np.float64]:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


class TangentBug(Steered):
    """TangentBug with a finite-range ring. Level ``sensor``; hand-written.

    *Motion to goal*: straight at the goal when the corridor to it (as far as the sensor
    sees) is ``margin`` clear; otherwise towards the endpoint O of the visible obstacle
    boundary (a jump of more than ``jump`` between neighbouring rays, or a ray at full
    range) that minimises |O| + |goal - O|, passed with clearance. When that heuristic
    distance stops decreasing the agent is at a local minimum and switches to *boundary
    following*: it keeps the nearest obstacle at ``follow`` on one side (the side that
    turned it towards the goal), recording d_followed, the least distance to the goal of
    the boundary points it sensed; it leaves as soon as some visible free point is closer
    to the goal than d_followed (d_reach < d_followed). At level ``map`` the goal is the
    route's aim point, and a new aim point restarts motion to goal.

    Parameters
    ----------
    margin : float
        Clearance of the straight corridor to the goal (beyond the agent's radius).
    follow : float
        Distance kept to the followed boundary (centre to hit point).
    jump : float
        Range difference between neighbouring rays that makes an endpoint.
    """

    name = "tangent-bug"

    def __init__(self, *, margin: float = 0.5, follow: float = 1.0, jump: float = 1.0) -> None:
        for key, v in (("margin", margin), ("follow", follow), ("jump", jump)):
            if not (math.isfinite(v) and v > 0):
                raise InvalidArgumentError(f"{key} must be a finite number > 0; got {v!r}")
        self.margin = float(margin)
        self.follow = float(follow)
        self.jump = float(jump)

    def reset(self, task: Task) -> None:
        super().reset(task)
        self.mode = "goal"
        self._best_h = math.inf
        self._d_followed = math.inf
        self._side = 1.0
        self._aim_abs: NDArray[np.float64] | None = None
        self._follow_steps = 0

    def _clear(self, pts: NDArray[np.float64], g: NDArray[np.float64]) -> bool:
        """Whether the straight corridor towards g (up to the sensor's range) is clear."""
        u, dist = unit(g)
        end = u * min(dist, self.max_range)
        d = segment_distance(pts, np.zeros((1, 2)), end[None])[0]
        return bool(d >= self.radius + self.margin)

    def _endpoints(self, ranges: NDArray[np.float64]) -> NDArray[np.float64]:
        """Points just past the ends of the visible boundary's continuous pieces, (m, 2)."""
        n = len(ranges)
        out = []
        for i in range(n):
            j = (i + 1) % n
            a, b = ranges[i], ranges[j]
            far = self.max_range
            if abs(a - b) <= self.jump and (a < far) == (b < far):
                continue
            near, other = (i, j) if a < b else (j, i)
            d = ranges[near]
            p = d * np.array([self.cos[near], self.sin[near]])
            # Step out of the boundary, towards the farther ray, by the agent's size.
            side = 1.0 if other == (near + 1) % n else -1.0
            off = math.asin(min(1.0, (self.radius + self.margin) / max(d, 1e-9)))
            out.append(_rotate(p, side * off))
        return np.asarray(out, dtype=np.float64).reshape(-1, 2)

    def steer(
        self, obs: Observation, desired: NDArray[np.float64], reach: float
    ) -> NDArray[np.float64]:
        ranges = np.asarray(obs.ranges, dtype=np.float64)
        u, _ = unit(desired)
        if not u.any():
            return np.zeros(2)
        g = u * (reach if math.isfinite(reach) else self.max_range)
        if obs.position is not None:
            aim = obs.position + g
            if self._aim_abs is None or np.hypot(*(aim - self._aim_abs)) > 0.5:
                self.mode, self._best_h = "goal", math.inf
            self._aim_abs = aim
        pts = hit_points(ranges, self.cos, self.sin, self.max_range)
        if self.mode == "follow":
            self._follow_steps += 1
            if len(pts):
                self._d_followed = min(
                    self._d_followed, float(np.hypot(*(pts - g[None]).T).min())
                )
            if self._reach(ranges, g) < self._d_followed - 1e-6 or self._follow_steps > 400:
                self.mode, self._best_h = "goal", math.inf
            else:
                v = self._follow(pts, g)
                self._explained(v[None], [0.0], "following the boundary: its one move")
                return v
        if self._clear(pts, g):
            self._explained(u[None], [0.0], "the goal in sight: straight at it")
            return u * min(1.0, float(np.hypot(*g)))
        ends = self._endpoints(ranges)
        if not len(ends):
            v = self._start_following(pts, g)
            self._explained(v[None], [0.0], "no gap to aim for: boundary following begins")
            return v
        h = np.hypot(*ends.T) + np.hypot(*(g[None] - ends).T)
        k = int(np.argmin(h))
        if self.explain:
            self._explained([unit(e)[0] for e in ends], -h,
                            "minus the heuristic distance through each gap's endpoint")
        if h[k] > self._best_h + 1e-3:
            v = self._start_following(pts, g)
            self._explained(v[None], [0.0], "no gap better than before: boundary following")
            return v
        self._best_h = min(self._best_h, float(h[k]))
        v, _ = unit(ends[k])
        return v

    def _reach(self, ranges: NDArray[np.float64], g: NDArray[np.float64]) -> float:
        """d_reach: least distance to the goal of a free point the rays show."""
        t = np.clip(g[0] * self.cos + g[1] * self.sin, 0.0, np.maximum(ranges - self.radius, 0))
        q = np.column_stack([t * self.cos, t * self.sin])
        return float(np.hypot(*(q - g[None]).T).min())

    def _start_following(self, pts: NDArray[np.float64], g: NDArray[np.float64]) -> NDArray[
        np.float64
    ]:
        self.mode = "follow"
        self._follow_steps = 0
        self._d_followed = float(np.hypot(*(pts - g[None]).T).min()) if len(pts) else math.inf
        if len(pts):
            p = pts[int(np.argmin(np.hypot(*pts.T)))]
            # Follow on the side whose tangent points more towards the goal.
            left = _rotate(p, math.pi / 2)
            self._side = 1.0 if left[0] * g[0] + left[1] * g[1] >= 0 else -1.0
        return self._follow(pts, g)

    def _follow(self, pts: NDArray[np.float64], g: NDArray[np.float64]) -> NDArray[np.float64]:
        if not len(pts):
            v, _ = unit(g)
            return v
        d = np.hypot(*pts.T)
        k = int(np.argmin(d))
        toward, _ = unit(pts[k])
        tangent = _rotate(toward, self._side * math.pi / 2)
        v, _ = unit(tangent + 1.5 * (d[k] - self.follow) * toward)
        return v
