"""The global strategy that plans with the causal map of one world (paper §III): map as
:class:`~copi.online.Mapping` does, and learn from the agent's own options which moves
work where (:class:`~copi.online._causal_map.CausalMap`)."""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.errors import InvalidArgumentError
from copi.online._causal_file import CausalMapFormatError
from copi.online._causal_kernels import OFFSETS, plausible_options
from copi.online._causal_map import CausalMap
from copi.online._mapping import Mapping

__all__ = ["CausalStrategy"]


class CausalStrategy:
    """The global strategy ``causal``: map as :class:`~copi.online.Mapping` does, and
    learn a :class:`CausalMap` from the agent's own options (paper §III).

    Needs only the `sensor` level (the ranges, the relative goal, and in a lifelong run
    the odometry; with no odometry it lives in the goal's frame, as ``mapping`` does,
    and keeps nothing between tasks). Each step the reading is folded into the
    occupancy grid, whose own plan is made as ``mapping`` makes it, and the option under
    way is checked: when the agent has entered another place, or has spent ``patience``
    steps in its own, the option's outcome is recorded and the next option is chosen at
    the new state (place, context). The grid's way (the option its plan takes out of the
    place) is kept unless the causal map's value of it, given what was learnt at this
    state, is worse than the best option's by more than ``slack`` steps: then the causal
    map's option is followed, aiming at the farthest point of its planned chain of places
    in a straight line on the grid within ``lookahead``. So where nothing was learnt the
    strategy is ``mapping``; what it learns (options that led to contacts, or went
    nowhere, in this context) turns it elsewhere. Values are recomputed at each new
    task, after an option ended somewhere else than planned, and every ``every`` steps.
    """

    name = "causal"

    def __init__(
        self,
        causal_map: CausalMap | None = None,
        *,
        mapping: Mapping | None = None,
        every: int = 25,
        lookahead: float = 6.0,
        margin: int = 3,
        slack: float = 8.0,
    ) -> None:
        self.map = causal_map or CausalMap()
        self.mapping = mapping or Mapping(extent=self.map.extent)
        if abs(self.mapping.extent - self.map.extent) > 1e-9:
            raise InvalidArgumentError(
                "the occupancy grid and the causal map must cover the same square"
            )
        k = self.map.place / self.mapping.cell
        if abs(k - round(k)) > 1e-9 or round(k) < 1:
            raise InvalidArgumentError(
                f"a place ({self.map.place}) must be a whole number of grid cells "
                f"({self.mapping.cell})"
            )
        self.k = int(round(k))
        self.every = int(every)
        self.lookahead = float(lookahead)
        self.margin = int(margin)
        self.slack = float(slack)
        self.follows_grid = True
        self.overrides = 0
        self._occupancy: NDArray[np.float64] | None = None
        self._hits: NDArray[np.int64] | None = None
        self.plans = 0
        self.tasks = 0

    def load_occupancy(
        self, occupancy: NDArray[np.float64], hits: NDArray[np.int64] | None = None
    ) -> None:
        """Start from an occupancy grid (and its hit counts) saved with the map."""
        self._occupancy = np.asarray(occupancy, dtype=np.float64)
        self._hits = None if hits is None else np.asarray(hits, dtype=np.int64)

    def reset(self, task: Any) -> None:
        """Start a task; the causal map and the grid are kept in a lifelong run."""
        keep = bool(getattr(task, "lifelong", False))
        if not keep:
            self.map = CausalMap(**self.map.params)
        self.mapping.reset(task.n_rays, task.max_range, task.agent_radius, keep=keep)
        if self._occupancy is not None:
            if self._occupancy.shape != self.mapping.occupancy.shape:
                raise InvalidArgumentError(
                    f"the saved occupancy grid has shape {self._occupancy.shape}; this map "
                    f"needs {self.mapping.occupancy.shape}"
                )
            self.mapping.occupancy[...] = self._occupancy
            if self._hits is not None:
                self.mapping.hits[...] = self._hits
            self._occupancy = self._hits = None
        size = self.map.m * self.map.m
        self._seen = np.zeros(self.mapping.n * self.mapping.n, dtype=np.int64)
        self._queue = np.empty(4 * self.k * self.k, dtype=np.int64)
        self._plaus = np.zeros((size, 8), dtype=np.bool_)
        if not hasattr(self, "_visited") or not keep:
            self._visited = np.zeros(size, dtype=np.bool_)
        self._visited |= self.map.n.sum(1) > 0  # places a loaded map has been in
        self.value = np.full(size, 1e9)
        self.best = np.full(size, -1, dtype=np.int64)
        self.goal_place = -1
        self.option: tuple[int, int, int] | None = None  # (place, context, option)
        self.option_steps = 0
        self.age = 0
        self.tasks += 1

    # -- planning ---------------------------------------------------------------------

    def _plan(self, here: int, goal: int) -> None:
        self.plans += 1
        self.age = 0
        free = ~self.mapping._blocked()
        self.mapping.planner.free[...] = free
        m = self.map.m
        # Plan over the places seen (visited, or in the grid's sight) and those of the
        # agent and the goal, with a margin of unknown (free) space around them.
        idx = np.flatnonzero(self._visited)
        pts = np.concatenate([idx, [here, goal]])
        jj, ii = np.divmod(pts, m)
        ys, xs = np.nonzero(self.mapping.occupancy)
        i_lo, i_hi = int(ii.min()), int(ii.max())
        j_lo, j_hi = int(jj.min()), int(jj.max())
        if len(xs):
            i_lo, i_hi = min(i_lo, int(xs.min()) // self.k), max(i_hi, int(xs.max()) // self.k)
            j_lo, j_hi = min(j_lo, int(ys.min()) // self.k), max(j_hi, int(ys.max()) // self.k)
        i0, i1 = max(0, i_lo - self.margin), min(m, i_hi + self.margin + 1)
        j0, j1 = max(0, j_lo - self.margin), min(m, j_hi + self.margin + 1)
        plausible_options(free, self.k, m, i0, i1, j0, j1, OFFSETS, self._plaus, self._seen,
                          self._queue)  # fmt: skip
        gi, gj = np.meshgrid(np.arange(i0, i1), np.arange(j0, j1))
        places = (gj * m + gi).ravel()
        self.value, self.best = self.map.solve(goal, self._plaus, places)

    def _choose(self, p: int, context: int) -> int:
        best, best_q = -1, math.inf
        for a in range(8):
            q = self.map.option_value(p, a, self.value, bool(self._plaus[p, a]), context)
            if q < best_q:
                best, best_q = a, q
        return best

    # -- acting -----------------------------------------------------------------------

    def _frame(self, obs: Any) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        g = np.asarray(obs.goal, dtype=np.float64)
        if obs.odometry is None:
            return -g, np.zeros(2)
        p = np.asarray(obs.odometry, dtype=np.float64)
        return p, p + g

    def aim(self, obs: Any, context: int = -1) -> tuple[NDArray[np.float64], float]:
        """(desired direction, distance to the point aimed at)."""
        pos, goal_at = self._frame(obs)
        g = goal_at - pos
        mapping = self.mapping
        # The grid's own plan (this also folds the reading into the grid).
        fine = mapping.aim(obs.ranges, g, None if obs.odometry is None else pos)
        cmap = self.map
        here = cmap.place_of(pos)
        goal = cmap.place_of(goal_at)
        self._visited[here] = True
        self.age += 1
        replan = goal != self.goal_place or self.age >= self.every
        if self.option is not None:
            p, c, a = self.option
            self.option_steps += 1
            if here != p or self.option_steps >= cmap.patience:
                cmap.record(p, c, a, here, self.option_steps, False)
                replan = replan or here != cmap.neighbour(p, a)
                self.option = None
        if replan:
            self.goal_place = goal
            self._plan(here, goal)
        if self.option is None and here != goal:
            self._start_option(here, int(context))
        dist = math.hypot(g[0], g[1])
        if here == goal or self.value[here] >= 1e9 or self.follows_grid:
            return fine
        if dist <= self.lookahead and mapping._clear_line(pos, goal_at):
            return g, dist
        assert self.option is not None
        # The chain of places: the chosen option, then the planned best ones.
        aim = cmap.centre(cmap.neighbour(here, self.option[2]))
        q = cmap.neighbour(here, self.option[2])
        seen: set[int] = {here}
        while q >= 0 and q not in seen and math.dist(pos, cmap.centre(q)) <= self.lookahead:
            seen.add(q)
            point = goal_at if q == goal else cmap.centre(q)
            if not mapping._clear_line(pos, point):
                break
            aim = point
            if q == goal or self.best[q] < 0:
                break
            q = cmap.neighbour(q, int(self.best[q]))
        v = aim - pos
        return v, math.hypot(v[0], v[1])

    def _grid_option(self, here: int) -> int:
        """The option the grid's plan takes from place ``here`` (-1: none, or it leaves
        the place for one that is not a neighbour)."""
        path = self.mapping.path
        if path is None:
            return -1
        cmap = self.map
        for point in path:
            q = cmap.place_of(point)
            if q != here:
                for a in range(8):
                    if cmap.neighbour(here, a) == q:
                        return a
                return -1
        return -1

    def _start_option(self, here: int, context: int) -> None:
        """Choose the option at state (here, context): the grid's own way unless what
        was learnt here says another option is better by more than ``slack`` steps
        (then the causal map's choice is followed for the option's duration)."""
        best = self._choose(here, context)
        grid = self._grid_option(here)
        self.follows_grid = False
        if grid >= 0:
            q_grid = self.map.option_value(here, grid, self.value, bool(self._plaus[here, grid]),
                                           context)  # fmt: skip
            q_best = self.map.option_value(here, best, self.value, bool(self._plaus[here, best]),
                                           context)  # fmt: skip
            if q_grid <= q_best + self.slack:
                best, self.follows_grid = grid, True
        self.option = (here, context, best)
        self.option_steps = 0
        self.overrides += not self.follows_grid

    def finish(self, outcome: str) -> None:
        """The task ended: an option cut short by a contact is recorded as one."""
        if self.option is not None and outcome == "collision":
            p, c, a = self.option
            self.map.record(p, c, a, None, self.option_steps + 1, True)
        self.option = None

    def save(
        self, path: str | os.PathLike[str], *, world: str = "", capabilities: str = ""
    ) -> Path:
        """Save the causal map and the occupancy grid (see :meth:`CausalMap.save`)."""
        return self.map.save(path, world=world, capabilities=capabilities,
                             occupancy=self.mapping.occupancy,
                             hits=self.mapping.hits)  # fmt: skip

    @classmethod
    def load(
        cls,
        path: str | os.PathLike[str],
        *,
        world: str | None = None,
        capabilities: str | None = None,
        **kwargs: Any,
    ) -> CausalStrategy:
        """A strategy resuming the life saved in ``path`` (see :meth:`CausalMap.load`)."""
        saved = CausalMap.read(path, world=world, capabilities=capabilities)
        cmap, occ, hits = saved.map, saved.occupancy, saved.hits
        try:
            strategy = cls(cmap, **kwargs)
        except InvalidArgumentError as exc:
            raise CausalMapFormatError(f"{path}: {exc}") from None
        if occ is not None:
            n = int(math.ceil(2 * strategy.mapping.extent / strategy.mapping.cell))
            if occ.shape != (n, n):
                raise CausalMapFormatError(
                    f"{path}: occupancy grid of shape {occ.shape}, expected {(n, n)}"
                )
            strategy.load_occupancy(occ, hits)
        return strategy
