"""A global strategy for an agent with no map: it maps as it goes (the `sensor` level)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import binary_dilation

from copi.errors import InvalidArgumentError
from copi.geometry import ring_angles
from copi.online._causal_kernels import cast_grid
from copi.planning import GridPlanner

__all__ = ["Mapping"]

# Occupancy in log-odds, clamped: a hit adds _HIT, a ray passing through takes _MISS
# off; a cell is occupied above 0. A wall, hit again and again, needs many passing rays
# to clear (a ray grazing a wall crosses cells the wall also crosses); a disc seen for a
# few steps clears a few steps after it has gone.
_HIT, _MISS, _CEIL, _FLOOR = 1.0, 0.4, 4.0, -2.0


class Mapping:
    """Occupancy grid built online from the range ring, with octile A* replanning.

    Needs only what the `sensor` level gives: the ranges and the goal relative to the
    agent. The grid lives in the goal's frame (the goal at its centre), where the agent's
    position is minus the relative goal, so no map and no localisation are needed. Each
    step, the cell a ray ends in gains occupancy and cells a ray passes through lose some
    (clamped log-odds): a moving obstacle fades once the sensor sees past where it was;
    a wall keeps being seen. Neighbouring rays' hits less than ``join`` apart are joined
    into a wall segment. Occupied cells grown by the agent's radius and ``margin`` are
    blocked; unknown cells are free (the optimistic assumption of planning in unknown
    worlds). The strategy keeps its plan until the next stretch of it becomes blocked (or
    for ``every`` steps at most: a plan that swings from side to side at each new sight
    of a wall never gets anywhere), and aims at the farthest point of the path within
    ``lookahead`` that it can see in a straight line on the grid. With no path (the goal
    walled off as far as it knows), it heads for the goal.

    Parameters
    ----------
    cell : float
        Side of a grid cell, agent steps.
    extent : float
        Half the side of the square the grid covers around the goal.
    margin : float
        Extra clearance beyond the agent's radius when growing occupied cells.
    every : int
        Steps between two plans at most.
    lookahead : float
        How far along the path the strategy aims.
    join : float
        Neighbouring rays' hits nearer than this to each other are joined into a wall.
    wall_level, wall_hits : float, int
        A cell counts as a *learnt wall* when its occupancy is at least ``wall_level``
        and it has been hit ``wall_hits`` times in all (a moving obstacle passes; a wall
        is seen again and again). :meth:`static_reading` casts the ring on those cells:
        the reading the walls alone would give, as far as the agent has learnt them,
        which is what a ``map``-level method is handed as the static reading.
    """

    name = "mapping"

    def __init__(
        self,
        *,
        cell: float = 0.5,
        extent: float = 80.0,
        margin: float = 0.0,
        every: int = 25,
        lookahead: float = 4.0,
        join: float = 2.0,
        wall_level: float = 3.5,
        wall_hits: int = 20,
    ) -> None:
        for key, v in (("cell", cell), ("extent", extent), ("lookahead", lookahead)):
            if not (math.isfinite(v) and v > 0):
                raise InvalidArgumentError(f"{key} must be a finite number > 0; got {v!r}")
        if not (math.isfinite(margin) and margin >= 0):
            raise InvalidArgumentError(f"margin must be a finite number >= 0; got {margin!r}")
        if int(every) != every or every < 1:
            raise InvalidArgumentError(f"every must be a positive int; got {every!r}")
        self.cell = float(cell)
        self.extent = float(extent)
        self.margin = float(margin)
        self.every = int(every)
        self.lookahead = float(lookahead)
        self.join = float(join)
        self.wall_level = float(wall_level)
        self.wall_hits = int(wall_hits)

    def reset(
        self, n_rays: int, max_range: float, agent_radius: float, *, keep: bool = False
    ) -> None:
        """Start a new task with an empty map (``keep``: with the map built so far, in a
        lifelong run, where the grid lives in the frame of the agent's odometry)."""
        n = int(math.ceil(2 * self.extent / self.cell))
        if not (keep and getattr(self, "n", None) == n):
            self.n = n
            self.occupancy = np.zeros((n, n))
            self.hits = np.zeros((n, n), dtype=np.int64)
            self.planner = GridPlanner(np.ones((n, n), dtype=bool))
        angles = ring_angles(n_rays)
        self._dirs = np.column_stack([np.cos(angles), np.sin(angles)])
        self._cos = np.ascontiguousarray(self._dirs[:, 0])
        self._sin = np.ascontiguousarray(self._dirs[:, 1])
        self._static = np.empty(n_rays)
        self.max_range = float(max_range)
        grow = int(math.ceil((agent_radius + self.margin) / self.cell))
        yy, xx = np.mgrid[-grow : grow + 1, -grow : grow + 1]
        self._disc = (xx * xx + yy * yy) * self.cell**2 <= (agent_radius + self.margin) ** 2
        # Points along each ray, every half cell, as fractions of the ray's length.
        self._steps = np.arange(0.5 * self.cell, self.max_range, 0.5 * self.cell)
        self.path: NDArray[np.float64] | None = None
        self.age = 0
        self.plans = 0

    def closes_the_way(self, world: Any, start: Any, goal: Any, agent_radius: float) -> bool:
        """Whether this strategy's grid, with every wall of ``world`` seen (its cells
        occupied, grown by the agent's radius and the margin as planning grows them),
        leaves no way from ``start`` to ``goal`` — a door the exact planner passes may be
        closed by the grid's cells (``copi evaluate`` and ``benchmark`` warn of it)."""
        from scipy.ndimage import label

        x0, y0, x1, y1 = world.bounds
        nx = int(math.ceil((x1 - x0) / self.cell)) + 1
        ny = int(math.ceil((y1 - y0) / self.cell)) + 1
        occ = np.zeros((ny, nx), dtype=bool)
        for ax, ay, bx, by in world.segments:
            k = int(math.ceil(math.hypot(bx - ax, by - ay) / (0.25 * self.cell))) + 1
            t = np.linspace(0.0, 1.0, k)
            i = np.floor((ay + t * (by - ay) - y0) / self.cell).astype(np.int64)
            j = np.floor((ax + t * (bx - ax) - x0) / self.cell).astype(np.int64)
            occ[np.clip(i, 0, ny - 1), np.clip(j, 0, nx - 1)] = True
        # Hits of neighbouring rays nearer than ``join`` are joined into a wall, so two
        # walls nearer than that (a door seen at a slant) may be joined across the gap:
        # join every two wall points that near, as the worst view would.
        from scipy.spatial import cKDTree

        pts = []
        for ax, ay, bx, by in world.segments:
            k = int(math.ceil(math.hypot(bx - ax, by - ay) / (0.5 * self.cell))) + 1
            t = np.linspace(0.0, 1.0, k)[:, None]
            pts.append(np.hstack([ax + t * (bx - ax), ay + t * (by - ay)]))
        wall = np.concatenate(pts)
        pairs = cKDTree(wall).query_pairs(self.join, output_type="ndarray")
        if len(pairs):
            t = np.linspace(0.0, 1.0, int(math.ceil(self.join / (0.25 * self.cell))) + 1)
            a, b = wall[pairs[:, 0]], wall[pairs[:, 1]]
            line = a[:, None, :] + t[None, :, None] * (b - a)[:, None, :]
            i = np.floor((line[..., 1] - y0) / self.cell).astype(np.int64)
            j = np.floor((line[..., 0] - x0) / self.cell).astype(np.int64)
            occ[np.clip(i, 0, ny - 1), np.clip(j, 0, nx - 1)] = True
        grow = int(math.ceil((agent_radius + self.margin) / self.cell))
        yy, xx = np.mgrid[-grow : grow + 1, -grow : grow + 1]
        disc = (xx * xx + yy * yy) * self.cell**2 <= (agent_radius + self.margin) ** 2
        free = ~binary_dilation(occ, structure=disc)
        cells = [(int((p[1] - y0) // self.cell), int((p[0] - x0) // self.cell))
                 for p in (np.asarray(start, float), np.asarray(goal, float))]  # fmt: skip
        for i, j in cells:
            free[min(max(i, 0), ny - 1), min(max(j, 0), nx - 1)] = True
        parts, _ = label(free, structure=np.ones((3, 3), dtype=bool))
        (si, sj), (gi, gj) = cells
        return bool(parts[si, sj] != parts[gi, gj] or parts[si, sj] == 0)

    # -- the grid ---------------------------------------------------------------------

    def _index(self, p: NDArray[np.float64]) -> NDArray[np.int64]:
        """Cells (x, y) of points (k, 2) in the goal's frame (clipped to the grid)."""
        ij = np.floor((p + self.extent) / self.cell).astype(np.int64)
        return np.clip(ij, 0, self.n - 1)

    def _centre(self, ij: Any) -> NDArray[np.float64]:
        return np.asarray((np.asarray(ij) + 0.5) * self.cell - self.extent, dtype=np.float64)

    def update(self, ranges: Any, position: NDArray[np.float64]) -> None:
        """Fold one reading taken at ``position`` (goal frame) into the grid."""
        r = np.asarray(ranges, dtype=np.float64)
        along = self._steps[None, :] < (r[:, None] - 0.5 * self.cell)  # (rays, samples)
        pts = position + self._steps[None, :, None] * self._dirs[:, None, :]
        free = self._index(pts[along])
        occ = self.occupancy
        occ[free[:, 1], free[:, 0]] = np.maximum(occ[free[:, 1], free[:, 0]] - _MISS, _FLOOR)
        hit = r < self.max_range
        ends = position + r[:, None] * self._dirs
        # Neighbouring hits close to each other are one surface: mark the cells between
        # them too (with 32 rays a wall 5 away is hit every metre, and a plan would slip
        # through the gaps, then swing to the other side once the agent came nearer).
        nxt = np.roll(np.arange(len(r)), -1)
        join = hit & hit[nxt] & (np.hypot(*(ends - ends[nxt]).T) <= self.join)
        t = np.linspace(0.0, 1.0, int(math.ceil(self.join / (0.5 * self.cell))) + 1)
        seg = ends[join, None, :] + t[None, :, None] * (ends[nxt][join] - ends[join])[:, None, :]
        cells = self._index(np.concatenate([ends[hit], seg.reshape(-1, 2)]))
        occ[cells[:, 1], cells[:, 0]] = np.minimum(occ[cells[:, 1], cells[:, 0]] + _HIT, _CEIL)
        self.hits[cells[:, 1], cells[:, 0]] += 1

    def static_reading(self, position: Any) -> NDArray[np.float64]:
        """The ring's reading at ``position`` (the grid's frame) of the learnt walls alone
        (cells with occupancy >= ``wall_level``, hit ``wall_hits`` times):
        never farther than the wall's face, the maximum range where no wall is known."""
        p = np.asarray(position, dtype=np.float64)
        cast_grid(self.occupancy, self.hits, self.wall_level, self.wall_hits, p[0], p[1],
                  self.cell, self.extent, self._cos, self._sin, self.max_range, 0.1,
                  self._static)  # fmt: skip
        return self._static.copy()

    def _blocked(self) -> NDArray[np.bool_]:
        return binary_dilation(self.occupancy > 0.0, structure=self._disc)

    # -- planning ---------------------------------------------------------------------

    def _plan(self, here: NDArray[np.int64], goal: NDArray[np.int64]) -> None:
        self.plans += 1
        self.age = 0
        free = ~self._blocked()
        free[here[1], here[0]] = True
        free[goal[1], goal[0]] = True
        self.planner.free[...] = free
        plan = self.planner.shortest_path(tuple(here), tuple(goal))
        self.path = None if plan.path is None else self._centre(plan.path)

    def _clear_line(self, a: NDArray[np.float64], b: NDArray[np.float64]) -> bool:
        """Whether the straight line a -> b crosses no blocked cell (as last planned)."""
        k = max(2, int(math.ceil(math.dist(a, b) / (0.5 * self.cell))) + 1)
        ij = self._index(a + np.linspace(0.0, 1.0, k)[:, None] * (b - a))
        return bool(self.planner.free[ij[:, 1], ij[:, 0]].all())

    def aim(
        self, ranges: Any, goal: Any, position: Any = None
    ) -> tuple[NDArray[np.float64], float]:
        """(desired direction, distance to the point aimed at), from the reading and the
        goal relative to the agent; ``position``: the agent's odometry in a lifelong run
        (the grid then lives in that frame), else None (the grid lives in the goal's)."""
        g = np.asarray(goal, dtype=np.float64)
        if position is None:
            p = -g  # the agent in the goal's frame
            goal_at = np.zeros(2)
        else:
            p = np.asarray(position, dtype=np.float64)
            goal_at = p + g
        self.update(ranges, p)
        here = self._index(p[None])[0]
        target = self._index(goal_at[None])[0]
        self.age += 1
        stale = self.path is None or self.age >= self.every
        if not stale and self.path is not None:
            ahead = self.path[: max(2, int(self.lookahead / self.cell))]
            ij = self._index(ahead)
            stale = bool((self.occupancy[ij[:, 1], ij[:, 0]] > 0.0).any())
        if stale:
            self._plan(here, target)
        if self.path is None or len(self.path) < 2:
            return g, math.hypot(g[0], g[1])
        return self._follow(p, goal_at)

    def _follow(
        self, p: NDArray[np.float64], goal_at: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], float]:
        """Aim along the planned path (``self.path``, two cells at least) from ``p``."""
        assert self.path is not None
        # Drop the cells behind, then aim at the farthest one in sight within lookahead.
        d = np.hypot(*(self.path - p).T)
        start = int(np.argmin(d))
        self.path = self.path[start:]
        aim = self.path[-1] if len(self.path) == 1 else self.path[1]
        for q in self.path[1:]:
            if math.dist(p, q) > self.lookahead or not self._clear_line(p, q):
                break
            aim = q
        if len(self.path) and math.dist(self.path[-1], aim) < 1e-9:
            aim = goal_at  # the last cell's centre stands for the goal itself
        v = aim - p
        return v, math.hypot(v[0], v[1])
