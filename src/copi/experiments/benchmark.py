"""The navigation benchmark: every method, at its sensing levels, on the same episodes of
every world family, into one resumable results store.

Episode k of a family draws its world, task and obstacles from ``default_rng([seed, k])``
(the obstacles' random walk ignores the agent), so every method meets exactly the same
episode and results can be compared pair by pair. One work item is one episode: the world
is drawn and the optimum computed once, then each method still missing for it runs on a
fresh copy of the simulator. Rows are committed as items come back; rerunning resumes.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from copi._rng import check_seed
from copi._validation import check_count, positive_int
from copi.errors import InvalidArgumentError, InvalidWorldError
from copi.learning import Capabilities, LearnParams, learn
from copi.methods import PRESETS, MethodRun, as_arms, make_agent, method_spec, parse_methods
from copi.results import EpisodeRow
from copi.runs import (
    MAX_EPISODES,
    Episode,
    Series,
    check_family_inputs,
    code_version,
    episode_world_name,
    load_capabilities,
    resolve_inputs,
    run_id,
    run_series,
    skipped_row,
    step_limit,
    world_file_label,
)
from copi.world import BENCHMARK_FAMILIES, check_family

__all__ = [
    "BENCHMARK_FAMILIES",
    "BenchmarkConfig",
    "benchmark_max_steps",
    "ensure_capabilities",
    "run_benchmark",
]

benchmark_max_steps = step_limit
"""An episode's step limit (:func:`copi.runs.step_limit`; the name older code imports)."""


@dataclass(frozen=True)
class BenchmarkConfig:
    """One benchmark: which methods (each at a level, with a global strategy), on which
    families or worlds, how many episodes."""

    methods: tuple[MethodRun, ...]
    """The arms (see :func:`copi.methods.parse_methods`; text such as
    ``"dwa@sensor:mapping"`` is parsed)."""
    families: tuple[str, ...] = BENCHMARK_FAMILIES
    episodes: int = 1000
    """Episodes per family (0 .. episodes - 1)."""
    seed: int = 0
    """Reported episodes use this seed; parameters were tuned on other seeds."""
    end_on_contact: bool = True
    """A contact with a moving obstacle ends the episode (a collision)."""
    agent_radius: float = 0.3
    world_file: str | None = None
    """Run the worlds of this file instead of the families (episode k draws its task in
    world k mod n); the file's name labels its rows as a family's would."""
    capabilities: dict[str, str] = field(default_factory=dict)
    """Capabilities file per preset ("faithful", "learnt", ...) for copi's methods."""
    capabilities_sha: dict[str, str] = field(default_factory=dict)
    inputs: dict[str, dict[str, str]] = field(default_factory=dict)
    """Per family, the content hashes of the data it draws from
    (:func:`copi.world.family_inputs`; the world file's for a world file; filled in by
    :meth:`resolved`)."""

    def __post_init__(self) -> None:
        positive_int(self.episodes, "episodes")
        check_count(self.episodes, "episodes", MAX_EPISODES)
        check_seed(self.seed)
        if not self.methods:
            raise InvalidArgumentError("methods must name at least one method; got none")
        # arms may be given as text ("dwa@sensor:mapping"), as on the command line
        object.__setattr__(self, "methods", as_arms(self.methods))
        for run in self.methods:
            parse_methods(f"{run.method}@{run.sensing}"
                          + (f":{run.strategy}" if run.sensing == "sensor" else ""))
            preset = method_spec(run.method).capabilities
            if preset is not None and preset not in self.capabilities:
                raise InvalidArgumentError(f"{run.method} needs the {preset!r} capabilities file")
        if self.world_file is None:
            if not self.families:
                raise InvalidArgumentError("families must name at least one family; got none")
            for f in self.families:
                check_family(f)

    @property
    def groups(self) -> tuple[str, ...]:
        """The families episodes are drawn from; for a world file, its name alone."""
        if self.world_file is not None:
            return (world_file_label(self.world_file),)
        return self.families

    def resolved(self) -> BenchmarkConfig:
        """With the content hash of each capabilities file (checking each loads and fits
        the methods that run on it), of the world file, and of the data each family
        draws from (:func:`copi.runs.resolve_inputs`)."""
        found = resolve_inputs(
            capabilities=self.capabilities, methods=[r.method for r in self.methods],
            families=() if self.world_file is not None else self.families,
            world_file=self.world_file, agent_radius=self.agent_radius,
        )  # fmt: skip
        if self.world_file is not None:
            inputs = {self.groups[0]: {"world_file_sha": found.world_file_sha}}
        else:
            inputs = found.families
        return dataclasses.replace(self, capabilities_sha=found.capabilities_sha, inputs=inputs)

    def identity(self, family: str, run: MethodRun) -> dict[str, Any]:
        """What makes one (family, arm) run the same run: not the number of episodes (a
        longer run extends a shorter one) nor any path."""
        spec = method_spec(run.method)
        ident: dict[str, Any] = {
            "family": family,
            "method": run.method,
            "sensing": run.sensing,
            "strategy": run.strategy,
            "seed": self.seed,
            "end_on_contact": self.end_on_contact,
            "agent_radius": self.agent_radius,
            "params": spec.params,
            "max_steps": "min(1000, ceil(3 optimal + 100))",
            "code": code_version(),
            **self.inputs.get(family, {}),
        }
        if spec.capabilities is not None:
            ident["capabilities_sha"] = self.capabilities_sha.get(spec.capabilities, "")
        ident.update(spec.input_hashes())
        return ident

    def run_id(self, family: str, run: MethodRun) -> str:
        return run_id(self.identity(family, run))

    def series(self) -> list[Series]:
        """Every (family, arm) run of the benchmark, family by family."""
        return [
            Series(self.run_id(f, r), "benchmark", r.method, self.identity(f, r), "episodes",
                   self.episodes, group=f)
            for f in self.groups
            for r in self.methods
        ]  # fmt: skip


def run_item(
    config: BenchmarkConfig, family: str, k: int, todo: list[Series]
) -> list[tuple[Series, EpisodeRow]]:
    """Episode k of ``family`` (or of the world file) for each series in ``todo``: the
    episode is drawn and its optimum computed once, then each method runs on a fresh
    copy of it."""
    check_family_inputs(family, config.inputs.get(family, {}), config.world_file)
    try:
        episode = Episode.draw(
            family, k, config.seed, agent_radius=config.agent_radius,
            world_file=config.world_file,
            world_file_sha=config.inputs.get(family, {}).get("world_file_sha", ""),
        )  # fmt: skip
    except InvalidWorldError as exc:  # recorded, so that the run goes on
        name = episode_world_name(family, k)
        return [
            (s, skipped_row(k, config.seed, name, str(exc), family=family,
                            sensing=s.config["sensing"], strategy=s.config["strategy"]))
            for s in todo
        ]  # fmt: skip
    out = []
    for s in todo:
        preset = method_spec(s.method).capabilities
        caps = None
        if preset is not None:
            caps = load_capabilities(
                config.capabilities[preset], config.capabilities_sha.get(preset, "")
            )
        row = episode.row(make_agent(s.method, caps), sensing=s.config["sensing"],
                          strategy=s.config["strategy"], end_on_contact=config.end_on_contact)
        out.append((s, row))  # fmt: skip
    return out


def ensure_capabilities(
    directory: str | os.PathLike[str], presets: set[str], *, seed: int = 0
) -> dict[str, str]:
    """The capabilities file of each preset in ``directory``, learnt (seed ``seed``) when
    missing; returns {preset: path}.

    A file already there is used only if it was learnt with exactly the parameters asked
    for (the number of workers aside); otherwise it is refused, with the first parameter
    that differs, and left as it is (results elsewhere may rest on it).
    """
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    paths = {}
    for preset in sorted(presets):
        path = d / f"capabilities-{preset}.npz"
        params = dataclasses.replace(PRESETS[preset].learn, seed=seed)
        if path.exists():
            _check_learnt_with(path, dataclasses.asdict(params))
        else:
            learn(params).save(path)
        paths[preset] = str(path)
    return paths


def _check_learnt_with(path: Path, wanted: dict[str, Any]) -> None:
    stored = Capabilities.load(path).params
    # A parameter added after a file was learnt had its default then.
    defaults = dataclasses.asdict(LearnParams())
    for key in sorted(set(wanted) | set(stored)):
        if key == "workers" or stored.get(key, defaults.get(key)) == wanted.get(key):
            continue
        raise InvalidArgumentError(
            f"{path} was learnt with {key}={stored.get(key, 'unset')!r}, not "
            f"{wanted.get(key, 'unset')!r} as this run asks; use another output directory "
            "(or move that file away to learn it anew)"
        )


def run_benchmark(
    config: BenchmarkConfig,
    output: str | os.PathLike[str],
    *,
    workers: int = 1,
    scheduler: str | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> dict[tuple[str, MethodRun], str]:
    """Run (or resume) the benchmark into the results file ``output``; returns the run id
    of each (family, arm)."""
    config = config.resolved()
    series = config.series()
    run_series(config, output, series, work=run_item, unit="episodes", workers=workers,
               scheduler=scheduler, progress=progress, chunk=8)  # fmt: skip
    arms = [(f, r) for f in config.groups for r in config.methods]
    return {arm: s.run_id for arm, s in zip(arms, series, strict=True)}
