"""The interface every navigating method answers, and what it is told.

copi's own modes, the baselines, navground's peers and any method a user adds are
:class:`Agent` subclasses: told the :class:`Task` when an episode starts, asked for a
velocity each step given an :class:`Observation`, and told how the episode ended. The
runner (:func:`copi.experiments.run_episode`) never asks which kind it drives.

What a method knows is explicit. Each episode runs at one *sensing level*, and the
runner hands the method only what that level contains:

========  ==========================================================================
level     what the method receives
========  ==========================================================================
sensor    the ring of ranges, the goal's position relative to the agent, and the
          global direction toward it (or along the map the agent builds, with the
          ``mapping`` and ``causal`` strategies)
map       plus the static world (and so the agent's position in it, the global
          direction along the static route, and the reading the static map alone
          would give, which tells walls apart from moving obstacles)
oracle    plus every moving obstacle's position, radius and velocity
future    plus the whole future of every moving obstacle (they ignore the agent, so
          it is recorded before the episode): only for the clairvoyant *bound*
========  ==========================================================================

A method declares the least level it needs (:attr:`Agent.sensing`); asking it to run
below that is an error, and at a higher level it is still handed that level's
information (it may ignore part of it, as a method of level ``sensor`` does at ``map``).

This module depends on nothing else of copi but its errors, so that a method written
elsewhere imports only it (and :mod:`copi.world` for the worlds it is told).

Examples
--------
>>> import numpy as np
>>> class Eastward(Agent):
...     name = "eastward"
...     def reset(self, task): pass
...     def act(self, obs): return np.array([1.0, 0.0])
>>> a = Eastward()
>>> a.act(None), a.counters(), a.sensing
(array([1., 0.]), {}, 'sensor')
"""

from __future__ import annotations

import abc
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal, get_args

import numpy as np
from numpy.typing import NDArray

from copi.errors import InvalidArgumentError

if TYPE_CHECKING:  # the interface needs the type only
    from copi.world import World

__all__ = [
    "Agent",
    "EXPLAINED",
    "OUTCOMES",
    "Observation",
    "Outcome",
    "SENSING_LEVELS",
    "SENSOR_STRATEGIES",
    "Sensing",
    "Task",
    "check_sensing",
    "check_strategy",
]

Sensing = Literal["sensor", "map", "oracle", "future"]
"""A sensing level (see the module)."""

SENSING_LEVELS: tuple[Sensing, ...] = get_args(Sensing)
"""The sensing levels, from least to most informed."""

Outcome = Literal["success", "collision", "timeout", "unreachable"]
"""How an episode ended: the goal reached without touching a moving obstacle; a contact
with one; out of steps; or a goal the agent's disc cannot reach at all (no path on the
static world for its radius: the episode is not run, and counts in no rate)."""

OUTCOMES: tuple[Outcome, ...] = get_args(Outcome)

EXPLAINED = 0.05
"""A hit of :attr:`Observation.ranges` within this of :attr:`Observation.static` is the
static map's (a wall); a nearer one is something that moves. The one tolerance of every
method that tells the two apart (copi's guards and safety features, tracked-mpc)."""

SENSOR_STRATEGIES = ("greedy", "mapping", "causal")
"""Global strategies at level ``sensor`` (levels with a map follow the static route):
head for the goal, map as it goes (:class:`copi.online.Mapping`), or map and learn a
causal map of the world from experience (:class:`copi.online.CausalStrategy`)."""


def check_strategy(name: str) -> str:
    """``name`` if it is a sensor-level strategy; otherwise one clear error."""
    if name not in SENSOR_STRATEGIES:
        raise InvalidArgumentError(
            f"sensor strategy must be one of {', '.join(SENSOR_STRATEGIES)}; got {name!r}"
        )
    return name


def check_sensing(level: str, needs: str | None = None, *, method: str = "method") -> int:
    """The rank of ``level`` (0, 1, 2, 3); refuses an unknown level, or one below ``needs``.

    Examples
    --------
    >>> check_sensing("map"), check_sensing("oracle", "map")
    (1, 2)
    >>> try:
    ...     check_sensing("sensor", "oracle", method="replan")
    ... except InvalidArgumentError as err:
    ...     print(err)
    replan needs sensing level 'oracle' or above; asked to run at 'sensor'
    """
    if level not in SENSING_LEVELS:
        raise InvalidArgumentError(
            f"sensing level must be one of {', '.join(SENSING_LEVELS)}; got {level!r}"
        )
    rank = SENSING_LEVELS.index(level)  # type: ignore[arg-type]
    if needs is not None and rank < check_sensing(needs):
        raise InvalidArgumentError(
            f"{method} needs sensing level {needs!r} or above; asked to run at {level!r}"
        )
    return rank


@dataclass(frozen=True)
class Task:
    """What an agent is told when an episode starts, restricted to its sensing level."""

    sensing: Sensing
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
    "mapping" (map as it goes) or "causal" (map, and learn from experience which moves
    work where). Levels with a map follow the route."""
    future: NDArray[np.float64] | None = None
    """Level ``future`` only: ``future[t, k] = (x, y, radius)`` of moving obstacle k at
    step t, for t = 0 .. the episode's step limit. A bound's knowledge, never a method's:
    the obstacles' random walk draws the same numbers whatever the agent does, so the
    future is the episode's own."""
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
    direction: NDArray[np.float64] | None = None
    """The level's global direction, shape (2,), a unit vector in the world's axes (or
    zero at the goal): along the static route at ``map`` and above (the shortest path
    on the static world for the agent's radius, replanned when the agent loses sight of
    it), toward the goal at ``sensor`` (along the map the agent builds as it goes with
    the ``mapping`` and ``causal`` strategies). Every level; handed to a method that does
    not find its own (:attr:`Agent.steers_itself` False), so that any method follows
    the same route as copi's own; None for one that does."""
    reach: float = math.inf
    """How far ahead along :attr:`direction` the point aimed at lies, agent steps (the
    next corner of the route, or the goal): a method may slow down to stop there."""


class Agent(abc.ABC):
    """A navigating method: told the task, then asked for a velocity each step.

    Subclasses set :attr:`name` and :attr:`sensing` and implement :meth:`reset` and
    :meth:`act`; :meth:`finish` and :meth:`counters` are optional (no-ops here). A new
    method is one such class plus one :func:`copi.experiments.register_method` call;
    :func:`copi.testing.check_agent` checks it keeps the contract.
    """

    name: str = "agent"
    """The method's name in results (e.g. ``copi-learnt``, ``dwa``)."""
    sensing: Sensing = "sensor"
    """The least sensing level the method needs."""
    steers_itself: bool = False
    """The method finds its own global direction (copi's methods and baselines do,
    through :class:`copi.online.Steering`); when False, the runner finds it and hands it
    over as :attr:`Observation.direction` each step, its cost counted in the decision's
    time."""

    @abc.abstractmethod
    def reset(self, task: Task) -> None:
        """Start an episode (in a lifelong run, a new task in the same world)."""

    @abc.abstractmethod
    def act(self, obs: Observation) -> NDArray[np.float64]:
        """The velocity for this step: shape (2,), finite, norm at most 1 (one agent
        step per time step)."""

    def finish(self, outcome: str) -> None:  # noqa: B027 - optional, a no-op by default
        """The episode ended with ``outcome`` ("success", "collision", "timeout")."""

    def counters(self) -> dict[str, Any]:
        """Per-episode diagnostics stored with the result (numbers by name)."""
        return {}
