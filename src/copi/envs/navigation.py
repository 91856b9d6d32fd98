"""Gymnasium environment of the navigation domain (``copi/Navigation-v0``)."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import Any, SupportsFloat

import gymnasium
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from copi._validation import check_count, non_negative, positive, positive_int
from copi.core import Observation, Task
from copi.errors import InvalidArgumentError
from copi.world import (
    ObstacleSpec,
    RangeSensor,
    Simulator,
    StepResult,
    World,
    WorldParams,
    load_worlds,
    random_world,
    render_rgb,
)

__all__ = ["NavigationEnv"]

ObsType = NDArray[np.float32]

MAX_PIXELS = 4096
"""The largest side of a rendered image (a larger one would take gigabytes)."""


class NavigationEnv(gymnasium.Env[ObsType, ObsType]):
    """Reach a goal in a random polygon world among random-walking discs (paper §IV).

    Each ``reset`` draws a world of :func:`~copi.world.random_world`, a start and goal and
    the moving obstacles, all from ``self.np_random``. To train or evaluate on given
    worlds, fix them at construction (``world=`` or ``world_file=``): every reset,
    including a vector environment's automatic ones, then draws among those worlds only.
    ``reset(options={"world": w})`` runs ``w`` (a :class:`~copi.world.World` or its JSON
    dict) for that one episode.

    Observation
        float32 vector of N + 2: the N ranges of the ring sensor (ray i at 2 pi i / N from
        +x, world frame, in [0, max_range]) followed by the goal relative to the agent
        (goal - position, agent steps), scaled down to fit in [-goal_range, goal_range]
        when farther (direction kept).
    Action
        float32 velocity (vx, vy) in [-1, 1]^2; its norm is clipped to 1 (the agent's top
        speed, one agent step per time step).
    Reward
        ``(d_prev - d) - 0.01 + 10 [goal reached] - 10 [contact]``, where d is the
        straight-line distance to the goal: progress, a small time cost, the goal bonus,
        and the collision penalty.
    Termination
        At the goal (within ``goal_tolerance``); at a contact with a moving obstacle when
        ``terminate_on_collision`` (the default). Walls only stop the agent.
    Truncation
        After ``max_steps`` steps. ``gymnasium.make`` also wraps the environment in a
        ``TimeLimit`` of ``spec.max_episode_steps`` (500, the default ``max_steps``;
        ``gymnasium.make(id, max_episode_steps=n)`` changes it): the earlier limit
        truncates.
    Info
        ``contact``, ``blocked``, ``min_gap``, ``distance``, ``is_success``, ``world``.

    Parameters
    ----------
    render_mode : {"rgb_array", None}
        ``rgb_array``: ``render()`` returns the state as an image (walls, moving obstacles
        and their traces, rays, the agent's path, the goal), drawn without Matplotlib
        (about 1 ms a frame at 64 x 64).
    world : World, dict or sequence of them, optional
        The worlds episodes run in (one is drawn per reset); default: random worlds.
    world_file : path, optional
        A world file (:func:`~copi.world.load_worlds`) holding those worlds instead.
    obstacles : int, (int, int) or ObstacleSpec, optional
        Number of moving obstacles (or a range, or a full spec); the paper's 10-15 when None.
    n_rays, max_range : sensor ring (32 rays, range 10 by default).
    agent_radius : float
    max_steps : int
    terminate_on_collision : bool
    goal_tolerance : float
    min_distance : float
        Least straight-line distance between start and goal.
    goal_range : float
        Bound of the goal part of the observation (1000 agent steps: beyond any world
        copi draws, and beyond a 512 x 512 Moving AI map).
    world_params : WorldParams, optional
        The random world distribution (when no worlds are given).
    width, height : int
        Size of the rendered image in pixels (height defaults to width).

    Examples
    --------
    >>> import gymnasium, copi
    >>> from copi.world import World
    >>> room = World([[0, 0], [30, 0], [30, 30], [0, 30]], name="room")
    >>> env = gymnasium.make("copi/Navigation-v0", world=room, render_mode="rgb_array",
    ...                      width=64)
    >>> env.spec.max_episode_steps
    500
    >>> obs, info = env.reset(seed=0)
    >>> info["world"], obs.shape, env.render().shape
    ('room', (34,), (64, 64, 3))
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(
        self,
        render_mode: str | None = None,
        *,
        obstacles: int | tuple[int, int] | ObstacleSpec | None = None,
        n_rays: int = 32,
        max_range: float = 10.0,
        agent_radius: float = 0.3,
        max_steps: int = 500,
        terminate_on_collision: bool = True,
        goal_tolerance: float = 0.5,
        min_distance: float = 10.0,
        world_params: WorldParams | None = None,
        goal_range: float = 1000.0,
        world: World | dict[str, Any] | Sequence[World | dict[str, Any]] | None = None,
        world_file: str | os.PathLike[str] | None = None,
        width: int = 400,
        height: int | None = None,
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise InvalidArgumentError(
                f"render_mode must be one of {self.metadata['render_modes']} or None; "
                f"got {render_mode!r}"
            )
        positive_int(max_steps, "max_steps")
        check_count(int(max_steps), "max_steps", 1_000_000)
        for name, value in (("agent_radius", agent_radius), ("goal_range", goal_range)):
            positive(value, name)
            if value > 1e6:
                raise InvalidArgumentError(f"{name} must be at most 1,000,000 agent steps; "
                                           f"got {value:g}")  # fmt: skip
        for name, value in (("goal_tolerance", goal_tolerance), ("min_distance", min_distance)):
            non_negative(value, name)
        if world is not None and world_file is not None:
            raise InvalidArgumentError("give world or world_file, not both")
        self.worlds: tuple[World, ...] | None = None
        if world_file is not None:
            self.worlds = tuple(load_worlds(world_file))
        elif world is not None:
            items = [world] if isinstance(world, World | dict) else list(world)
            if not items:
                raise InvalidArgumentError("world must hold at least one world; got none")
            self.worlds = tuple(_as_world(w, "world") for w in items)
        for name, size in (("width", width), ("height", width if height is None else height)):
            if isinstance(size, bool) or not isinstance(size, int | np.integer) or not (
                1 <= size <= MAX_PIXELS
            ):
                raise InvalidArgumentError(
                    f"{name} must be an int in 1 .. {MAX_PIXELS} pixels; got {size!r}"
                )
        self.width = int(width)
        self.height = int(width if height is None else height)
        self.render_mode = render_mode
        self.sensor = RangeSensor(n_rays, max_range)
        if obstacles is None or isinstance(obstacles, ObstacleSpec):
            self.obstacle_spec = obstacles
        else:
            count = (obstacles, obstacles) if isinstance(obstacles, int) else tuple(obstacles)
            self.obstacle_spec = ObstacleSpec(count=count)  # type: ignore[arg-type]
        self.agent_radius = float(agent_radius)
        self.max_steps = int(max_steps)
        self.terminate_on_collision = bool(terminate_on_collision)
        self.goal_tolerance = float(goal_tolerance)
        self.min_distance = float(min_distance)
        self.world_params = world_params or WorldParams()
        self.goal_range = float(goal_range)
        n = self.sensor.n_rays
        low = np.concatenate([np.zeros(n), np.full(2, -self.goal_range)]).astype(np.float32)
        high = np.concatenate([np.full(n, self.sensor.max_range), np.full(2, self.goal_range)])
        self.observation_space = spaces.Box(low, high.astype(np.float32), dtype=np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.sim: Simulator | None = None
        self._ended: str | None = None
        self._obs = np.zeros(n + 2, dtype=np.float32)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsType, dict[str, Any]]:
        super().reset(seed=seed)
        options = dict(options or {})
        world = options.pop("world", None)
        if options:
            raise InvalidArgumentError(f"unknown reset options {sorted(options)}; expected 'world'")
        if world is not None:
            world = _as_world(world, "options['world']")
        elif self.worlds is None:
            world = random_world(self.np_random, params=self.world_params)
        elif len(self.worlds) == 1:
            world = self.worlds[0]
        else:
            world = self.worlds[int(self.np_random.integers(len(self.worlds)))]
        self.sim = Simulator.from_world(
            world,
            self.np_random,
            agent_radius=self.agent_radius,
            sensor=self.sensor,
            obstacles=self.obstacle_spec,
            min_distance=self.min_distance,
            goal_tolerance=self.goal_tolerance,
            record=self.render_mode is not None,
        )
        self._ended = None
        return self._observation(), self._info(None)

    def step(self, action: ObsType) -> tuple[ObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        sim = self.sim
        if sim is None:
            raise gymnasium.error.ResetNeeded("call reset() before step()")
        if self._ended is not None:
            raise gymnasium.error.ResetNeeded(f"the episode has ended ({self._ended}); call "
                                              "reset() before step()")  # fmt: skip
        try:
            a = np.asarray(action)
        except (TypeError, ValueError):
            raise InvalidArgumentError(
                f"action must be a velocity (vx, vy); got {type(action).__name__}"
            ) from None
        if a.dtype.kind not in "iuf":
            raise InvalidArgumentError(
                f"action must be 2 real numbers (vx, vy); got {a.dtype} values"
            )
        a = a.astype(np.float64)
        if a.shape != (2,) or not np.isfinite(a).all():
            raise InvalidArgumentError(
                f"action must be 2 finite numbers (vx, vy), as the action space {self.action_space}"
                f" says; got {a.tolist() if a.size <= 8 else f'shape {a.shape}'}"
            )
        before = sim.distance
        res = sim.step(a)
        reward = (before - res.distance) - 0.01
        if res.reached:
            reward += 10.0
        if res.contact:
            reward -= 10.0
        terminated = res.reached or (res.contact and self.terminate_on_collision)
        truncated = not terminated and sim.t >= self.max_steps
        if terminated or truncated:
            self._ended = "terminated" if terminated else "truncated"
        return self._observation(), float(reward), terminated, truncated, self._info(res)

    def _observation(self) -> ObsType:
        sim = self.sim
        assert sim is not None
        n = self.sensor.n_rays
        obs = self._obs.copy()
        obs[:n] = sim.ranges
        gx = sim.goal[0] - sim.position[0]
        gy = sim.goal[1] - sim.position[1]
        far = max(abs(gx), abs(gy))
        if far > self.goal_range:
            gx, gy = gx * self.goal_range / far, gy * self.goal_range / far
        obs[n] = gx
        obs[n + 1] = gy
        return obs

    def _info(self, res: StepResult | None) -> dict[str, Any]:
        sim = self.sim
        assert sim is not None
        if res is None:
            return {"distance": sim.distance, "world": sim.world.name, "is_success": False}
        return {
            "contact": res.contact,
            "blocked": res.blocked,
            "min_gap": res.min_gap,
            "distance": res.distance,
            "is_success": res.reached,
            "world": sim.world.name,
        }

    def task(self) -> Task:
        """What a copi :class:`~copi.core.Agent` is told of the current episode: its
        observation is level ``sensor``'s (the ranges and the goal relative to the agent),
        with this environment's radius, goal tolerance and sensor."""
        if self.sim is None:
            raise gymnasium.error.ResetNeeded("call reset() before task()")
        return Task(sensing="sensor", agent_radius=self.agent_radius,
                    goal_tolerance=self.goal_tolerance, n_rays=self.sensor.n_rays,
                    max_range=self.sensor.max_range)  # fmt: skip

    def observation(self) -> Observation:
        """The current observation as a copi :class:`~copi.core.Observation` (level
        ``sensor``: the goal unscaled, the global direction toward it)."""
        sim = self.sim
        if sim is None:
            raise gymnasium.error.ResetNeeded("call reset() before observation()")
        goal = sim.goal - sim.position
        dist = math.hypot(goal[0], goal[1])
        return Observation(ranges=sim.ranges.copy(), goal=goal,
                           direction=goal / dist if dist > 0 else np.zeros(2), reach=dist)

    def render(self) -> NDArray[np.uint8] | None:  # type: ignore[override]
        if self.render_mode is None:
            gymnasium.logger.warn("render() called without a render_mode; nothing drawn")
            return None
        if self.sim is None:
            raise gymnasium.error.ResetNeeded("call reset() before render()")
        return render_rgb(self.sim, pixels=self.width, height=self.height)


def _as_world(world: Any, what: str) -> World:
    if isinstance(world, World):
        return world
    if isinstance(world, dict):
        return World.from_dict(world)
    raise InvalidArgumentError(f"{what} must be a World or its dict; got {type(world).__name__}")
