"""What an agent is told, and the one protocol every navigating method answers.

The benchmark compares copi with methods that know more or less than it does, so what a
method knows is explicit. Each episode runs at one *sensing level*, and the runner hands
the method only what that level contains:

========  ==========================================================================
level     what the method receives
========  ==========================================================================
sensor    the ring of ranges and the goal's position relative to the agent
map       plus the static world (and so the agent's position in it, the static route,
          and the reading the static map alone would give, which tells walls apart
          from moving obstacles)
oracle    plus every moving obstacle's position, radius and velocity
========  ==========================================================================

A method declares the least level it needs (:attr:`Agent.sensing`); asking it to run
below that is an error, and at a higher level it is still handed that level's
information (it may ignore part of it, as a method of level ``sensor`` does at ``map``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from copi.errors import InvalidArgumentError
from copi.learning import Capabilities
from copi.online._controller import ContextController, Decision
from copi.online._mapping import Mapping
from copi.online._strategies import Route
from copi.world import World

__all__ = [
    "SENSING_LEVELS",
    "SENSOR_STRATEGIES",
    "Agent",
    "CopiAgent",
    "Observation",
    "Steering",
    "Task",
    "check_sensing",
    "check_strategy",
]

SENSING_LEVELS = ("sensor", "map", "oracle")
"""The sensing levels, from least to most informed."""


SENSOR_STRATEGIES = ("greedy", "mapping", "causal")
"""Global strategies at level ``sensor`` (levels with a map follow the static route):
head for the goal, map as it goes (:class:`Mapping`), or map and learn a causal map of
the world from experience (:class:`~copi.online.CausalStrategy`, lifelong runs)."""


def check_strategy(name: str) -> str:
    """``name`` if it is a sensor-level strategy; otherwise one clear error."""
    if name not in SENSOR_STRATEGIES:
        raise InvalidArgumentError(
            f"sensor strategy must be one of {', '.join(SENSOR_STRATEGIES)}; got {name!r}"
        )
    return name


def check_sensing(level: str, needs: str | None = None, *, method: str = "method") -> int:
    """The rank of ``level`` (0, 1, 2); refuses an unknown level, or one below ``needs``."""
    if level not in SENSING_LEVELS:
        raise InvalidArgumentError(
            f"sensing level must be one of {', '.join(SENSING_LEVELS)}; got {level!r}"
        )
    rank = SENSING_LEVELS.index(level)
    if needs is not None and rank < check_sensing(needs):
        raise InvalidArgumentError(
            f"{method} needs sensing level {needs!r} or above; asked to run at {level!r}"
        )
    return rank


@dataclass(frozen=True)
class Task:
    """What an agent is told when an episode starts, restricted to its sensing level."""

    sensing: str
    """The level the episode runs at."""
    agent_radius: float
    """Radius of the agent's disc, agent steps."""
    goal_tolerance: float
    """The goal is reached when the agent's centre is this close to it."""
    n_rays: int
    """Rays of the range ring (ray i at angle 2 pi i / n_rays from +x)."""
    max_range: float
    """Readings are clipped to this range."""
    world: World | None = None
    """The static world (levels ``map`` and ``oracle``; None at ``sensor``)."""
    start: NDArray[np.float64] | None = None
    """The start in the world's frame (``map`` and ``oracle``)."""
    goal: NDArray[np.float64] | None = None
    """The goal in the world's frame (``map`` and ``oracle``)."""
    strategy: str = "greedy"
    """The global strategy at level ``sensor``: "greedy" (head for the goal),
    "mapping" (map as it goes, :class:`Mapping`) or "causal" (map, and learn from
    experience which moves work where, :class:`~copi.online.CausalStrategy`). Levels
    with a map follow the route."""
    lifelong: bool = False
    """The agent lives on in this world: tasks follow one another, each observation's
    ``odometry`` places it in one frame for its whole life, and a method may keep what
    it learnt (a map, a causal map) from one task to the next (Experiment 3)."""


@dataclass(frozen=True)
class Observation:
    """What an agent perceives at one step, restricted to its sensing level."""

    ranges: NDArray[np.float64]
    """The range reading, shape (n_rays,), agent steps (every level)."""
    goal: NDArray[np.float64]
    """The goal relative to the agent, shape (2,) (every level)."""
    position: NDArray[np.float64] | None = None
    """The agent's position in the world's frame (``map``, ``oracle``)."""
    static: NDArray[np.float64] | None = None
    """The reading the static world alone would give here (``map``, ``oracle``)."""
    obstacles: NDArray[np.float64] | None = None
    """Moving obstacles as rows (x, y, vx, vy, radius), velocities in steps per step,
    measured over the last step (``oracle``)."""
    odometry: NDArray[np.float64] | None = None
    """The agent's position relative to where its life in this world began (lifelong
    runs, every level; None otherwise): what its own motion tells it, not a map."""


class Agent(Protocol):
    """A navigating method: told the task, then asked for a velocity each step."""

    name: str
    """The method's name in results (e.g. ``copi-extended``, ``dwa``)."""
    sensing: str
    """The least sensing level the method needs."""

    def reset(self, task: Task) -> None:
        """Start an episode."""

    def act(self, obs: Observation) -> NDArray[np.float64]:
        """The velocity for this step, shape (2,), norm at most 1."""
        ...


class Steering:
    """The global half shared by copi's modes and the local baselines: where to go.

    At level ``map`` and above it follows the static route (:class:`Route`, the shortest
    path on the static world, replanned when the agent loses sight of it); at ``sensor``
    it heads for the goal (the relative goal), or with ``Task.strategy == "mapping"``
    follows a map it builds from the ranges (:class:`Mapping`), or with ``"causal"``
    also learns from its own experience which moves work where
    (:class:`~copi.online.CausalStrategy`). So every method at one level gets the same
    global direction, and only its local behaviour differs.

    In a lifelong run (``Task.lifelong``) the map and the causal map are kept from one
    task to the next, in the frame of the agent's odometry, and the walls learnt on the
    map stand in for the static reading a ``map``-level method is handed
    (:meth:`observe`, :meth:`Mapping.static_reading`): what the agent's life taught it.
    """

    def __init__(self) -> None:
        self.route: Route | None = None
        self.mapping: Mapping | None = None
        self.causal: Any = None
        self.lifelong = False
        self._learnt_static: NDArray[np.float64] | None = None

    def reset(self, task: Task) -> None:
        from copi.online._causal import CausalStrategy

        self.route = None
        self.lifelong = task.lifelong
        self._learnt_static = None
        if task.world is not None and task.start is not None and task.goal is not None:
            self.mapping = self.causal = None
            self.route = Route()
            self.route.reset(task.world, task.start, task.goal, task.agent_radius)
            return
        kind = check_strategy(task.strategy)
        keep = task.lifelong
        if kind == "mapping":
            self.causal = None
            if self.mapping is None or not keep:
                self.mapping = Mapping()
            self.mapping.reset(task.n_rays, task.max_range, task.agent_radius, keep=keep)
        elif kind == "causal":
            self.mapping = None
            if self.causal is None or not keep:
                self.causal = CausalStrategy()
            self.causal.reset(task)
        else:
            self.mapping = self.causal = None

    def aim(self, obs: Observation, context: int = -1) -> tuple[NDArray[np.float64], float]:
        """(desired direction, distance to the point aimed at); ``context``: the local
        context the agent recognised last (a template index; -1 when it has none), which
        the causal strategy records its experience under."""
        if self.route is not None and obs.position is not None:
            return self.route.aim(obs.position)
        if self.causal is not None:
            out: tuple[NDArray[np.float64], float] = self.causal.aim(obs, context)
            grid = self.causal.mapping
        elif self.mapping is not None:
            out = self.mapping.aim(obs.ranges, obs.goal, obs.odometry)
            grid = self.mapping
        else:
            g = obs.goal
            return np.asarray(g, dtype=np.float64), math.hypot(g[0], g[1])
        if self.lifelong and obs.static is None:
            here = -np.asarray(obs.goal) if obs.odometry is None else obs.odometry
            self._learnt_static = grid.static_reading(here)
        return out

    def observe(self, obs: Observation) -> Observation:
        """``obs``, with the static reading of the walls learnt in a lifelong run where the
        level gives none (call after :meth:`aim`, which folds the reading in first)."""
        if obs.static is not None or self._learnt_static is None:
            return obs
        return dataclasses.replace(obs, static=self._learnt_static)

    def finish(self, outcome: str) -> None:
        """Tell the strategy how the task ended ("success", "collision", "timeout")."""
        if self.causal is not None:
            self.causal.finish(outcome)


class CopiAgent:
    """copi's online chain (:class:`ContextController`) as an :class:`Agent`.

    The context chain picks among the template's policies; :class:`Steering` gives the
    global direction. With a guard, the static reading (level ``map`` and above) tells
    the guard which hits are walls; at ``sensor`` every hit counts as a hazard.

    Parameters
    ----------
    capabilities : Capabilities
    name : str
    guard : float
        See :class:`ContextController`.
    continual : bool
        Grow contexts for unfamiliar readings (see :class:`ContextController`).
    explain : bool
        Keep each step's :class:`Decision` in :attr:`last_decision` (slower).
    """

    sensing = "sensor"

    def __init__(
        self,
        capabilities: Capabilities,
        *,
        name: str = "copi",
        guard: float = 0.0,
        continual: bool = False,
        explain: bool = False,
    ) -> None:
        self.capabilities = capabilities
        self.name = name
        self.guard = guard
        self.continual = continual
        self.explain = explain
        self.last_decision: Decision | None = None
        self.steering = Steering()
        self.controller = ContextController(capabilities, guard=guard, continual=continual)

    def reset(self, task: Task) -> None:
        if task.n_rays != self.capabilities.n_rays:
            raise InvalidArgumentError(
                f"the capabilities were learnt for {self.capabilities.n_rays} rays; "
                f"the sensor has {task.n_rays}"
            )
        self.controller = ContextController(
            self.capabilities, guard=self.guard, continual=self.continual
        )
        self.steering.reset(task)

    def act(self, obs: Observation) -> NDArray[np.float64]:
        desired, reach = self.steering.aim(obs)
        obs = self.steering.observe(obs)
        static = obs.static if self.guard > 0 else None
        action, self.last_decision = self.controller.decide(
            obs.ranges, desired, reach=reach, static=static, explain=self.explain
        )
        return action

    def finish(self, outcome: str) -> None:
        """The task ended (``outcome``): tells the global strategy."""
        self.steering.finish(outcome)

    def counters(self) -> dict[str, Any]:
        """Per-episode diagnostics stored with the result."""
        return {"unfamiliar": self.controller.unfamiliar_rate}
