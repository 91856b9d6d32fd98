"""The static distance to the goal on a grid: the cost-to-go both ceilings search towards.

Why by hand: both ceilings look up the distance to the goal around walls hundreds of
thousands of times an episode, at points no planner was asked about. A Dijkstra over a
grid of the free space, once per episode, answers each look-up in nanoseconds; the
visibility graph (:mod:`copi.planning`) would need a query per point, and scipy's
``dijkstra`` a sparse graph of the grid built in Python first (slower than the search).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from copi.geometry import clearance
from copi.geometry.kernels import point_segment_d2
from copi.planning.kernels import heap_pop, heap_push, heap_room
from copi.world import World

__all__ = ["GoalField", "clearance_grid"]

_SQRT2 = math.sqrt(2.0)


@njit(cache=True)
def _dijkstra(free, seeds, h, out):  # type: ignore[no-untyped-def]
    """Distances over the 8-connected free cells (no corner cutting), cell side ``h``,
    from the free cells where ``seeds`` is finite, each starting at its seed's value,
    into ``out`` (inf where unreachable)."""
    ny, nx = free.shape
    out[:, :] = np.inf
    cap = 4 * (nx + ny) + 64
    keys = np.empty(cap)
    items = np.empty(cap, dtype=np.int64)
    size = 0
    for i in range(ny):
        for j in range(nx):
            if free[i, j] and seeds[i, j] < np.inf:
                out[i, j] = seeds[i, j]
                keys, items = heap_room(keys, items, size)
                size = heap_push(keys, items, size, seeds[i, j], i * nx + j)
    done = np.zeros((ny, nx), dtype=np.bool_)
    while size > 0:
        d, u, size = heap_pop(keys, items, size)
        i = u // nx
        j = u % nx
        if done[i, j]:
            continue
        done[i, j] = True
        for di in range(-1, 2):
            for dj in range(-1, 2):
                if di == 0 and dj == 0:
                    continue
                a = i + di
                b = j + dj
                if a < 0 or b < 0 or a >= ny or b >= nx or not free[a, b] or done[a, b]:
                    continue
                if di != 0 and dj != 0:
                    if not (free[i, b] and free[a, j]):
                        continue
                    step = _SQRT2 * h
                else:
                    step = h
                nd = d + step
                if nd < out[a, b]:
                    out[a, b] = nd
                    keys, items = heap_room(keys, items, size)
                    size = heap_push(keys, items, size, nd, a * nx + b)


@njit(cache=True)
def clearance_grid(segs, x0, y0, h, ny, nx, cap):  # type: ignore[no-untyped-def]
    """Distance to the nearest of ``segs`` at the centres of an ny x nx grid (origin x0,
    y0, side h), ``cap`` wherever no wall is nearer: each segment visits only the cells
    within ``cap`` of it, so a box with a few dozen walls costs a few dozen small loops
    (the clearance of every cell against every wall would cost a hundred times more)."""
    out = np.full((ny, nx), cap * cap)
    for k in range(segs.shape[0]):
        ax, ay, bx, by = segs[k, 0], segs[k, 1], segs[k, 2], segs[k, 3]
        j0 = max(0, int(math.floor((min(ax, bx) - cap - x0) / h)))
        j1 = min(nx - 1, int(math.ceil((max(ax, bx) + cap - x0) / h)))
        i0 = max(0, int(math.floor((min(ay, by) - cap - y0) / h)))
        i1 = min(ny - 1, int(math.ceil((max(ay, by) + cap - y0) / h)))
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                d = point_segment_d2(x0 + j * h, y0 + i * h, segs, k)
                if d < out[i, j]:
                    out[i, j] = d
    return np.sqrt(out)


@njit(cache=True, inline="always")
def field_at(dist, x0, y0, h, x, y, gx, gy):  # type: ignore[no-untyped-def]
    """The distance to go from (x, y): the grid's value at the nearest cell plus the way
    to that cell's centre, or the straight distance when it is shorter (in sight of the
    goal the grid's octile detours are not needed); inf off the reachable cells."""
    j = int(math.floor((x - x0) / h + 0.5))
    i = int(math.floor((y - y0) / h + 0.5))
    ny, nx = dist.shape
    if i < 0 or j < 0 or i >= ny or j >= nx:
        return np.inf
    v = dist[i, j]
    if not math.isfinite(v):
        return np.inf
    cx = x0 + j * h - x
    cy = y0 + i * h - y
    v = v + math.sqrt(cx * cx + cy * cy)
    straight = math.sqrt((gx - x) * (gx - x) + (gy - y) * (gy - y))
    return straight if straight > v else v


class GoalField:
    """Distance to the goal around the walls, for a disc of ``radius``, on a grid of side
    ``h`` (agent steps) over the world's bounding box.

    A cell is free when its centre is at least ``radius - h / sqrt 2`` from every wall, so
    every position the disc may take lies in a free cell (the field may then pass a gap a
    hair narrower than the disc: it is a cost-to-go, not a proof of a path). Distances
    are 8-connected (at most 8 % longer than straight lines), never shorter than the
    straight distance; a look-up is :func:`field_at`.

    Examples
    --------
    >>> room = World([[0, 0], [10, 0], [10, 10], [0, 10]])
    >>> f = GoalField(room, [8.0, 5.0], 0.3)
    >>> round(f.at(2.0, 5.0), 2), f.at(-5.0, 5.0)
    (6.0, inf)
    """

    def __init__(self, world: World, goal: NDArray[np.float64], radius: float, h: float = 0.25):
        segs = world.segments
        lo = np.minimum(segs[:, [0, 1]].min(axis=0), segs[:, [2, 3]].min(axis=0)) - h
        hi = np.maximum(segs[:, [0, 1]].max(axis=0), segs[:, [2, 3]].max(axis=0)) + h
        nx = int(math.ceil((hi[0] - lo[0]) / h)) + 1
        ny = int(math.ceil((hi[1] - lo[1]) / h)) + 1
        xs = lo[0] + h * np.arange(nx)
        ys = lo[1] + h * np.arange(ny)
        pts = np.column_stack([np.tile(xs, ny), np.repeat(ys, nx)])
        free = (clearance(pts, segs) >= radius - h / _SQRT2) & world.contains(pts)
        self._search(free.reshape(ny, nx), lo[0], lo[1], h, goal, open_edges=False)

    @classmethod
    def open(cls, clear: NDArray[np.float64], x0: float, y0: float, h: float,
             goal: NDArray[np.float64], radius: float) -> GoalField:  # fmt: skip
        """The field over a box of a world known only by some walls (level ``sensor``:
        the walls the agent sees), from their clearance ``clear`` at the centres of the
        box's cells (origin ``x0``, ``y0``, side ``h``): a cell is free when the disc fits
        at its centre (the cells a planner on the same grid may stand on), unknown space
        is free, and the way out of the box at a cell of its edge is the straight line
        from there to the goal, wherever the goal is."""
        self = cls.__new__(cls)
        self._search(clear >= radius, x0, y0, h, goal, open_edges=True)
        return self

    def _search(self, free: NDArray[np.bool_], x0: float, y0: float, h: float, goal: Any,
                open_edges: bool) -> None:  # fmt: skip
        self.free = free
        ny, nx = free.shape
        self.x0, self.y0, self.h = float(x0), float(y0), float(h)
        self.goal = np.asarray(goal, dtype=np.float64).copy()
        seeds = np.full((ny, nx), np.inf)
        gj = int(round((self.goal[0] - self.x0) / h))
        gi = int(round((self.goal[1] - self.y0) / h))
        if open_edges:  # leaving the box: the straight way on from its edge
            edge = np.zeros((ny, nx), dtype=bool)
            edge[[0, -1], :] = edge[:, [0, -1]] = True
            dx = self.x0 + h * np.arange(nx) - self.goal[0]
            dy = self.y0 + h * np.arange(ny) - self.goal[1]
            seeds[edge] = np.hypot(dx[None, :], dy[:, None])[edge]
        if 0 <= gi < ny and 0 <= gj < nx or not open_edges:
            seeds[int(np.clip(gi, 0, ny - 1)), int(np.clip(gj, 0, nx - 1))] = 0.0
        self.dist = np.empty((ny, nx))
        _dijkstra(self.free, seeds, self.h, self.dist)

    def at(self, x: float, y: float) -> float:
        """The distance to go from (x, y) (see :func:`field_at`)."""
        return float(field_at(self.dist, self.x0, self.y0, self.h, x, y, *self.goal))
