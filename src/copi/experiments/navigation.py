"""Experiment 1 (paper §IV, Fig. 3-4): reach a goal in dynamic worlds never seen, and
compare the path with the optimal one on the stationary snapshot at t = 0."""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from copi._rng import check_seed
from copi._validation import positive_int
from copi.core import Sensing, check_sensing, check_strategy
from copi.errors import InvalidArgumentError, InvalidWorldError, WorldFileError
from copi.experiments._episode import EpisodeOutcome, optimal_to_goal, run_episode
from copi.experiments._runs import (
    MAX_EPISODES,
    RunIdentity,
    check_count,
    check_family_inputs,
    file_sha,
)
from copi.experiments.methods import check_method_capabilities, make_agent, method_spec
from copi.learning import Capabilities
from copi.online import ContextController, LearntAgent
from copi.world import (
    RangeSensor,
    Simulator,
    World,
    check_family,
    check_task,
    load_worlds,
    sample_world,
)

__all__ = [
    "EpisodeResult",
    "NavigationConfig",
    "draw_episode",
    "evaluate",
    "evaluate_episode",
    "evaluate_episodes",
    "result_row",
    "world_file_label",
]


@dataclass(frozen=True)
class NavigationConfig(RunIdentity):
    """One evaluation run of Experiment 1: everything that decides its results."""

    capabilities: str | None
    """Path of the capabilities file, for copi's modes (its content hash, not the path,
    enters the run id); None for the baselines."""
    method: str = "copi-faithful"
    """The method, by its registered name (:data:`copi.experiments.methods.METHODS`)."""
    worlds: int = 1549
    """Episodes (the paper: 1549 dynamic worlds)."""
    world_file: str | None = None
    """Worlds to run instead of the family's (episode k uses world k mod n)."""
    family: str = "star"
    """World family of the episodes (:data:`copi.world.FAMILIES`; "star": the paper's)."""
    sensing: Sensing = "map"
    """Sensing level the method runs at (sensor, map or oracle; see copi.online)."""
    sensor_strategy: str = "greedy"
    """Global strategy at level sensor: "greedy" or "mapping" (see copi.online.Mapping)."""
    seed: int = 0
    """Episode k draws world, task and obstacles from default_rng([seed, k])."""
    max_steps: int = 1000
    """Steps before an episode times out."""
    agent_radius: float = 0.3
    """Radius of the disc agent."""
    guard: float | None = None
    """copi's and compass-guard's guard (None: the method's registered value; 0: none)."""
    continual: bool = False
    """Grow contexts for unfamiliar readings online (copi's modes)."""
    end_on_contact: bool = True
    """A contact with a moving obstacle ends the episode (a collision); False goes on
    (the episode still counts as a collision)."""
    record: int = 8
    """Episodes (the first ones) whose trajectories are stored for figures."""
    capabilities_sha: str = field(default="", compare=False)
    """Content hash of the capabilities file (filled in by :meth:`resolved`)."""
    world_file_sha: str = field(default="", compare=False)
    """Content hash of the world file (filled in by :meth:`resolved`)."""
    inputs: dict[str, str] = field(default_factory=dict, compare=False)
    """Content hashes of the data the family draws from (:func:`copi.world.family_inputs`,
    filled in by :meth:`resolved`)."""

    def __post_init__(self) -> None:
        for name in ("worlds", "max_steps"):
            positive_int(getattr(self, name), name)
        check_count(self.worlds, "worlds", MAX_EPISODES)
        check_count(self.max_steps, "max_steps", 100_000)
        check_seed(self.seed)
        spec = method_spec(self.method)
        check_sensing(self.sensing, spec.sensing, method=self.method)
        check_strategy(self.sensor_strategy)
        if spec.capabilities is not None and self.capabilities is None:
            raise InvalidArgumentError(f"{self.method} needs a capabilities file")
        if self.world_file is None:
            check_family(self.family)
        if self.guard is not None and not (math.isfinite(self.guard) and self.guard >= 0):
            raise InvalidArgumentError(f"guard must be a finite number >= 0; got {self.guard!r}")

    @property
    def row_family(self) -> str:
        """The family its rows name: the family's, or the world file's label."""
        if self.world_file is not None:
            return world_file_label(self.world_file)
        return self.family

    @property
    def strategy(self) -> str:
        """The global strategy of the run's rows: the route at levels with a map."""
        return self.sensor_strategy if self.sensing == "sensor" else "route"

    def agent_params(self) -> dict[str, Any]:
        """The method's parameters as this run sets them."""
        p = dict(method_spec(self.method).params)
        if self.guard is not None and "guard" in p:
            p["guard"] = self.guard
        if "continual" in p:
            p["continual"] = self.continual or bool(p["continual"])
        return p


@dataclass(frozen=True)
class EpisodeResult:
    """One episode's row in the results store (DESIGN.md, "Results store")."""

    episode: int
    world: str
    seed: int
    success: bool
    """Reached the goal within the step limit without touching a moving obstacle."""
    reached: bool
    collided: bool
    """Touched a moving obstacle (exclusive of success and timeout)."""
    timed_out: bool
    """Neither reached the goal nor touched anything within the step limit."""
    steps: int
    contacts: int
    """Steps with a contact (at most 1 when contacts end episodes)."""
    path_length: float
    optimal_length: float
    """Lower bound (within 0.12 %) on the shortest path to the goal's tolerance disc on
    the snapshot at t = 0 with obstacles frozen (NaN: none)."""
    excess: float
    """path_length / optimal_length - 1 on success (>= 0), NaN otherwise."""
    decision_us: float
    """Mean wall time of one decision (global direction and local choice), µs."""
    strategy_us: float
    """Kept for older readers: 0 (the decision time includes the global direction)."""
    unfamiliar: float
    """Share of this episode's decisions whose reading was unfamiliar (copi's modes)."""
    no_policy: int
    """Steps at which the method commanded no motion."""
    family: str = "star"
    sensing: str = "map"
    outcome: str = "timeout"
    """success, collision or timeout (exclusive); "skipped" when the episode's world has
    no valid task (then ``reason`` says why, and the episode counts in no rate)."""
    time_to_goal: float = math.nan
    """Steps to the goal on success."""
    min_clearance: float = math.nan
    """Least surface distance to a moving obstacle over the episode."""
    smoothness: float = math.nan
    """Sum of turning angles between consecutive moves, radians."""
    trajectory: dict[str, Any] | None = None
    """For recorded episodes: world, path, obstacle traces and radii (JSON-able)."""
    reason: str | None = None
    """Why an episode was skipped (None otherwise)."""
    strategy: str = "route"
    """The global strategy: "route" (levels with a map) or the sensor-level one."""


def world_file_label(path: str | os.PathLike[str]) -> str:
    """How a run of a world file names its rows' family: ``file:NAME``."""
    return f"file:{Path(path).name}"


def skipped_row(
    k: int,
    seed: int,
    world: str,
    reason: str,
    *,
    family: str,
    sensing: str,
    strategy: str = "route",
) -> EpisodeResult:
    """The stored row of an episode whose world has no valid task: recorded as such, so
    that a run goes on (and a resumed run does not stop there again)."""
    nan = math.nan
    return EpisodeResult(
        episode=k, world=world, seed=seed, success=False, reached=False, collided=False,
        timed_out=False, steps=0, contacts=0, path_length=nan, optimal_length=nan,
        excess=nan, decision_us=nan, strategy_us=0.0, unfamiliar=0.0, no_policy=0,
        family=family, sensing=sensing, outcome="skipped", reason=reason, strategy=strategy,
    )  # fmt: skip


def episode_world_name(
    family: str, k: int, *, world_file: str | None = None, world_file_sha: str = ""
) -> str:
    """The name of episode k's world (as :func:`draw_episode` names it)."""
    if world_file is not None:
        worlds = _world_list(world_file, world_file_sha)
        return worlds[k % len(worlds)].name
    return f"{family}-{k:05d}"


@lru_cache(maxsize=4)
def _capabilities(path: str, sha: str) -> Capabilities:
    del sha  # part of the cache key: a rewritten file is read again
    caps = Capabilities.load(path)
    # Load the compiled chain now, so that no episode's decision time includes it (the
    # chain does not take contexts that see motion: those serve the learnt preset only).
    if caps.motion:
        if caps.safety is not None:
            s = np.full((1, caps.n_rays), 5.0)
            LearntAgent(caps).decide_batch(s, s, [[1.0, 0.0]])
    else:
        ContextController(caps).decide(np.full(caps.n_rays, 5.0), [1.0, 0.0])
    return caps


@lru_cache(maxsize=4)
def _world_list(path: str, sha: str = "") -> tuple[World, ...]:
    """The worlds of ``path``, checked to be the content the run was started with."""
    if sha and file_sha(path) != sha:
        raise WorldFileError(
            f"{path}: the world file changed during the run; rerun the same command to "
            "be told how it differs from the stored run"
        )
    return tuple(load_worlds(path))


def draw_episode(
    family: str,
    k: int,
    seed: int,
    *,
    world_file: str | None = None,
    world_file_sha: str = "",
    agent_radius: float = 0.3,
    n_rays: int = 32,
    max_range: float = 10.0,
    record: bool = False,
) -> Simulator:
    """Episode k's world, task and obstacles, all from default_rng([seed, k]): the same
    for every method, so that methods can be compared episode by episode."""
    rng = np.random.default_rng([seed, k])
    if world_file is not None:
        worlds = _world_list(world_file, world_file_sha)
        world = worlds[k % len(worlds)]
    else:
        world = sample_world(family, rng, name=f"{family}-{k:05d}")
    sensor = RangeSensor(n_rays, max_range)
    sim = Simulator.from_world(world, rng, agent_radius=agent_radius, sensor=sensor, record=record)
    if world_file is not None:
        # A user's world may have no way through for the agent (a door narrower than it):
        # such an episode is no task at all, and is skipped saying so, never counted as a
        # collision (the families are drawn with a way through).
        _check_reachable(world_file, world_file_sha, k % len(worlds), agent_radius,
                         tuple(sim.position), tuple(sim.goal))  # fmt: skip
    return sim


def mapping_closes(world_file: str | os.PathLike[str], agent_radius: float = 0.3,
                   most: int = 100) -> list[str]:  # fmt: skip
    """Warnings for the worlds of ``world_file`` (the first ``most``, those with a start
    and a goal) whose every way the occupancy grid of the ``mapping`` strategy may close,
    though the agent fits through (see :meth:`copi.online.Mapping.closes_the_way`)."""
    from copi.online import Mapping
    from copi.planning import shortest_path

    grid = Mapping()
    out = []
    for world in load_worlds(world_file)[:most]:
        if world.start is None or world.goal is None:
            continue
        if not grid.closes_the_way(world, world.start, world.goal, agent_radius):
            continue
        if not math.isfinite(shortest_path(world, world.start, world.goal,
                                           radius=agent_radius).length):  # fmt: skip
            continue  # closed for the agent too: skipped as no task, said then
        out.append(
            f"world {world.name!r}: the occupancy grid of the mapping strategy joins walls "
            f"nearer than {grid.join:g} to each other into one, which may close every way "
            "from the start to the goal (a passage narrower than that): expect timeouts "
            "there with --sensor-strategy mapping; greedy, or level map, keep it open"
        )
    return out


@lru_cache(maxsize=64)
def _check_reachable(
    path: str, sha: str, index: int, radius: float, start: tuple, goal: tuple
) -> None:
    from copi.planning import shortest_path

    world = _world_list(path, sha)[index]
    if not math.isfinite(shortest_path(world, start, goal, radius=radius).length):
        raise InvalidWorldError(
            f"world {world.name!r}: no way from the start ({start[0]:.4g}, {start[1]:.4g}) to "
            f"the goal ({goal[0]:.4g}, {goal[1]:.4g}) for an agent of radius {radius:g}: a "
            f"passage narrower than {2 * radius:g} closes it"
        )


def result_row(
    sim: Simulator,
    k: int,
    seed: int,
    optimal: float,
    out: EpisodeOutcome,
    *,
    family: str,
    sensing: str,
    strategy: str = "route",
) -> EpisodeResult:
    """The stored row of one agent's episode (``sim`` after the episode)."""
    success = out.outcome == "success"
    excess = (
        out.path_length / optimal - 1
        if success and math.isfinite(optimal) and optimal > 0
        else math.nan
    )
    trajectory = None
    if sim.record:
        trajectory = {
            "world": sim.world.to_dict(),
            "path": np.asarray(sim.path).round(4).tolist(),
            "traces": np.asarray(sim.traces).round(4).tolist(),
            "radii": sim.radii.tolist(),
            "goal": sim.goal.tolist(),
            "outcome": out.outcome,
        }
    return EpisodeResult(
        episode=k,
        world=sim.world.name,
        seed=seed,
        success=success,
        reached=out.reached,
        collided=out.outcome == "collision",
        timed_out=out.outcome == "timeout",
        steps=out.steps,
        contacts=out.contacts,
        path_length=out.path_length,
        optimal_length=optimal,
        excess=excess,
        decision_us=out.decision_us,
        strategy_us=0.0,
        unfamiliar=float(out.counters.get("unfamiliar", 0.0)),
        no_policy=out.no_policy,
        family=family,
        sensing=sensing,
        outcome=out.outcome,
        time_to_goal=out.time_to_goal,
        min_clearance=out.min_clearance,
        smoothness=out.smoothness,
        trajectory=trajectory,
        strategy=strategy,
    )


def evaluate_episode(config: NavigationConfig, k: int) -> EpisodeResult:
    """Episode k of a run: draw the task, measure the optimum on the frozen snapshot,
    then run the method online. Depends only on (config, k)."""
    spec = method_spec(config.method)
    if config.world_file is None:
        check_family_inputs(config.family, config.inputs)
    caps = None
    n_rays, max_range = 32, 10.0
    if spec.capabilities is not None:
        assert config.capabilities is not None
        caps = _capabilities(config.capabilities, config.capabilities_sha)
        n_rays, max_range = caps.n_rays, float(caps.params.get("max_range", 10.0))
    try:
        sim = draw_episode(
            config.family, k, config.seed, world_file=config.world_file,
            world_file_sha=config.world_file_sha,
            agent_radius=config.agent_radius, n_rays=n_rays, max_range=max_range,
            record=k < config.record,
        )  # fmt: skip
    except InvalidWorldError as exc:
        name = episode_world_name(
            config.family, k, world_file=config.world_file, world_file_sha=config.world_file_sha
        )
        return skipped_row(
            k, config.seed, name, str(exc), family=config.row_family, sensing=config.sensing,
            strategy=config.strategy,
        )  # fmt: skip
    optimal = optimal_to_goal(sim)
    agent = make_agent(config.method, caps, **config.agent_params())
    out = run_episode(
        agent, sim, sensing=config.sensing, max_steps=config.max_steps,
        end_on_contact=config.end_on_contact, strategy=config.sensor_strategy,
    )  # fmt: skip
    return result_row(
        sim, k, config.seed, optimal, out, family=config.row_family, sensing=config.sensing,
        strategy=config.strategy,
    )  # fmt: skip


def check_world_file(path: str | os.PathLike[str], *, agent_radius: float = 0.3) -> None:
    """Refuse a world file any of whose worlds has no valid task, naming the file and the
    world (before a run is registered)."""
    for i, world in enumerate(load_worlds(path)):
        try:
            check_task(world, radius=agent_radius)
        except InvalidWorldError as exc:
            raise WorldFileError(f"{path}: world {i}: {exc}") from None


def evaluate_episodes(config: NavigationConfig, episodes: list[int]) -> list[EpisodeResult]:
    """Several episodes of a run (in order)."""
    return [evaluate_episode(config, k) for k in episodes]


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
    caps = None
    if config.capabilities is not None:  # before anything is written
        caps = _capabilities(config.capabilities, config.capabilities_sha)
        check_method_capabilities(config.method, caps, config.capabilities)
    # the method is built once now: a file it reads (weights) is checked before anything
    # is written
    make_agent(config.method, caps, **config.agent_params())
    if config.world_file is not None:
        check_world_file(config.world_file, agent_radius=config.agent_radius)
    return config.run_into(
        output, experiment="navigation", method=config.method, table="episodes",
        total=config.worlds, item=evaluate_episode, unit="episodes", chunk=16,
        workers=workers, scheduler=scheduler, progress=progress,
    )  # fmt: skip
