"""The global half every method at one level shares (:class:`Steering`), and copi's
online chain as an :class:`~copi.core.Agent` (:class:`CopiAgent`)."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.core import Agent, Observation, Task, check_strategy
from copi.errors import InvalidArgumentError
from copi.learning import Capabilities
from copi.online._controller import ContextController, Decision
from copi.online._mapping import Mapping
from copi.online._strategies import Route

__all__ = ["CopiAgent", "Steering"]


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


class CopiAgent(Agent):
    """copi's online chain (:class:`ContextController`) as an :class:`~copi.core.Agent`.

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
    steers_itself = True

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
