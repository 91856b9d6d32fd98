"""The navigation benchmark: every method, at its sensing levels, on the same episodes of
every world family, into one resumable results store.

Episode k of a family draws its world, task and obstacles from ``default_rng([seed, k])``
(the obstacles' random walk ignores the agent), so every method meets exactly the same
episode and results can be compared pair by pair. One work item is one episode: the world
is drawn and the optimum computed once, then each method still missing for it runs on a
fresh copy of the simulator. Rows are committed as items come back; rerunning resumes.
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import json
import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from copi._rng import check_seed
from copi._validation import positive_int
from copi.errors import InvalidArgumentError, InvalidWorldError
from copi.experiments._episode import optimal_to_goal, run_episode
from copi.experiments._runs import (
    MAX_EPISODES,
    Series,
    check_count,
    check_family_inputs,
    code_version,
    file_sha,
    run_series,
)
from copi.experiments.methods import (
    MethodRun,
    as_arms,
    check_method_capabilities,
    make_agent,
    method_spec,
    parse_methods,
)
from copi.experiments.navigation import (
    EpisodeResult,
    _capabilities,
    check_world_file,
    draw_episode,
    episode_world_name,
    result_row,
    skipped_row,
    world_file_label,
)
from copi.experiments.presets import PRESETS
from copi.learning import Capabilities, LearnParams
from copi.world import check_family, family_inputs

__all__ = [
    "BENCHMARK_FAMILIES",
    "BenchmarkConfig",
    "benchmark_max_steps",
    "ensure_capabilities",
    "run_benchmark",
]

BENCHMARK_FAMILIES = ("star", "polygon", "indoor", "maps", "crowd")
"""Families in the order the report shows them (the paper's first)."""


def benchmark_max_steps(optimal: float) -> int:
    """The step limit of an episode: three times its optimum plus 100 (1000 at most, and
    when there is no optimum), so a stuck method costs little and a slow one has room."""
    if not math.isfinite(optimal):
        return 1000
    return int(min(1000, math.ceil(3.0 * optimal + 100)))


@dataclass(frozen=True)
class BenchmarkConfig:
    """One benchmark: which methods (each at a level, with a global strategy), on which
    families or worlds, how many episodes."""

    methods: tuple[MethodRun, ...]
    """The arms (see :func:`copi.experiments.methods.parse_methods`; text such as
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
        the methods that run on it) and of the data each family draws from."""
        shas = {}
        for preset, path in self.capabilities.items():
            caps = Capabilities.load(path)
            for run in self.methods:
                if method_spec(run.method).capabilities == preset:
                    check_method_capabilities(run.method, caps, path)
            shas[preset] = file_sha(path)
        for run in self.methods:  # each method built once: the files it reads are checked
            needs = method_spec(run.method).capabilities
            make_agent(run.method, None if needs is None else _capabilities(
                self.capabilities[needs], shas[needs]))  # fmt: skip
        if self.world_file is not None:
            check_world_file(self.world_file, agent_radius=self.agent_radius)
            inputs = {self.groups[0]: {"world_file_sha": file_sha(self.world_file)}}
        else:
            inputs = {f: family_inputs(f) for f in self.families}
        return dataclasses.replace(self, capabilities_sha=shas, inputs=inputs)

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
        text = json.dumps(self.identity(family, run), sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:16]

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
) -> list[tuple[Series, EpisodeResult]]:
    """Episode k of ``family`` (or of the world file) for each series in ``todo``: the
    world is drawn and the optimum computed once, then each method runs on a fresh copy
    of the simulator."""
    check_family_inputs(family, config.inputs.get(family, {}), config.world_file)
    world_file = config.world_file
    try:
        base = draw_episode(
            family, k, config.seed, agent_radius=config.agent_radius, world_file=world_file,
            world_file_sha=config.inputs.get(family, {}).get("world_file_sha", ""),
        )  # fmt: skip
    except InvalidWorldError as exc:  # recorded, so that the run goes on
        name = episode_world_name(family, k)
        return [
            (s, skipped_row(k, config.seed, name, str(exc), family=family,
                            sensing=s.config["sensing"], strategy=s.config["strategy"]))
            for s in todo
        ]  # fmt: skip
    optimal = optimal_to_goal(base)
    max_steps = benchmark_max_steps(optimal)
    out = []
    for s in todo:
        method, sensing, strategy = s.method, s.config["sensing"], s.config["strategy"]
        preset = method_spec(method).capabilities
        caps = None
        if preset is not None:
            caps = _capabilities(
                config.capabilities[preset], config.capabilities_sha.get(preset, "")
            )
        sim = copy.deepcopy(base)
        agent = make_agent(method, caps)
        res = run_episode(
            agent, sim, sensing=sensing, max_steps=max_steps,
            end_on_contact=config.end_on_contact,
            strategy=strategy if sensing == "sensor" else "greedy",
        )  # fmt: skip
        out.append((s, result_row(sim, k, config.seed, optimal, res, family=family,
                                  sensing=sensing, strategy=strategy)))  # fmt: skip
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
    from copi.learning import learn

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
