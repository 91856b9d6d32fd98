"""Vector Field Histogram (VFH+, Ulrich & Borenstein, ICRA 1998) on the range ring."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from copi.baselines._common import Steered, hit_points, segment_distance, unit
from copi.core import Observation, Task
from copi.errors import InvalidArgumentError

__all__ = ["VFH"]

_TWO_PI = 2 * math.pi


def _wrap(a: NDArray[np.float64] | float) -> NDArray[np.float64] | float:
    """Angles to (-pi, pi]."""
    return (np.asarray(a) + math.pi) % _TWO_PI - math.pi


class VFH(Steered):
    """VFH+ for a holonomic disc with a ring of ranges. Level ``sensor``; hand-written.

    Each hit at distance d adds (1 - d / max_range)^2 to every sector within
    arcsin((radius + safety) / d) of it (the obstacle enlarged by the agent's radius and
    a safety distance; the primary polar histogram keeps the maximum per sector). A
    sector is blocked above ``threshold`` and free below 0.8 ``threshold`` (hysteresis
    between steps). Candidate directions are the centres of narrow free valleys and, in
    wide ones (more than ``wide`` sectors), the two directions ``wide / 2`` sectors in
    from its borders and the target direction if it lies inside; the cheapest by
    5 |target - c| + 2 |previous - c| is taken, at a speed that falls with the
    histogram's value there. With every sector blocked the agent moves at half speed
    along its longest ray. When the point aimed at is within range and the straight way
    to it keeps ``radius + safety`` clear of every hit, the agent goes straight there:
    the histogram counts hits beyond that point too (a wall behind the goal), which must
    not keep the agent from a goal it can see.

    Parameters
    ----------
    threshold : float
        Histogram value above which a sector is blocked (tuned).
    safety : float
        Extra clearance by which hits are enlarged, agent steps (tuned).
    sectors : int
        Sectors of the polar histogram.
    wide : int
        Valleys wider than this many sectors are wide.
    """

    name = "vfh"

    def __init__(
        self, *, threshold: float = 0.5, safety: float = 0.5, sectors: int = 72, wide: int = 12
    ) -> None:
        for key, v in (("threshold", threshold), ("safety", safety)):
            if not (math.isfinite(v) and v >= 0):
                raise InvalidArgumentError(f"{key} must be a finite number >= 0; got {v!r}")
        if int(sectors) != sectors or sectors < 8:
            raise InvalidArgumentError(f"sectors must be an int >= 8; got {sectors!r}")
        self.threshold = float(threshold)
        self.safety = float(safety)
        self.sectors = int(sectors)
        self.wide = int(wide)
        self._phi = _TWO_PI * np.arange(self.sectors) / self.sectors

    def reset(self, task: Task) -> None:
        super().reset(task)
        self._blocked = np.zeros(self.sectors, dtype=bool)
        self._previous: float | None = None
        self._angles = np.arctan2(self.sin, self.cos)

    def histogram(self, ranges: NDArray[np.float64]) -> NDArray[np.float64]:
        """The primary polar histogram, shape (sectors,)."""
        hit = ranges < self.max_range
        d = np.maximum(ranges[hit], 1e-9)
        theta = self._angles[hit]
        m = (1.0 - d / self.max_range) ** 2
        gamma = np.arcsin(np.minimum(1.0, (self.radius + self.safety) / d))
        near = np.abs(_wrap(self._phi[:, None] - theta[None, :])) <= gamma[None, :]
        return np.where(near, m[None, :], 0.0).max(axis=1, initial=0.0)

    def steer(
        self, obs: Observation, desired: NDArray[np.float64], reach: float
    ) -> NDArray[np.float64]:
        ranges = np.asarray(obs.ranges, dtype=np.float64)
        u, _ = unit(desired)
        if not u.any():
            return np.zeros(2)
        if reach < self.max_range and self._in_sight(ranges, u * reach):
            self._previous = math.atan2(u[1], u[0])
            self._explained(u[None], [0.0], "the aim point in sight: straight at it")
            return u * min(1.0, reach)
        h = self.histogram(ranges)
        blocked = np.where(
            h > self.threshold, True, np.where(h < 0.8 * self.threshold, False, self._blocked)
        )
        self._blocked = blocked
        target = math.atan2(u[1], u[0])
        if blocked.all():
            k = int(np.argmax(ranges))
            a = self._angles[k]
            self._previous = a
            self._explained([[math.cos(a), math.sin(a)]], [0.0],
                            "every sector blocked: along the longest ray, at half speed")
            return 0.5 * np.array([math.cos(a), math.sin(a)])
        cands = self._candidates(blocked, target)
        prev = target if self._previous is None else self._previous
        cost = 5.0 * np.abs(_wrap(cands - target)) + 2.0 * np.abs(_wrap(cands - prev))
        if self.explain:
            self._explained(np.column_stack([np.cos(cands), np.sin(cands)]), -cost,
                            "minus the cost of turning from the target and the last heading")
        a = float(cands[int(np.argmin(cost))])
        self._previous = a
        k = int(round(a / _TWO_PI * self.sectors)) % self.sectors
        speed = 1.0 - min(h[k], 1.0)
        v = np.array([math.cos(a), math.sin(a)])
        along = (v[0] * u[0] + v[1] * u[1]) * reach  # not v @ u: BLAS rounds per processor
        if along > 0:
            speed = min(speed, along)
        return v * max(speed, 0.1)

    def _in_sight(self, ranges: NDArray[np.float64], aim: NDArray[np.float64]) -> bool:
        """Whether the segment to ``aim`` keeps ``radius + safety`` clear of every hit."""
        pts = hit_points(ranges, self.cos, self.sin, self.max_range)
        d = segment_distance(pts, np.zeros((1, 2)), aim[None])[0]
        return bool(d >= self.radius + self.safety)

    def _candidates(self, blocked: NDArray[np.bool_], target: float) -> NDArray[np.float64]:
        n = self.sectors
        width = _TWO_PI / n
        if not blocked.any():
            return np.array([target])
        # Valleys: runs of free sectors, walked from the sector after a blocked one.
        start = int(np.flatnonzero(blocked)[0])
        out: list[float] = []
        k = 0
        while k < n:
            i = (start + k) % n
            if blocked[i]:
                k += 1
                continue
            j = k
            while j < n and not blocked[(start + j) % n]:
                j += 1
            lo = (start + k) * width
            hi = (start + j - 1) * width
            size = j - k
            if size > self.wide:
                out += [lo + 0.5 * self.wide * width, hi - 0.5 * self.wide * width]
                rel = (target - lo) % _TWO_PI
                if rel <= hi - lo:
                    out.append(target)
            else:
                out.append(0.5 * (lo + hi))
            k = j
        return np.asarray(out, dtype=np.float64)
