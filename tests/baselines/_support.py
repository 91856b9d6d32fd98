"""Episodes the baseline tests share: a simulator that counts steps stopped by a wall, a
spy that records what a method is told, and the standard episodes (empty room, wall,
trap, head-on)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.core import Agent, Observation, Task
from copi.methods import make_agent
from copi.planning import shortest_path
from copi.runs import EpisodeOutcome, run_episode
from copi.world import Simulator, StepResult, World
from tests.common import SQUARE_ROOM

LOCAL = ("straight", "compass-guard", "vfh", "dwa", "tangent-bug")
"""The methods of level ``sensor``."""

TRAP_GOAL = (20.0, 2.0)
"""Below U_TRAP's U: from its start inside the U, the straight line to it ends against
the U's bottom, and the way round is out of the U's mouth, at the other end."""

EMPTY_PAIRS = [
    ((3, 3), (17, 15)),
    ((10, 2), (10, 18)),
    ((18, 2), (2, 18)),
    ((10, 10), (10, 19)),  # the goal a step from a wall
    ((2, 2), (18.5, 18.5)),  # the goal in a corner
]
"""(start, goal) pairs in SQUARE_ROOM."""


class WallCounter(Simulator):
    """A :class:`Simulator` that counts the steps a wall stopped (commanded into a wall)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.blocked = 0

    def step(self, action: Any) -> StepResult:
        res = super().step(action)
        self.blocked += res.blocked
        return res


class Spy(Agent):
    """Wraps an agent and records the task and every observation it is handed."""

    def __init__(self, agent: Agent) -> None:
        self.agent = agent
        self.name = agent.name
        self.sensing = agent.sensing
        self.tasks: list[Task] = []
        self.observations: list[Observation] = []

    def reset(self, task: Task) -> None:
        self.tasks.append(task)
        self.agent.reset(task)

    def act(self, obs: Observation) -> NDArray[np.float64]:
        self.observations.append(obs)
        return self.agent.act(obs)

    def finish(self, outcome: str) -> None:
        self.agent.finish(outcome)

    def counters(self) -> dict[str, Any]:
        return self.agent.counters()


def empty(start: Any, goal: Any, world: World = SQUARE_ROOM) -> WallCounter:
    """An episode with no moving obstacle."""
    return WallCounter(world, start, goal, np.zeros((0, 2)), [], seed=0)


def head_on(x: float = 12.0, y: float = 10.0, *, radius: float = 0.75, speed: float = 0.6
            ) -> WallCounter:  # fmt: skip
    """From (3, 10) to (17, 10) in SQUARE_ROOM, one disc at (x, y) moving straight at the
    agent (heading -x, no turning) at ``speed``."""
    sim = WallCounter(SQUARE_ROOM, [3, 10], [17, 10], [[x, y]], [radius], seed=0, speed=speed,
                      turn_sd=0.0)  # fmt: skip
    sim.headings[:] = math.pi
    return sim


def route_length(world: World, start: Any, goal: Any) -> float:
    """The shortest path's length for the agent's disc on the static world."""
    return float(shortest_path(world, start, goal, radius=0.3).length)


def run(name: str, sim: Simulator, level: str, max_steps: int, **params: Any) -> EpisodeOutcome:
    """A fresh ``name`` agent run in ``sim`` at ``level``."""
    return run_episode(make_agent(name, **params), sim, sensing=level, max_steps=max_steps)


__all__ = [
    "EMPTY_PAIRS",
    "LOCAL",
    "TRAP_GOAL",
    "Spy",
    "WallCounter",
    "empty",
    "head_on",
    "route_length",
    "run",
]
