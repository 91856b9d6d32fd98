"""Re-planning on the current snapshot: the planner that knows everything now and
nothing of what comes next (level ``oracle``)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from copi.baselines._common import unit
from copi.core import Agent, Observation, Task, check_sensing
from copi.errors import CopiError, InvalidArgumentError
from copi.geometry import move_discs
from copi.planning import shortest_path

__all__ = ["Replan"]



_PAD = 0.01
"""Added to the agent's radius when planning: the planner's circles are circumscribed
polygons whose edges touch the true circle, and a path along such an edge grazes a wall's
corner exactly, where the simulator stops the agent."""


class Replan(Agent):
    """Follow the shortest path on the current snapshot, the moving obstacles frozen and
    inflated by ``inflate``; re-plan every ``every`` steps and whenever the next stretch
    of the path (``lookahead`` steps) meets an inflated obstacle. Level ``oracle`` (it
    sees every obstacle's position, wherever it is); hand-written; ``inflate`` is tuned.

    A disc is inflated less when the agent or the goal is nearer to it than ``inflate``
    (just enough to leave them free); failing a plan, the obstacles are taken at their
    true size; failing that, the agent steps away from the nearest obstacle. Plans are
    made for the agent's disc grown by a hundredth of a step (a path must not graze a
    wall's corner, which would stop the agent there), or at its true size when it rests
    closer than that to a wall.

    Parameters
    ----------
    inflate : float
        Added to each obstacle's radius when planning, agent steps.
    every : int
        Steps between two plans at most.
    lookahead : float
        Length of path checked each step against the inflated obstacles.
    quad_segs : int
        Circles of the configuration space as polygons of 4 ``quad_segs`` sides.
    """

    name = "replan"
    sensing = "oracle"
    steers_itself = True

    def __init__(
        self, *, inflate: float = 1.0, every: int = 5, lookahead: float = 3.0, quad_segs: int = 2
    ) -> None:
        if not (math.isfinite(inflate) and inflate >= 0):
            raise InvalidArgumentError(f"inflate must be a finite number >= 0; got {inflate!r}")
        self.inflate = float(inflate)
        self.every = int(every)
        self.lookahead = float(lookahead)
        self.quad_segs = int(quad_segs)

    def reset(self, task: Task) -> None:
        check_sensing(task.sensing, self.sensing, method=self.name)
        if task.world is None or task.goal is None:
            raise InvalidArgumentError(
                f"replan needs the task's world and goal (level 'oracle'); got a task at "
                f"{task.sensing!r} without them"
            )
        self.task = task
        self.world = task.world
        self.goal = np.asarray(task.goal, dtype=np.float64)
        self.path: NDArray[np.float64] | None = None
        self.age = 0
        self.plans = 0

    def _plan(self, p: NDArray[np.float64], obstacles: NDArray[np.float64]) -> None:
        self.plans += 1
        self.age = 0
        r = self.task.agent_radius
        centers, radii = obstacles[:, :2], obstacles[:, 4]
        # Each disc is inflated by `inflate`, but never so much that it swallows the agent
        # or the goal (dropping the inflation then planned a path that skims the disc).
        room = np.minimum(
            np.hypot(*(centers - p).T), np.hypot(*(centers - self.goal).T)
        ) - radii - r - _PAD - 0.01
        inflated = np.clip(room, 0.0, self.inflate)
        for grow, pad in ((inflated, _PAD), (0.0, _PAD), (0.0, 0.0)):
            try:
                plan = shortest_path(
                    self.world, p, self.goal, radius=r + pad, centers=centers,
                    radii=radii + grow, quad_segs=self.quad_segs,
                )  # fmt: skip
            except CopiError:
                continue
            if plan.path is not None:
                self.path = plan.path[1:]
                return
        self.path = None

    def _blocked(self, p: NDArray[np.float64], obstacles: NDArray[np.float64]) -> bool:
        """Whether the next ``lookahead`` of the path meets an inflated obstacle."""
        if self.path is None or not len(obstacles):
            return self.path is None
        pts = [p]
        left = self.lookahead
        for q in self.path:
            seg = math.dist(pts[-1], q)
            if seg >= left:
                u, _ = unit(q - pts[-1])
                pts.append(pts[-1] + u * left)
                break
            pts.append(q)
            left -= seg
        a = np.asarray(pts[:-1])
        b = np.asarray(pts[1:])
        if not len(a):
            return False
        c = obstacles[:, :2]
        ab = b - a
        L2 = np.maximum((ab * ab).sum(1), 1e-12)
        t = np.clip(((c[:, None, :] - a[None]) * ab[None]).sum(-1) / L2[None], 0, 1)
        d = np.hypot(*(c[:, None, :] - a[None] - t[..., None] * ab[None]).transpose(2, 0, 1))
        need = obstacles[:, 4] + self.task.agent_radius + 0.5 * self.inflate
        return bool((d.min(1) < need).any())

    def act(self, obs: Observation) -> NDArray[np.float64]:
        assert obs.position is not None and obs.obstacles is not None
        p = np.asarray(obs.position, dtype=np.float64)
        self.age += 1
        if self.path is None or self.age >= self.every or self._blocked(p, obs.obstacles):
            self._plan(p, obs.obstacles)
        if self.path is None:
            if not len(obs.obstacles):
                return np.zeros(2)
            d = p[None] - obs.obstacles[:, :2]
            k = int(np.argmin(np.hypot(*d.T) - obs.obstacles[:, 4]))
            away, _ = unit(d[k])
            return away
        # One step along the path (past vertices nearer than a step: a path round a
        # disc's polygon has vertices a hair apart, and stopping at each one crawled
        # while the disc came on), unless that chord would run into a wall (it can clip
        # a corner the path turns round): then to the next vertex.
        left = 1.0
        here = p
        target = self.path[-1]
        passed = len(self.path) - 1
        for i, q in enumerate(self.path):
            seg = math.dist(here, q)
            if seg >= left:
                u, _ = unit(q - here)
                target = here + u * left
                passed = i
                break
            left -= seg
            here = q
        _, blocked = move_discs(p, target - p, self.world.segments, self.task.agent_radius)
        if bool(np.asarray(blocked).any()) and passed > 0:
            u, dist = unit(self.path[0] - p)
            target = p + u * min(1.0, dist)
            passed = 0 if dist > 1.0 else min(1, len(self.path) - 1)
        self.path = self.path[passed:]  # the vertices before the target are behind
        v = target - p
        n = math.hypot(v[0], v[1])
        return v / n if n > 1.0 else v
