"""One navigation episode of any method at any sensing level: the loop every navigation
experiment shares, and the outcome and metrics it records."""

from __future__ import annotations

import copy
import dataclasses
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.core import Agent, Observation, Sensing, Task, check_sensing
from copi.errors import CopiError, InvalidArgumentError, MethodError, ctrl_c_behind
from copi.online import Steering
from copi.planning import length_error_bound, shortest_path
from copi.world import Simulator

__all__ = [
    "EnvEpisode",
    "EpisodeOutcome",
    "GlobalDirection",
    "checked_act",
    "make_task",
    "obstacle_future",
    "optimal_to_goal",
    "run_episode",
    "run_in_env",
]

@dataclass(frozen=True)
class EpisodeOutcome:
    """What one agent did in one episode (the method-dependent part of a result row)."""

    outcome: str
    """"success" (goal reached, no contact), "collision" (a contact with a moving
    obstacle; it ends the episode unless told otherwise), or "timeout"."""
    reached: bool
    """The goal was reached (also after a contact, when contacts do not end episodes)."""
    steps: int
    contacts: int
    """Steps with a contact."""
    path_length: float
    time_to_goal: float
    """Steps to reach the goal on success (NaN otherwise)."""
    min_clearance: float
    """Least surface-to-surface distance to any moving obstacle over the episode (negative
    after a contact; inf with no obstacles)."""
    smoothness: float
    """Sum of the turning angles between consecutive moves, radians (lower: smoother)."""
    decision_us: float
    """Mean wall time of the method's decision per step (global direction included),
    microseconds."""
    no_policy: int
    """Steps on which the method commanded no motion."""
    counters: dict[str, Any]
    """Method-specific diagnostics (e.g. copi's unfamiliar rate)."""
    close_steps: int | None = None
    """Steps that ended closer to a moving obstacle than ``discomfort`` (surface to
    surface), when :func:`run_episode` was given one."""


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _broke(agent: Agent, what: str, exc: BaseException) -> MethodError:
    """The one-line error of a method whose ``what`` raised ``exc`` (its own error, an
    exit it called, running out of memory: all of them the method's, not copi's). A
    Ctrl-C behind ``exc`` (numba's SystemError) is raised instead: it is the user's."""
    stop = ctrl_c_behind(exc)
    if stop is not None:
        raise stop
    if isinstance(exc, SystemExit):
        did = f"called sys.exit({exc.code!r})"
    else:
        did = f"raised {type(exc).__name__}" + (f": {exc}" if str(exc) else "")
    return MethodError(f"method {agent.name!r}: {what} {did}")


def checked_act(agent: Agent, obs: Observation, step: int) -> NDArray[np.float64]:
    """``agent.act(obs)`` as a velocity: 2 finite real numbers, float64. What the method
    raises (or a non-velocity it returns) is a :class:`~copi.errors.MethodError` naming
    it and the step; Ctrl-C and copi's own errors pass through."""
    try:
        action = agent.act(obs)
    except (KeyboardInterrupt, CopiError):
        raise
    except BaseException as exc:  # SystemExit and MemoryError too: the method's own
        raise _broke(agent, f"act at step {step}", exc) from None
    return velocity_of(action, agent, step)


def velocity_of(action: Any, agent: Agent, step: int) -> NDArray[np.float64]:
    """``action`` as a float64 velocity of shape (2,), or the one-line
    :class:`~copi.errors.MethodError` saying what the method returned instead."""
    if isinstance(action, np.ndarray) and action.dtype == np.float64 and action.shape == (2,):
        a = action
    else:
        try:
            a = np.asarray(action)
        except Exception:
            a = np.asarray(None)
        if a.shape != (2,) or a.dtype.kind not in "iuf":
            raise MethodError(
                f"method {agent.name!r}: act returned {_shown(action)} at step {step}; "
                "expected a velocity: 2 real numbers"
            )
        a = a.astype(np.float64)
    if not (math.isfinite(a[0]) and math.isfinite(a[1])):
        raise MethodError(
            f"method {agent.name!r}: act returned {a.tolist()} at step {step}; expected a "
            "velocity of finite numbers"
        )
    return a


class GlobalDirection:
    """The level's global direction for a method that does not find its own
    (:attr:`copi.core.Agent.steers_itself` False): :class:`copi.online.Steering`, the
    same that copi's methods and baselines follow, run by the runner, its direction put in
    :attr:`Observation.direction` and :attr:`Observation.reach`.

    One per agent, kept on it (``agent._global_direction``), so that in a lifelong run
    the map the strategy builds lasts from task to task as copi's own do.
    """

    def __init__(self) -> None:
        self.steering = Steering()

    @classmethod
    def of(cls, agent: Agent, task: Task) -> GlobalDirection | None:
        """The agent's, reset for ``task``; None for a method that steers itself."""
        if getattr(agent, "steers_itself", False):
            return None
        here: GlobalDirection | None = agent.__dict__.get("_global_direction")
        if here is None:
            here = cls()
            agent.__dict__["_global_direction"] = here
        here.steering.reset(task)
        return here

    def __call__(self, obs: Observation) -> Observation:
        """``obs`` with the direction (and in a lifelong run at ``sensor``, the static
        reading of the walls the strategy learnt, as copi's methods see it)."""
        desired, reach = self.steering.aim(obs)
        obs = self.steering.observe(obs)
        d = np.asarray(desired, dtype=np.float64)
        n = math.hypot(d[0], d[1])
        return dataclasses.replace(obs, direction=d / n if n > 0 else np.zeros(2),
                                   reach=float(reach))  # fmt: skip

    def finish(self, outcome: str) -> None:
        self.steering.finish(outcome)


def optimal_to_goal(sim: Simulator, *, quad_segs: int = 16) -> float:
    """A lower bound, within 0.12 %, on the shortest path from the start to the goal's
    tolerance disc on the snapshot at t = 0 with obstacles frozen (paper §IV).

    The planner's path (circles as circumscribed polygons) is at most
    ``length_error_bound(quad_segs)`` longer than the true shortest path to the goal; it
    is divided by that factor, and the tolerance is subtracted, since the agent stops as
    soon as it is within the tolerance. So a successful episode's excess is >= 0 (unless
    a wall lies between the goal and its tolerance circle). NaN when there is no path.
    """
    try:
        length = shortest_path(
            sim.world, sim.position, sim.goal, radius=sim.agent_radius, centers=sim.centers,
            radii=sim.radii, quad_segs=quad_segs,
        ).length  # fmt: skip
    except CopiError:
        return math.nan
    if not math.isfinite(length):
        return math.nan
    return max(0.0, length / (1.0 + length_error_bound(quad_segs)) - sim.goal_tolerance)


def obstacle_future(sim: Simulator, steps: int) -> NDArray[np.float64]:
    """The moving obstacles' next ``steps`` steps from ``sim``'s present, shape
    (steps + 1, d, 3), rows (x, y, radius): a copy of the episode run with the agent
    standing still. The obstacles' random walk draws the same numbers whatever the
    agent does and ignores it, so this is the future of the episode whatever the agent
    will do (tested)."""
    twin = copy.deepcopy(sim)
    twin.record = False
    d = twin.radii.shape[0]
    out = np.empty((steps + 1, d, 3))
    out[:, :, 2] = twin.radii
    out[0, :, :2] = twin.centers
    still = np.zeros(2)
    for t in range(steps):
        twin.step(still)
        out[t + 1, :, :2] = twin.centers
    return out


def make_task(
    sim: Simulator,
    sensing: Sensing,
    strategy: str = "greedy",
    *,
    lifelong: bool = False,
    max_steps: int = 1000,
) -> Task:
    """The task as a method at ``sensing`` is told it (``strategy``: the global strategy
    at level ``sensor``; ``lifelong``: one of a life's tasks, see :class:`Task`;
    ``max_steps``: the episode's step limit, over which level ``future`` records the
    obstacles' future)."""
    rank = check_sensing(sensing)
    knows_map = rank >= 1
    if rank >= 3 and sim.crowd is not None and sim.crowd.spec.sees_agent:
        raise InvalidArgumentError(
            "level future needs moving obstacles that ignore the agent: this world's crowd "
            "sees it, so its future depends on what the agent does"
        )
    return Task(
        sensing=sensing,
        agent_radius=sim.agent_radius,
        goal_tolerance=sim.goal_tolerance,
        n_rays=sim.sensor.n_rays,
        max_range=sim.sensor.max_range,
        world=sim.world if knows_map else None,
        start=sim.position.copy() if knows_map else None,
        goal=sim.goal.copy() if knows_map else None,
        strategy=strategy,
        future=obstacle_future(sim, max_steps) if rank >= 3 else None,
        lifelong=lifelong,
    )


def run_episode(
    agent: Agent,
    sim: Simulator,
    *,
    sensing: Sensing,
    max_steps: int,
    end_on_contact: bool = True,
    strategy: str = "greedy",
    origin: NDArray[np.float64] | None = None,
    discomfort: float | None = None,
) -> EpisodeOutcome:
    """Run ``agent`` in ``sim`` (fresh, at t = 0) at ``sensing`` until it reaches the
    goal, touches a moving obstacle (when ``end_on_contact``) or runs out of steps.

    The agent receives only its level's information (:mod:`copi.online`): the static
    reading is computed only at ``map`` and above, obstacle states only at ``oracle``.
    ``strategy`` is the global strategy every method uses at level ``sensor``.
    ``origin``: in a lifelong run, where the agent's life began (its odometry is its
    position less ``origin``, and it may keep what it learnt from earlier tasks).
    ``discomfort``: count the steps whose least surface distance to a moving obstacle is
    below it (CrowdNav's discomfort frequency).
    When the episode ends, the agent is told its outcome (:meth:`Agent.finish`) and
    asked for its counters.

    Examples
    --------
    >>> from copi.baselines import Straight
    >>> from copi.world import ObstacleSpec, Simulator, World
    >>> room = World([[0, 0], [20, 0], [20, 20], [0, 20]], start=[2, 2], goal=[12, 2])
    >>> sim = Simulator.from_world(room, 0, obstacles=ObstacleSpec(count=(0, 0)))
    >>> out = run_episode(Straight(), sim, sensing="sensor", max_steps=50)
    >>> out.outcome, out.steps
    ('success', 10)
    """
    if not isinstance(agent, Agent):
        raise InvalidArgumentError(
            f"{type(agent).__name__} is not a copi.core.Agent: subclass it (reset and act; "
            "finish and counters are optional)"
        )
    rank = check_sensing(sensing, agent.sensing, method=agent.name)
    world = sim.world
    sensor = sim.sensor
    task = make_task(sim, sensing, strategy, lifelong=origin is not None, max_steps=max_steps)
    try:
        agent.reset(task)
    except (KeyboardInterrupt, CopiError):
        raise
    except BaseException as exc:
        raise _broke(agent, "reset", exc) from None
    steer = GlobalDirection.of(agent, task)
    prev_centers = sim.centers.copy()
    # what an oracle is told of the discs' motion before any step: a random walk's
    # heading at its speed; a crowd's own velocities (at rest, as CrowdNav's humans start)
    velocities = (
        sim.crowd.velocities()
        if sim.crowd is not None
        else sim.speed * np.column_stack([np.cos(sim.headings), np.sin(sim.headings)])
    )
    length = 0.0
    contacts = 0
    no_policy = 0
    reached = False
    t_decide = 0.0
    turning = 0.0
    last_move: np.ndarray | None = None
    min_gap = math.inf
    close = 0
    steps = 0
    clock = time.perf_counter
    while steps < max_steps:
        steps += 1
        pos = sim.position
        static = sensor.scan(world, pos) if rank >= 1 else None
        obstacles = (
            np.column_stack([sim.centers, velocities, sim.radii]) if rank >= 2 else None
        )
        obs = Observation(
            ranges=sim.ranges.copy(),
            goal=sim.goal - pos,
            position=pos.copy() if rank >= 1 else None,
            static=static,
            obstacles=obstacles,
            odometry=None if origin is None else pos - origin,
        )
        t0 = clock()
        if steer is not None:
            obs = steer(obs)
        try:
            action = agent.act(obs)
        except (KeyboardInterrupt, CopiError):
            raise
        except BaseException as exc:  # SystemExit and MemoryError too: the method's own
            raise _broke(agent, f"act at step {steps}", exc) from None
        t_decide += clock() - t0
        action = velocity_of(action, agent, steps)
        if action[0] == 0.0 and action[1] == 0.0:
            no_policy += 1
        x, y = pos
        res = sim.step(action)
        dx, dy = sim.position[0] - x, sim.position[1] - y
        moved = math.hypot(dx, dy)
        length += moved
        if moved > 1e-9:
            if last_move is not None:
                c = (dx * last_move[0] + dy * last_move[1]) / moved
                turning += math.acos(max(-1.0, min(1.0, c)))
            last_move = np.array([dx / moved, dy / moved])
        if rank >= 2:
            velocities = sim.centers - prev_centers
            prev_centers = sim.centers.copy()
        min_gap = min(min_gap, res.min_gap)
        if discomfort is not None and res.min_gap < discomfort:
            close += 1
        if res.contact:
            contacts += 1
            if end_on_contact:
                break
        if res.reached:
            reached = True
            break
    if contacts:
        outcome = "collision"
    elif reached:
        outcome = "success"
    else:
        outcome = "timeout"
    if steer is not None:
        steer.finish(outcome)
    try:
        agent.finish(outcome)
        counters = agent.counters()
    except (KeyboardInterrupt, CopiError):
        raise
    except BaseException as exc:
        raise _broke(agent, "finish or counters", exc) from None
    if not isinstance(counters, dict):
        raise MethodError(f"method {agent.name!r}: counters returned {_shown(counters)}; "
                          "expected a dict of numbers by name")  # fmt: skip
    return EpisodeOutcome(
        outcome=outcome,
        reached=reached,
        steps=steps,
        contacts=contacts,
        path_length=length,
        time_to_goal=float(steps) if outcome == "success" else math.nan,
        min_clearance=min_gap,
        smoothness=turning,
        decision_us=1e6 * t_decide / steps,
        no_policy=no_policy,
        counters=counters,
        close_steps=close if discomfort is not None else None,
    )


@dataclass(frozen=True)
class EnvEpisode:
    """What an agent did in one episode of the Gymnasium environment."""

    outcome: str
    """"success" (the goal reached), "collision" (a contact ended it), "timeout" (the
    environment truncated it)."""
    steps: int
    reward: float
    """The environment's return (sum of rewards)."""
    info: dict[str, Any]
    """The last step's info."""


def run_in_env(
    agent: Agent,
    env: Any,
    *,
    seed: int | None = None,
    options: dict[str, Any] | None = None,
) -> EnvEpisode:
    """Run a copi :class:`~copi.core.Agent` for one episode of ``copi/Navigation-v0`` (or
    any environment wrapping :class:`~copi.world.NavigationEnv`): the agent is told the
    environment's task (level ``sensor``: its radius, goal tolerance and sensor) and acts
    on its observations; every step goes through ``env.step`` (and so through its
    wrappers, such as the time limit).

    Examples
    --------
    >>> import gymnasium, copi
    >>> from copi.baselines import CompassGuard
    >>> env = gymnasium.make("copi/Navigation-v0")
    >>> run_in_env(CompassGuard(), env, seed=0).outcome
    'success'
    """
    if not isinstance(agent, Agent):
        raise InvalidArgumentError(
            f"{type(agent).__name__} is not a copi.core.Agent: subclass it (reset and act; "
            "finish and counters are optional)"
        )
    base = env.unwrapped
    if not hasattr(base, "task") or not hasattr(base, "observation"):
        raise InvalidArgumentError(
            f"{type(base).__name__} is not copi's navigation environment (it has no task() "
            "and observation())"
        )
    env.reset(seed=seed, options=options)
    agent.reset(base.task())
    total, steps = 0.0, 0
    info: dict[str, Any] = {}
    outcome = "timeout"
    while True:
        action = np.asarray(agent.act(base.observation()), dtype=np.float32)
        _, reward, terminated, truncated, info = env.step(action)
        total += float(reward)
        steps += 1
        if terminated:
            outcome = "success" if info.get("is_success") else "collision"
            break
        if truncated:
            break
    agent.finish(outcome)
    return EnvEpisode(outcome, steps, total, info)
