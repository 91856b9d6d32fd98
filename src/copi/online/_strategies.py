"""Global strategies: where the agent wants to go, separate from how it gets through its
local context (paper §III: the global task as "a game against an abstract adversary",
factored from "more local aspects of non-stationarity")."""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np
import shapely
import shapely.ops
from numpy.typing import NDArray

from copi.errors import InvalidArgumentError
from copi.planning import VisibilityGraph, configuration_space, length_error_bound
from copi.planning.kernels import point_free, segment_free
from copi.world import World

__all__ = ["GlobalStrategy", "Greedy", "Route", "make_strategy"]


class GlobalStrategy(Protocol):
    """Chooses, each step, the direction the agent should make progress in."""

    name: str

    def reset(self, world: World, start: Any, goal: Any, agent_radius: float) -> None:
        """Start a new task."""

    def aim(self, position: Any) -> tuple[NDArray[np.float64], float]:
        """(desired direction, distance to the point aimed at) from ``position``."""
        ...


class Greedy:
    """Knows only where the goal is: always head straight for it."""

    name = "greedy"

    def reset(self, world: World, start: Any, goal: Any, agent_radius: float) -> None:
        self.goal = np.asarray(goal, dtype=np.float64)

    def aim(self, position: Any) -> tuple[NDArray[np.float64], float]:
        d = self.goal - np.asarray(position, dtype=np.float64)
        return d, math.hypot(d[0], d[1])


class Route:
    """Knows the static world, not the moving obstacles: follows the shortest route on
    the static world (the visibility graph of its configuration space).

    It aims at the farthest waypoint of the route it can see from where it is (a
    shortcut never crosses a wall), and replans from its position when it can see none
    (the local policies took it off the route).
    """

    name = "route"

    def __init__(self, *, quad_segs: int = 4) -> None:
        self.quad_segs = quad_segs

    def reset(self, world: World, start: Any, goal: Any, agent_radius: float) -> None:
        self.goal = np.asarray(goal, dtype=np.float64)
        cspace = configuration_space(world, radius=agent_radius, quad_segs=self.quad_segs)
        self.graph = VisibilityGraph.from_geometry(cspace)
        self.snap = agent_radius * length_error_bound(self.quad_segs) + 1e-6
        self.replans = 0
        self._plan(np.asarray(start, dtype=np.float64))

    def _plan(self, position: NDArray[np.float64]) -> None:
        try:
            plan = self.graph.shortest_path(position, self.goal, snap=max(self.snap, 0.05))
        except Exception:  # off the static free space (pushed by numerics): go straight
            plan = None
        if plan is None or plan.path is None:
            self.waypoints = np.array([self.goal])
        else:
            pts = plan.path[1:]
            far = np.hypot(*(pts - position).T) > 1e-6
            far[-1] = True  # the goal stays
            self.waypoints = pts[far]
        self.next = 0

    def _sees(self, p: NDArray[np.float64], q: NDArray[np.float64]) -> bool:
        g = self.graph
        return bool(segment_free(p[0], p[1], q[0], q[1], g.xy, g.starts, g.eps, g.pins))

    def _inside(self, p: NDArray[np.float64]) -> NDArray[np.float64]:
        """p itself, or its nearest point of the (polygonal) free space when p lies in the
        thin band between it and the true one (a disc resting against a wall)."""
        g = self.graph
        if point_free(p[0], p[1], g.xy, g.starts, g.eps):
            return p
        near = shapely.ops.nearest_points(g.geometry, shapely.Point(p))[0]
        return np.array([near.x, near.y])

    def aim(self, position: Any) -> tuple[NDArray[np.float64], float]:
        p = np.asarray(position, dtype=np.float64)
        q = self._inside(p)
        w = self.waypoints
        # Look ahead along the route for the farthest waypoint in sight.
        while self.next + 1 < len(w) and self._sees(q, w[self.next + 1]):
            self.next += 1
        if not self._sees(q, w[self.next]):
            self.replans += 1
            self._plan(q)
            w = self.waypoints
        # A waypoint already reached (within a hair) is passed.
        while self.next + 1 < len(w) and math.dist(p, w[self.next]) < 1e-3:
            self.next += 1
        d = w[self.next] - p
        return d, math.hypot(d[0], d[1])


def make_strategy(name: str) -> GlobalStrategy:
    """A strategy by name: "route" or "greedy"."""
    if name == "route":
        return Route()
    if name == "greedy":
        return Greedy()
    raise InvalidArgumentError(f"strategy must be 'route' or 'greedy'; got {name!r}")
