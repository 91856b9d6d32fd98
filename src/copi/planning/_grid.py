"""Octile A* on occupancy grids (the Moving AI benchmark conventions)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.errors import InvalidArgumentError, InvalidQueryError
from copi.planning import kernels
from copi.planning._visibility import Plan

__all__ = ["GridPlanner"]


class GridPlanner:
    """A* on a grid of free (True) and blocked (False) cells ``free[y, x]``.

    8-connected; a straight step costs 1 and a diagonal sqrt 2; no corner cutting (a
    diagonal step needs both orthogonal neighbours free), as in Sturtevant's benchmarks.
    The planner keeps work arrays of the grid's size between queries, so many queries on
    one map cost no allocation. Paths are in cell coordinates (x = column, y = row).

    Examples
    --------
    >>> grid = np.array([[1, 1, 1], [0, 0, 1], [1, 1, 1]], dtype=bool)  # no corner cutting:
    >>> plan = GridPlanner(grid).shortest_path((0, 0), (0, 2))
    >>> round(plan.length, 6), plan.path.tolist()
    (6.0, [[0, 0], [1, 0], [2, 0], [2, 1], [2, 2], [1, 2], [0, 2]])
    """

    def __init__(self, free: Any) -> None:
        grid = np.asarray(free)
        if grid.ndim != 2 or grid.size == 0:
            raise InvalidArgumentError(
                f"free must be a non-empty 2-D grid of booleans; got shape {grid.shape}"
            )
        self.free: NDArray[np.bool_] = np.ascontiguousarray(grid.astype(bool))
        n = self.free.size
        self._g = np.empty(n)
        self._parent = np.empty(n, dtype=np.int64)
        self._stamp = np.zeros(n, dtype=np.int64)
        self._query = 0

    @property
    def shape(self) -> tuple[int, int]:
        """(height, width) of the grid."""
        h, w = self.free.shape
        return int(h), int(w)

    def _cell(self, value: Any, name: str) -> tuple[int, int]:
        h, w = self.shape
        try:
            x, y = (int(v) for v in value)
        except (TypeError, ValueError):
            raise InvalidArgumentError(
                f"{name} must be a cell (x, y) of ints; got {value!r}"
            ) from None
        if not (0 <= x < w and 0 <= y < h):
            raise InvalidQueryError(f"{name} cell ({x}, {y}) is outside the {w} x {h} grid")
        if not self.free[y, x]:
            raise InvalidQueryError(f"{name} cell ({x}, {y}) is blocked")
        return x, y

    def shortest_path(self, start: Any, goal: Any) -> Plan:
        """Shortest octile path between two free cells; ``Plan(None, inf)`` if none."""
        sx, sy = self._cell(start, "start")
        gx, gy = self._cell(goal, "goal")
        self._query += 1
        length = kernels.grid_astar(
            self.free, sx, sy, gx, gy, self._g, self._parent, self._stamp, self._query
        )
        if not math.isfinite(length):
            return Plan(None, math.inf)
        w = self.shape[1]
        cells = []
        v = gy * w + gx
        while v >= 0:
            cells.append((v % w, v // w))
            v = int(self._parent[v])
        return Plan(np.array(cells[::-1], dtype=np.int64), float(length))
