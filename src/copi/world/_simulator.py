"""One episode of the dynamic navigation domain: a world, moving obstacles, an agent."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from copi._rng import Seed, as_generator
from copi._validation import FloatArray, as_vector, positive
from copi.errors import InvalidArgumentError
from copi.geometry.kernels import step_agent, step_world
from copi.world._generate import place_obstacles, sample_free, sample_start_goal
from copi.world._reactive import ReactiveCrowd
from copi.world._sensor import RangeSensor
from copi.world._world import ObstacleSpec, World

__all__ = ["Simulator", "StepResult"]

# Headings tried, in order, by an obstacle whose random-walk move would touch a wall.
_RETRIES = 4


@dataclass(frozen=True)
class StepResult:
    """What happened in one time step."""

    blocked: bool
    """A wall stopped the agent short of its commanded move."""
    contact: bool
    """The agent touched a moving obstacle during the step (a collision)."""
    min_gap: float
    """Least surface-to-surface distance to any moving obstacle over the step."""
    reached: bool
    """The agent's centre ended within the goal tolerance."""
    distance: float
    """Straight-line distance from the agent's centre to the goal after the step."""


class Simulator:
    """Mutable state of one episode of the paper's navigation domain (§IV).

    The agent is a holonomic disc that moves at most 1 agent step per time step; walls
    stop it, exactly (it never passes through one). Moving obstacles are discs doing a
    correlated random walk at ``speed``: each step the heading turns by N(0, turn_sd);
    if the move would touch a wall, up to four uniformly random headings are tried, and
    if all fail the obstacle waits. Obstacles ignore the agent and each other; touching
    the agent is a contact, reported, never prevented.

    Use :meth:`from_world` to draw a task; the constructor only stores a given state.

    Parameters
    ----------
    world : World
    start, goal : array_like of shape (2,)
    centers, radii : array_like of shape (d, 2) and (d,)
        The moving obstacles.
    seed : int or Generator
        Drives the obstacles' random walk.
    agent_radius : float
    sensor : RangeSensor
    speed : float
        Obstacle speed per step, in agent steps.
    turn_sd : float
        Standard deviation of an obstacle's heading change per step, in radians.
    goal_tolerance : float
        The goal is reached when the centre ends a step within this distance of it.
    record : bool
        Keep the agent's path and the obstacles' traces (for pictures).
    crowd : ObstacleSpec, optional
        A crowd behaviour the obstacles follow instead of the random walk
        (:class:`~copi.world.ReactiveCrowd`), toward ``crowd_goals`` (one per obstacle).
    """

    def __init__(
        self,
        world: World,
        start: Any,
        goal: Any,
        centers: Any,
        radii: Any,
        *,
        seed: Seed = None,
        agent_radius: float = 0.3,
        sensor: RangeSensor | None = None,
        speed: float = 0.6,
        turn_sd: float = 0.6,
        goal_tolerance: float = 0.5,
        record: bool = False,
        crowd: ObstacleSpec | None = None,
        crowd_goals: Any = None,
    ) -> None:
        self.world = world
        self.sensor = sensor or RangeSensor()
        self.rng = as_generator(seed)
        self.agent_radius = positive(agent_radius, "agent_radius")
        self.speed = float(speed)
        self.turn_sd = float(turn_sd)
        self.goal_tolerance = float(goal_tolerance)
        self.goal = as_vector(goal, "goal", length=2).copy()
        self.position = as_vector(start, "start", length=2).copy()
        self.centers = np.array(centers, dtype=np.float64).reshape(-1, 2)
        self.radii = np.ascontiguousarray(np.array(radii, dtype=np.float64).reshape(-1))
        if self.radii.shape[0] != self.centers.shape[0]:
            raise InvalidArgumentError(
                f"radii must have one entry per obstacle ({self.centers.shape[0]}); "
                f"got {self.radii.shape[0]}"
            )
        self.headings = self.rng.uniform(0, 2 * np.pi, size=self.radii.shape[0])
        self.crowd: ReactiveCrowd | None = None
        if crowd is not None and crowd.reactive:
            goals = np.asarray(crowd_goals, dtype=np.float64).reshape(-1, 2)
            if goals.shape != self.centers.shape:
                raise InvalidArgumentError(f"crowd_goals must be one per obstacle "
                                           f"({len(self.centers)}); got {goals.shape}")  # fmt: skip
            self.crowd = ReactiveCrowd(world, crowd, self.centers, self.radii, goals,
                                       self.agent_radius)  # fmt: skip
        self.t = 0
        self.ranges = self.sensor.scan(world, self.position, self.centers, self.radii)
        self.record = record
        self.path: list[FloatArray] = [self.position.copy()] if record else []
        self.traces: list[FloatArray] = [self.centers.copy()] if record else []
        self._action = np.zeros(2)

    @classmethod
    def from_world(
        cls,
        world: World,
        seed: Seed = None,
        *,
        agent_radius: float = 0.3,
        sensor: RangeSensor | None = None,
        obstacles: ObstacleSpec | None = None,
        min_distance: float = 10.0,
        **kwargs: Any,
    ) -> Simulator:
        """Draw a task in ``world``: start and goal (unless the world fixes them), then the
        moving obstacles (``obstacles``, else the world's spec, else the paper's), all from
        ``seed``. Obstacles start clear of the agent and of the goal by at least one agent
        step (so that the snapshot at t = 0 has the goal free)."""
        agent_radius = positive(agent_radius, "agent_radius")
        rng = as_generator(seed)
        start, goal = sample_start_goal(world, rng, radius=agent_radius, min_distance=min_distance)
        spec = obstacles or world.obstacles or ObstacleSpec()
        if spec.positions is not None:  # the world places them itself
            centers = np.array(spec.positions, dtype=np.float64)
            radii = rng.uniform(spec.radius[0], spec.radius[1], size=len(centers))
        else:
            centers, radii = place_obstacles(
                world,
                rng,
                spec=spec,
                keep_clear=np.vstack([start, goal]),
                keep_clear_radius=agent_radius + 1.0,
            )
        goals = None
        if spec.reactive:
            drawn = [sample_free(world, rng, r) for r in radii] if spec.goals is None else None
            goals = np.array(spec.goals if drawn is None else drawn, dtype=np.float64)
        return cls(
            world,
            start,
            goal,
            centers,
            radii,
            seed=rng,
            agent_radius=agent_radius,
            sensor=sensor,
            speed=spec.speed,
            crowd=spec if spec.reactive else None,
            crowd_goals=goals,
            **kwargs,
        )

    @property
    def distance(self) -> float:
        """Straight-line distance from the agent's centre to the goal."""
        return math.hypot(self.goal[0] - self.position[0], self.goal[1] - self.position[1])

    def step(self, action: Any) -> StepResult:
        """Advance one time step with the agent's velocity ``action`` (clipped to norm 1).

        Obstacles move first in the sense of drawing their random walk, but both move over
        the same unit of time: contact is tested on the closest approach of the two linear
        motions, then the sensor reads from the agent's new position (``self.ranges``).
        """
        a = self._action
        try:
            a[0] = action[0]
            a[1] = action[1]
        except (TypeError, ValueError, IndexError):
            raise InvalidArgumentError(
                f"action must be a velocity of shape (2,); got {action!r}"
            ) from None
        norm = math.hypot(a[0], a[1])
        if not math.isfinite(norm):
            raise InvalidArgumentError(f"action must be finite; got {a.tolist()}")
        if norm > 1.0:
            a /= norm
        if self.crowd is not None:
            old = self.centers.copy()
            self.centers = self.crowd.step(self.position, a, self.rng)
            blocked, contact, gap = step_agent(
                self.position, a, self.agent_radius, self.world.segments, old, self.centers,
                self.radii, self.sensor.cos, self.sensor.sin, self.sensor.max_range, self.ranges,
            )  # fmt: skip
            return self._after(blocked, contact, gap)
        d = self.radii.shape[0]
        turn = self.rng.normal(0.0, self.turn_sd, d)
        retry = self.rng.random((d, _RETRIES))
        blocked, contact, gap = step_world(
            self.position,
            a,
            self.agent_radius,
            self.world.segments,
            self.centers,
            self.headings,
            self.radii,
            self.speed,
            turn,
            retry,
            self.sensor.cos,
            self.sensor.sin,
            self.sensor.max_range,
            self.ranges,
        )
        return self._after(blocked, contact, gap)

    def _after(self, blocked: bool, contact: bool, gap: float) -> StepResult:
        self.t += 1
        if self.record:
            self.path.append(self.position.copy())
            self.traces.append(self.centers.copy())
        dist = self.distance
        return StepResult(
            blocked=bool(blocked),
            contact=bool(contact),
            min_gap=float(gap),
            reached=dist <= self.goal_tolerance,
            distance=dist,
        )
