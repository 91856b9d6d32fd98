"""Experiment 1 (paper §IV, Fig. 3-4): reach a goal in dynamic worlds never seen, and
compare the path with the optimal one on the stationary snapshot at t = 0."""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from copi.errors import CopiError, InvalidArgumentError
from copi.experiments._runs import RunIdentity, run_into_store
from copi.geometry._arrays import positive_int
from copi.learning import Capabilities
from copi.online import ContextController, make_strategy
from copi.planning import shortest_path
from copi.world import RangeSensor, Simulator, World, load_worlds, random_world

__all__ = ["EpisodeResult", "NavigationConfig", "evaluate", "run_episode", "run_episodes"]


@dataclass(frozen=True)
class NavigationConfig(RunIdentity):
    """One evaluation run of Experiment 1: everything that decides its results."""

    capabilities: str
    """Path of the capabilities file (its content hash, not the path, enters the run id)."""
    method: str = "copi"
    """Label of the method in the results (e.g. "faithful", "extended")."""
    worlds: int = 1549
    """Episodes (the paper: 1549 dynamic worlds)."""
    world_file: str | None = None
    """Worlds to run instead of the paper's random ones (episode k uses world k mod n)."""
    seed: int = 0
    """Episode k draws world, task and obstacles from default_rng([seed, k])."""
    strategy: str = "route"
    """Global strategy: "route" (knows the static world) or "greedy" (knows the goal)."""
    max_steps: int = 1000
    """Steps before an episode times out."""
    agent_radius: float = 0.3
    """Radius of the disc agent."""
    guard: float = 0.0
    """The controller's guard (0: the paper's chain; see ContextController). With the
    route strategy, which knows the static map, the guard is told what the map alone
    would show, so that only moving obstacles count as hazards."""
    continual: bool = False
    """Grow contexts for unfamiliar readings online."""
    record: int = 8
    """Episodes (the first ones) whose trajectories are stored for figures."""
    capabilities_sha: str = field(default="", compare=False)
    """Content hash of the capabilities file (filled in by :meth:`resolved`)."""

    def __post_init__(self) -> None:
        for name in ("worlds", "max_steps"):
            positive_int(getattr(self, name), name)
        if self.strategy not in ("route", "greedy"):
            raise InvalidArgumentError(
                f"strategy must be 'route' or 'greedy'; got {self.strategy!r}"
            )


@dataclass(frozen=True)
class EpisodeResult:
    """One episode's row in the results store (DESIGN.md, "Results store")."""

    episode: int
    world: str
    seed: int
    success: bool
    """Reached the goal within the step limit without touching anything."""
    reached: bool
    collided: bool
    timed_out: bool
    steps: int
    contacts: int
    """Steps with a contact (the episode goes on after one)."""
    path_length: float
    optimal_length: float
    """Shortest path on the snapshot at t = 0 with obstacles frozen (inf: none)."""
    excess: float
    """path_length / optimal_length - 1 when the goal was reached (NaN otherwise)."""
    decision_us: float
    """Mean wall time of one online decision (the controller's chain), microseconds."""
    strategy_us: float
    """Mean wall time of the global strategy's aim per step, microseconds."""
    unfamiliar: float
    """Share of this episode's decisions whose reading was unfamiliar."""
    no_policy: int
    """Steps at which the context offered no policy (the agent stood still)."""
    trajectory: dict[str, Any] | None = None
    """For recorded episodes: world, path, obstacle traces and radii (JSON-able)."""


@lru_cache(maxsize=4)
def _capabilities(path: str, sha: str) -> Capabilities:
    del sha  # part of the cache key: a rewritten file is read again
    caps = Capabilities.load(path)
    # Load the compiled chain now, so that no episode's decision time includes it.
    ContextController(caps).decide(np.full(caps.n_rays, 5.0), [1.0, 0.0])
    return caps


@lru_cache(maxsize=4)
def _world_list(path: str) -> tuple[World, ...]:
    return tuple(load_worlds(path))


def run_episode(config: NavigationConfig, k: int) -> EpisodeResult:
    """Episode k of a run: draw the task, measure the optimum on the frozen snapshot,
    then run the agent online. Depends only on (config, k)."""
    caps = _capabilities(config.capabilities, config.capabilities_sha)
    rng = np.random.default_rng([config.seed, k])
    if config.world_file is not None:
        worlds = _world_list(config.world_file)
        world = worlds[k % len(worlds)]
    else:
        world = random_world(rng, name=f"random-{k:05d}")
    sensor = RangeSensor(caps.n_rays, float(caps.params.get("max_range", 10.0)))
    sim = Simulator.from_world(
        world, rng, agent_radius=config.agent_radius, sensor=sensor, record=k < config.record
    )
    start = sim.position.copy()
    try:
        optimal = shortest_path(
            world, start, sim.goal, radius=config.agent_radius, centers=sim.centers, radii=sim.radii
        ).length
    except CopiError:
        optimal = math.nan
    controller = ContextController(caps, guard=config.guard, continual=config.continual)
    knows_map = config.guard > 0 and config.strategy == "route"
    strategy = make_strategy(config.strategy)
    strategy.reset(world, start, sim.goal, config.agent_radius)
    length = 0.0
    contacts = 0
    no_policy = 0
    reached = False
    t_decide = 0.0
    t_aim = 0.0
    steps = 0
    clock = time.perf_counter
    while steps < config.max_steps:
        steps += 1
        t0 = clock()
        desired, reach = strategy.aim(sim.position)
        static = sensor.scan(world, sim.position) if knows_map else None
        t1 = clock()
        action, _ = controller.decide(sim.ranges, desired, reach=reach, static=static)
        t2 = clock()
        t_aim += t1 - t0
        t_decide += t2 - t1
        if action[0] == 0.0 and action[1] == 0.0:
            no_policy += 1
        x, y = sim.position
        res = sim.step(action)
        length += math.hypot(sim.position[0] - x, sim.position[1] - y)
        contacts += res.contact
        if res.reached:
            reached = True
            break
    excess = (
        length / optimal - 1 if reached and math.isfinite(optimal) and optimal > 0 else math.nan
    )
    trajectory = None
    if sim.record:
        trajectory = {
            "world": world.to_dict(),
            "path": np.asarray(sim.path).round(4).tolist(),
            "traces": np.asarray(sim.traces).round(4).tolist(),
            "radii": sim.radii.tolist(),
            "goal": sim.goal.tolist(),
        }
    return EpisodeResult(
        episode=k,
        world=world.name,
        seed=config.seed,
        success=reached and contacts == 0,
        reached=reached,
        collided=contacts > 0,
        timed_out=not reached,
        steps=steps,
        contacts=contacts,
        path_length=length,
        optimal_length=optimal,
        excess=excess,
        decision_us=1e6 * t_decide / steps,
        strategy_us=1e6 * t_aim / steps,
        unfamiliar=controller.unfamiliar_rate,
        no_policy=no_policy,
        trajectory=trajectory,
    )


def run_episodes(config: NavigationConfig, episodes: list[int]) -> list[EpisodeResult]:
    """Several episodes in one task (fewer round trips to the workers)."""
    return [run_episode(config, k) for k in episodes]


def evaluate(
    config: NavigationConfig,
    output: str | os.PathLike[str],
    *,
    workers: int = 1,
    scheduler: str | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> str:
    """Run (or resume) Experiment 1 into the results file ``output``; returns the run id.

    Episodes already in the file for this run are skipped, so rerunning the same command
    after an interruption finishes the missing ones only. Each finished episode is
    committed at once.
    """
    config = config.resolved()
    return run_into_store(
        config,
        output,
        experiment="navigation",
        method=config.method,
        table="episodes",
        total=config.worlds,
        one=run_episode,
        many=run_episodes,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        chunk=16,
    )
