"""Experiment 1 (paper §IV, Fig. 3-4): reach a goal in dynamic worlds never seen, and
compare the path with the optimal one on the stationary snapshot at t = 0."""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from copi._moved import moved_names
from copi._rng import check_seed
from copi._validation import check_count, non_negative, positive_int
from copi.core import Sensing, check_sensing, check_strategy
from copi.errors import InvalidArgumentError, InvalidWorldError
from copi.methods import make_agent, method_spec
from copi.results import EpisodeRow
from copi.runs import (
    MAX_EPISODES,
    Episode,
    check_family_inputs,
    code_version,
    episode_world_name,
    load_capabilities,
    resolve_inputs,
    run_one,
    skipped_row,
    world_file_label,
)
from copi.world import check_family

__all__ = ["NavigationConfig", "evaluate", "evaluate_episode", "evaluate_episodes"]

__getattr__ = moved_names(__name__, {
    "EpisodeResult": "copi.results:EpisodeRow",
    "check_world_file": "copi.runs",
    "draw_episode": "copi.runs",
    "mapping_closes": "copi.runs",
    "result_row": "copi.runs",
    "world_file_label": "copi.runs",
})  # fmt: skip


@dataclass(frozen=True)
class NavigationConfig:
    """One evaluation run of Experiment 1: everything that decides its results."""

    capabilities: str | None
    """Path of the capabilities file, for copi's modes (its content hash, not the path,
    enters the run id); None for the baselines."""
    method: str = "copi-faithful"
    """The method, by its registered name (:func:`copi.methods.method_names`)."""
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
    method_inputs: dict[str, str] = field(default_factory=dict, compare=False)
    """Content hashes of the files the method reads (its weights; filled in by
    :meth:`resolved`)."""

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
        if self.guard is not None:
            non_negative(self.guard, "guard")

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

    def resolved(self) -> NavigationConfig:
        """The config with its inputs' content hashes, every input checked
        (:func:`copi.runs.resolve_inputs`) before anything is written."""
        preset = method_spec(self.method).capabilities or "file"
        found = resolve_inputs(
            capabilities={} if self.capabilities is None else {preset: self.capabilities},
            methods=[self.method], params={self.method: self.agent_params()},
            families=[] if self.world_file is not None else [self.family],
            world_file=self.world_file, agent_radius=self.agent_radius,
        )  # fmt: skip
        return dataclasses.replace(
            self, capabilities_sha=found.capabilities_sha.get(preset, ""),
            world_file_sha=found.world_file_sha, inputs=found.families.get(self.family, {}),
            method_inputs=found.methods[self.method],
        )  # fmt: skip

    def identity(self) -> dict[str, Any]:
        """What makes two runs the same run: the configuration without the input paths,
        with their contents and copi's version."""
        d = dataclasses.asdict(self)
        del d["capabilities"], d["world_file"]
        d.update(d.pop("inputs"))
        d.update(d.pop("method_inputs"))
        d["code"] = code_version()
        return d

    def agent_params(self) -> dict[str, Any]:
        """The method's parameters as this run sets them."""
        p = dict(method_spec(self.method).params)
        if self.guard is not None and "guard" in p:
            p["guard"] = self.guard
        if "continual" in p:
            p["continual"] = self.continual or bool(p["continual"])
        return p


def evaluate_episode(config: NavigationConfig, k: int) -> EpisodeRow:
    """Episode k of a run: draw the task, measure the optimum on the frozen snapshot,
    then run the method online. Depends only on (config, k)."""
    spec = method_spec(config.method)
    if config.world_file is None:
        check_family_inputs(config.family, config.inputs)
    caps = None
    n_rays, max_range = 32, 10.0
    if spec.capabilities is not None:
        assert config.capabilities is not None
        caps = load_capabilities(config.capabilities, config.capabilities_sha)
        n_rays, max_range = caps.n_rays, float(caps.params.get("max_range", 10.0))
    try:
        episode = Episode.draw(
            config.family, k, config.seed, world_file=config.world_file,
            world_file_sha=config.world_file_sha, agent_radius=config.agent_radius,
            n_rays=n_rays, max_range=max_range, record=k < config.record,
            max_steps=config.max_steps,
        )  # fmt: skip
    except InvalidWorldError as exc:
        name = episode_world_name(
            config.family, k, world_file=config.world_file, world_file_sha=config.world_file_sha
        )
        return skipped_row(
            k, config.seed, name, str(exc), family=config.row_family, sensing=config.sensing,
            strategy=config.strategy,
        )  # fmt: skip
    agent = make_agent(config.method, caps, **config.agent_params())
    return episode.row(agent, sensing=config.sensing, strategy=config.sensor_strategy,
                       end_on_contact=config.end_on_contact)  # fmt: skip


def evaluate_episodes(config: NavigationConfig, episodes: list[int]) -> list[EpisodeRow]:
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
    return run_one(
        config, config.identity(), output, experiment="navigation", method=config.method,
        table="episodes", total=config.worlds, item=evaluate_episode, unit="episodes",
        chunk=16, workers=workers, scheduler=scheduler, progress=progress,
    )  # fmt: skip
