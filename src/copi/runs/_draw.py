"""Episodes drawn the same for every method: episode k of a family (or of a world file)
from ``default_rng([seed, k])``, its optimum on the frozen snapshot, its step limit, and
the row it leaves in the store.

:class:`Episode` is the one sequence every experiment, study and training loop runs:
draw, measure the optimum, set the step limit, run a method on a fresh copy of the
simulator (as many methods as wanted, each meeting exactly the same episode), make the
row."""

from __future__ import annotations

import copy
import math
import os
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from copi._files import file_sha
from copi.core import Agent, Sensing
from copi.errors import InvalidWorldError, MethodError, WorldFileError
from copi.learning import Capabilities
from copi.online import ContextController, LearntAgent, Mapping
from copi.planning import check_plannable, check_size, shortest_path
from copi.results import EpisodeRow
from copi.runs._episode import EpisodeOutcome, optimal_to_goal, run_episode
from copi.world import (
    RangeSensor,
    Simulator,
    World,
    check_task,
    family_spec,
    load_worlds,
    sample_world,
)

__all__ = [
    "Episode",
    "check_world_file",
    "draw_episode",
    "episode_world_name",
    "load_capabilities",
    "mapping_closes",
    "result_row",
    "skipped_row",
    "step_limit",
    "world_file_label",
]


def step_limit(optimal: float) -> int:
    """The step limit of an episode: three times its optimum plus 100 (1000 at most, and
    when there is no optimum), so a stuck method costs little and a slow one has room."""
    if not math.isfinite(optimal):
        return 1000
    return int(min(1000, math.ceil(3.0 * optimal + 100)))


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
) -> EpisodeRow:
    """The stored row of an episode whose world has no valid task: recorded as such, so
    that a run goes on (and a resumed run does not stop there again)."""
    nan = math.nan
    return EpisodeRow(
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
def load_capabilities(path: str, sha: str = "") -> Capabilities:
    """The capabilities file ``path`` (of content hash ``sha``: a rewritten file is read
    again), loaded once per process with its compiled chain, so that no episode's
    decision time includes either."""
    del sha  # part of the cache key
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
    for every method, so that methods can be compared episode by episode. A family with
    its own episode settings (:class:`copi.world.EpisodeSettings`: CrowdNav's scenarios)
    sets the agent's radius, the goal's tolerance and the ring's range itself."""
    rng = np.random.default_rng([seed, k])
    extra: dict[str, Any] = {}
    if world_file is not None:
        worlds = _world_list(world_file, world_file_sha)
        world = worlds[k % len(worlds)]
    else:
        world = sample_world(family, rng, name=f"{family}-{k:05d}")
        own = family_spec(family).episode
        if own is not None:
            agent_radius, max_range = own.agent_radius, own.max_range
            extra["goal_tolerance"] = own.goal_tolerance
    sensor = RangeSensor(n_rays, max_range)
    sim = Simulator.from_world(world, rng, agent_radius=agent_radius, sensor=sensor, record=record,
                               **extra)  # fmt: skip
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
) -> EpisodeRow:
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
    return EpisodeRow(
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
        close_steps=out.close_steps,
    )


def check_world_file(path: str | os.PathLike[str], *, agent_radius: float = 0.3) -> None:
    """Refuse a world file any of whose worlds has no valid task, or is too fine for the
    planner that measures every episode's optimum, naming the file and the world (before
    a run is registered)."""
    for i, world in enumerate(load_worlds(path)):
        try:
            check_size(world)  # a few milliseconds, before the geometry that would take minutes
            check_task(world, radius=agent_radius)
            check_plannable(world, radius=agent_radius)
        except InvalidWorldError as exc:
            raise WorldFileError(f"{path}: world {i}: {exc}") from None


@dataclass(frozen=True)
class Episode:
    """Episode ``k`` of a family (or of a world file), drawn once: its simulator at
    t = 0, its optimum on the frozen snapshot (paper §IV's yardstick) and its step
    limit. Every method run on it meets exactly the same world, task and obstacles (the
    obstacles' random walk ignores the agent), each on a fresh copy.

    Examples
    --------
    >>> from copi.baselines import Straight
    >>> ep = Episode.draw("star", 3, seed=0)
    >>> row = ep.row(Straight(), sensing="map")
    >>> row.episode, row.family, row.steps <= ep.max_steps
    (3, 'star', True)
    """

    family: str
    """The family its rows name (``file:NAME`` for a world file's)."""
    k: int
    seed: int
    sim: Simulator
    """The episode at t = 0; never stepped (each run steps a copy)."""
    optimal: float
    """:func:`~copi.runs.optimal_to_goal` of the snapshot at t = 0 (NaN: no way)."""
    max_steps: int
    """The step limit (:func:`step_limit` of the optimum, unless set)."""

    @classmethod
    def draw(
        cls,
        family: str,
        k: int,
        seed: int = 0,
        *,
        world_file: str | None = None,
        world_file_sha: str = "",
        agent_radius: float = 0.3,
        n_rays: int = 32,
        max_range: float = 10.0,
        record: bool = False,
        max_steps: int | None = None,
    ) -> Episode:
        """Draw episode ``k`` (see :func:`draw_episode`; ``max_steps``: a fixed step limit
        instead of :func:`step_limit`'s). Raises :class:`~copi.errors.InvalidWorldError`
        when a world file's world has no way through for the agent."""
        sim = draw_episode(
            family, k, seed, world_file=world_file, world_file_sha=world_file_sha,
            agent_radius=agent_radius, n_rays=n_rays, max_range=max_range, record=record,
        )  # fmt: skip
        optimal = optimal_to_goal(sim)
        label = world_file_label(world_file) if world_file is not None else family
        own = family_spec(family).episode if world_file is None else None
        if max_steps is None and own is not None and own.max_steps is not None:
            max_steps = own.max_steps  # the family's own limit (CrowdNav's 24 s)
        limit = step_limit(optimal) if max_steps is None else int(max_steps)
        return cls(label, k, seed, sim, optimal, limit)

    def fresh(self) -> Simulator:
        """A copy of the episode at t = 0, to step."""
        return copy.deepcopy(self.sim)

    def run(
        self,
        agent: Agent,
        *,
        sensing: Sensing,
        strategy: str = "greedy",
        end_on_contact: bool = True,
        sim: Simulator | None = None,
    ) -> EpisodeOutcome:
        """Run ``agent`` at ``sensing`` on a fresh copy (or on ``sim``, a copy the caller
        keeps) within the step limit; ``strategy``: the global strategy at level
        ``sensor`` (above it, the method follows the route)."""
        own = None if self.family.startswith("file:") else family_spec(self.family).episode
        try:
            return run_episode(
                agent, self.fresh() if sim is None else sim, sensing=sensing,
                max_steps=self.max_steps, end_on_contact=end_on_contact,
                strategy=strategy if sensing == "sensor" else "greedy",
                discomfort=None if own is None else own.discomfort,
            )  # fmt: skip
        except MethodError as exc:
            raise MethodError(f"{exc} (episode {self.k} of {self.family}, seed {self.seed}, "
                              f"level {sensing})") from None  # fmt: skip

    def row(
        self,
        agent: Agent,
        *,
        sensing: Sensing,
        strategy: str = "greedy",
        end_on_contact: bool = True,
    ) -> EpisodeRow:
        """Run ``agent`` as :meth:`run` does and make its row in the store."""
        sim = self.fresh()
        out = self.run(agent, sensing=sensing, strategy=strategy, end_on_contact=end_on_contact,
                       sim=sim)  # fmt: skip
        return result_row(
            sim, self.k, self.seed, self.optimal, out, family=self.family, sensing=sensing,
            strategy=strategy if sensing == "sensor" else "route",
        )  # fmt: skip
