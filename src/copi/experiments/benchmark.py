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

from copi.errors import InvalidArgumentError, InvalidWorldError
from copi.experiments._episode import optimal_to_goal, run_agent
from copi.experiments._runs import (
    Tally,
    check_family_inputs,
    code_version,
    execute,
    file_sha,
    stops_cleanly,
)
from copi.experiments.methods import (
    CAPABILITY_PRESETS,
    check_method_capabilities,
    make_agent,
    method_spec,
    parse_methods,
)
from copi.experiments.navigation import (
    EpisodeResult,
    _capabilities,
    draw_episode,
    episode_world_name,
    result_row,
    skipped_row,
)
from copi.geometry._arrays import positive_int
from copi.learning import Capabilities, LearnParams
from copi.online import check_strategy
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
    """One benchmark: which methods, at which levels, on which families, how many episodes."""

    methods: tuple[tuple[str, str], ...]
    """(method, sensing level) pairs (see :func:`copi.experiments.methods.parse_methods`)."""
    families: tuple[str, ...] = BENCHMARK_FAMILIES
    episodes: int = 1000
    """Episodes per family (0 .. episodes - 1)."""
    seed: int = 0
    """Reported episodes use this seed; parameters were tuned on other seeds."""
    end_on_contact: bool = True
    """A contact with a moving obstacle ends the episode (a collision)."""
    sensor_strategy: str = "greedy"
    """The global strategy of every method at level ``sensor``: "greedy" (head for the
    goal) or "mapping" (map as it goes, :class:`copi.online.Mapping`)."""
    agent_radius: float = 0.3
    capabilities: dict[str, str] = field(default_factory=dict)
    """Capabilities file per preset ("faithful", "extended") for copi's methods."""
    capabilities_sha: dict[str, str] = field(default_factory=dict)
    inputs: dict[str, dict[str, str]] = field(default_factory=dict)
    """Per family, the content hashes of the data it draws from
    (:func:`copi.world.family_inputs`; filled in by :meth:`resolved`)."""

    def __post_init__(self) -> None:
        positive_int(self.episodes, "episodes")
        check_strategy(self.sensor_strategy)
        if not self.families:
            raise InvalidArgumentError("families must name at least one family; got none")
        for f in self.families:
            check_family(f)
        for m, level in self.methods:
            parse_methods(f"{m}@{level}")
        for m, _ in self.methods:
            preset = method_spec(m).capabilities
            if preset is not None and preset not in self.capabilities:
                raise InvalidArgumentError(f"{m} needs the {preset!r} capabilities file")

    def resolved(self) -> BenchmarkConfig:
        """With the content hash of each capabilities file (checks each loads)."""
        shas = {}
        for preset, path in self.capabilities.items():
            caps = Capabilities.load(path)
            for m, _ in self.methods:
                if method_spec(m).capabilities == preset:
                    check_method_capabilities(m, caps, path)
            shas[preset] = file_sha(path)
        inputs = {f: family_inputs(f) for f in self.families}
        return dataclasses.replace(self, capabilities_sha=shas, inputs=inputs)

    def identity(self, family: str, method: str, sensing: str) -> dict[str, Any]:
        """What makes one (family, method, level) run the same run: not the number of
        episodes (a longer run extends a shorter one) nor any path."""
        spec = method_spec(method)
        ident: dict[str, Any] = {
            "family": family,
            "method": method,
            "sensing": sensing,
            "seed": self.seed,
            "end_on_contact": self.end_on_contact,
            "agent_radius": self.agent_radius,
            "params": spec.params,
            "max_steps": "min(1000, ceil(3 optimal + 100))",
            "code": code_version(),
            **self.inputs.get(family, {}),
        }
        if sensing == "sensor" and self.sensor_strategy != "greedy":
            ident["strategy"] = self.sensor_strategy
        if spec.capabilities is not None:
            ident["capabilities_sha"] = self.capabilities_sha.get(spec.capabilities, "")
        return ident

    def run_id(self, family: str, method: str, sensing: str) -> str:
        text = json.dumps(self.identity(family, method, sensing), sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def run_item(
    config: BenchmarkConfig, family: str, k: int, todo: list[tuple[str, str, str]]
) -> list[tuple[str, str, EpisodeResult]]:
    """Episode k of ``family`` for each (run_id, method, level) in ``todo``."""
    check_family_inputs(family, config.inputs.get(family, {}))
    try:
        base = draw_episode(family, k, config.seed, agent_radius=config.agent_radius)
    except InvalidWorldError as exc:  # recorded, so that the run goes on
        name = episode_world_name(family, k)
        return [
            (rid, m, skipped_row(k, config.seed, name, str(exc), family=family, sensing=level))
            for rid, m, level in todo
        ]
    optimal = optimal_to_goal(base)
    max_steps = benchmark_max_steps(optimal)
    out = []
    for run_id, method, level in todo:
        preset = method_spec(method).capabilities
        caps = None
        if preset is not None:
            caps = _capabilities(
                config.capabilities[preset], config.capabilities_sha.get(preset, "")
            )
        sim = copy.deepcopy(base)
        agent = make_agent(method, caps)
        res = run_agent(
            agent, sim, sensing=level, max_steps=max_steps, end_on_contact=config.end_on_contact,
            strategy=config.sensor_strategy,
        )  # fmt: skip
        out.append(
            (run_id, method, result_row(sim, k, config.seed, optimal, res, family=family,
                                        sensing=level))
        )  # fmt: skip
    return out


def run_items(
    config: BenchmarkConfig, items: list[tuple[str, int, list[tuple[str, str, str]]]]
) -> list[tuple[str, str, EpisodeResult]]:
    """Several items in one task (fewer round trips to the workers)."""
    return [row for f, k, todo in items for row in run_item(config, f, k, todo)]


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
        params = dataclasses.replace(CAPABILITY_PRESETS[preset], seed=seed)
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
) -> dict[tuple[str, str, str], str]:
    """Run (or resume) the benchmark into the results file ``output``; returns the run id
    of each (family, method, level)."""
    from copi.experiments.store import ResultsStore

    config = config.resolved()
    runs: dict[tuple[str, str, str], str] = {}
    with ResultsStore(output) as store:
        missing: dict[tuple[str, int], list[tuple[str, str, str]]] = {}
        total = 0
        for family in config.families:
            for method, level in config.methods:
                rid = config.run_id(family, method, level)
                runs[(family, method, level)] = rid
                ident = config.identity(family, method, level)
                store.begin(rid, "benchmark", method, ident)
                done = store.done(rid, method)
                for k in range(config.episodes):
                    total += 1
                    if k not in done:
                        missing.setdefault((family, k), []).append((rid, method, level))
        items = [(f, k, todo) for (f, k), todo in missing.items()]
        tally = Tally(total - sum(len(t) for _, _, t in items), total)
        if progress is not None:
            progress(tally.finished, total)

        def commit(rows: list[tuple[str, str, EpisodeResult]]) -> None:
            for rid, method, result in rows:
                store.add(rid, "benchmark", method, result)
                tally.finished += 1
            if progress is not None:
                progress(tally.finished, total)

        if not items:
            return runs

        def saved() -> int:
            return sum(len(store.done(rid, m)) for (_, m, _), rid in runs.items())

        execute(
            config, items, one=lambda c, item: run_item(c, *item), many=run_items,
            commit=commit, workers=workers, scheduler=scheduler, chunk=8,
            stopping=stops_cleanly(tally, output, "episodes", saved),
        )  # fmt: skip
    return runs
