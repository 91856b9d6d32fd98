"""The clairvoyant bound: what is solvable at all, given the obstacles' whole future."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.bounds._kernels import spacetime_astar
from copi.core import Agent, Observation, Task, check_sensing
from copi.errors import InvalidArgumentError
from copi.planning import GoalField
from copi.planning.futures import compass_moves

__all__ = ["Clairvoyant"]


class Clairvoyant(Agent):
    """A bound, not a method: the share of episodes solvable at all (level ``future``).

    Told the whole future of every moving obstacle (:attr:`copi.core.Task.future`: the
    obstacles ignore the agent, so their future is the episode's own), it searches space
    and time at once: A* over (position, step) with 16 directions at full and half speed
    and waiting, states merged on cells of ``cell`` agent steps at one step, each move
    checked with the simulator's own tests of walls (it never plans a move a wall would
    stop) and of contacts (the closest approach over the step). Cost: steps; heuristic:
    ``weight`` times the distance to go around the walls (:class:`GoalField`). Its plan is
    then replayed through the simulator, which decides the outcome: a success is a real,
    contact-free episode.

    The search is not complete (a discrete set of moves, merged states, a budget of
    ``max_nodes``), so its success rate is a lower bound on the share solvable; its path
    length is no yardstick (paper §IV: an optimum known only in retrospect). Counters:
    ``planned`` (1 when a plan was found), ``nodes`` (search nodes) and ``budget`` (1
    when the budget ran out before a plan or a proof that none exists within the limit).

    Parameters
    ----------
    cell : float
        Side of the cells that merge states, agent steps.
    weight : float
        Weight of the heuristic (1: shortest in time; above: faster, maybe longer).
    max_nodes : int
        Search nodes at most.
    """

    name = "clairvoyant"
    sensing = "future"
    steers_itself = True

    def __init__(self, *, cell: float = 0.2, weight: float = 1.5, max_nodes: int = 400_000):
        if not (math.isfinite(cell) and cell > 0):
            raise InvalidArgumentError(f"cell must be a finite number > 0; got {cell!r}")
        if not (math.isfinite(weight) and weight >= 1):
            raise InvalidArgumentError(f"weight must be a finite number >= 1; got {weight!r}")
        if int(max_nodes) != max_nodes or not 1 <= max_nodes <= 10_000_000:
            raise InvalidArgumentError(
                f"max_nodes must be a whole number in 1 .. 10000000; got {max_nodes!r}"
            )
        self.cell = float(cell)
        self.weight = float(weight)
        self.max_nodes = int(max_nodes)
        self.moves, self.dirs = compass_moves()
        self._plan: list[NDArray[np.float64]] = []
        self._stats: dict[str, Any] = {}

    def reset(self, task: Task) -> None:
        check_sensing(task.sensing, self.sensing, method=self.name)
        if task.future is None or task.world is None or task.start is None or task.goal is None:
            raise InvalidArgumentError(
                "clairvoyant needs the obstacles' future, the world, start and goal (level "
                f"'future'); got a task at {task.sensing!r} without them"
            )
        self._plan = self.plan(task)

    def plan(self, task: Task) -> list[NDArray[np.float64]]:
        """The moves of the plan (empty when none was found); sets the counters."""
        assert task.world is not None and task.start is not None and task.goal is not None
        future = np.ascontiguousarray(task.future, dtype=np.float64)
        field = GoalField(task.world, task.goal, task.agent_radius)
        goal, n, _, _, parent, move = spacetime_astar(
            float(task.start[0]), float(task.start[1]), float(task.goal[0]),
            float(task.goal[1]), task.goal_tolerance, task.agent_radius,
            np.ascontiguousarray(task.world.segments), future, field.dist, field.x0,
            field.y0, field.h, self.moves, self.dirs, self.cell, self.weight, self.max_nodes,
        )  # fmt: skip
        self._stats = {"planned": int(goal >= 0), "nodes": int(n), "budget": int(goal == -2)}
        steps: list[NDArray[np.float64]] = []
        u = int(goal)
        while u > 0:
            steps.append(self.moves[move[u]].copy())
            u = int(parent[u])
        steps.reverse()
        return steps

    def act(self, obs: Observation) -> NDArray[np.float64]:
        if self._plan:
            return self._plan.pop(0)
        return np.zeros(2)

    def counters(self) -> dict[str, Any]:
        return dict(self._stats)
