"""Experiment 3, lifelong: an agent that keeps working in one world, task after task
(paper §I's long-lived agent; §III's causal map; §II-A and §III's continual contexts).

In each of ``worlds`` worlds of a family the agent lives through ``tasks`` successive
tasks: task t starts where task t - 1's goal was (task 0 at a drawn start) and has a new
goal; the moving obstacles are drawn anew for each task. World w and all its tasks come
from ``default_rng([seed, w])`` and ``default_rng([seed, w, t + 1])``, so every method
meets exactly the same tasks and can be compared task by task. A task that fails (a
contact, a timeout) leaves the agent where it stopped; it is carried to the next start,
and its odometry (its position less where its life began) says so: the agent knows where
it is in its own frame, never the map.

Arms (:data:`LIFELONG_METHODS`) differ in what they keep from task to task: the
``causal`` strategy keeps its causal map and occupancy grid, ``mapping`` keeps the grid
(like for like with the baselines, which keep their grids too), ``copi-learnt-continual``
also keeps the contexts it grew. One work item is one world: its tasks and their optima are drawn
once, then each method still missing for it lives its life there; a life's rows are
committed together, so a rerun resumes at the first world not finished.
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from copi._files import file_sha
from copi._rng import check_seed
from copi._validation import check_count, positive_int
from copi.errors import InvalidArgumentError, InvalidWorldError, MethodError
from copi.learning import Capabilities
from copi.methods import (
    LIFELONG_METHODS,
    LIFELONG_REFERENCE,
    MethodRun,
    as_arms,
    check_preset_capabilities,
    make_agent,
    method_spec,
    parse_lifelong_methods,
)
from copi.online import CausalStrategy
from copi.results import LifeRow
from copi.runs import (
    MAX_LIFE_TASKS,
    MAX_LIVES,
    MAX_TASKS,
    Series,
    check_family_inputs,
    code_version,
    load_capabilities,
    optimal_to_goal,
    resolve_inputs,
    run_episode,
    run_id,
    run_series,
    step_limit,
)
from copi.world import (
    RangeSensor,
    Simulator,
    check_family,
    place_obstacles,
    sample_start_goal,
    sample_world,
)

__all__ = [
    "LIFELONG_METHODS",
    "LifelongConfig",
    "REFERENCE",
    "draw_life",
    "parse_lifelong_methods",
    "run_lifelong",
]

REFERENCE = LIFELONG_REFERENCE
"""The arm every other arm of Experiment 3 is paired against
(:data:`copi.methods.LIFELONG_REFERENCE`)."""


@dataclass(frozen=True)
class LifelongConfig:
    """One run of Experiment 3."""

    capabilities: str | None
    """The ``learnt`` preset's capabilities file (copi's methods need it)."""
    family: str = "indoor"
    worlds: int = 20
    tasks: int = 50
    seed: int = 0
    methods: tuple[MethodRun, ...] = dataclasses.field(
        default_factory=lambda: parse_lifelong_methods(None)
    )
    """The arms (text such as ``"dwa@sensor:mapping"`` is parsed); default: every arm of
    :data:`LIFELONG_METHODS`."""
    agent_radius: float = 0.3
    capabilities_sha: str = ""
    maps: str | None = None
    """A directory to save each (method, world)'s causal map in at the end of its life."""
    from_maps: str | None = None
    """A directory of causal maps saved by an earlier run (``maps``): each causal
    method's life starts from its map of that world (a life resumed)."""
    from_maps_sha: str = ""
    inputs: dict[str, str] = dataclasses.field(default_factory=dict)
    """Content hashes of the data the family draws from (:func:`copi.world.family_inputs`,
    filled in by :meth:`resolved`)."""

    def __post_init__(self) -> None:
        check_family(self.family)
        positive_int(self.worlds, "worlds")
        positive_int(self.tasks, "tasks")
        check_count(self.worlds, "worlds", MAX_LIVES)
        check_count(self.tasks, "tasks", MAX_TASKS)
        check_count(self.worlds * self.tasks, "worlds x tasks", MAX_LIFE_TASKS)
        check_seed(self.seed)
        if not self.methods:
            raise InvalidArgumentError("methods must name at least one method; got none")
        # arms may be given as text, as on the command line
        object.__setattr__(self, "methods", as_arms(self.methods, parse_lifelong_methods))
        needs = [m for m in self.methods if method_spec(m.method).capabilities]
        if needs and self.capabilities is None:
            raise InvalidArgumentError(
                f"{needs[0].label} needs the learnt preset's capabilities file"
            )

    def resolved(self) -> LifelongConfig:
        """With the content hashes of its inputs (:func:`copi.runs.resolve_inputs`): the
        capabilities file must hold what the learnt preset needs, for the lives' sensor;
        the causal maps a run starts from (``from_maps``) must each load for its world."""
        if self.capabilities is not None:
            caps = Capabilities.load(self.capabilities)
            check_preset_capabilities("learnt", caps, self.capabilities)
            rays = RangeSensor().n_rays  # the lives' sensor
            if caps.n_rays != rays:
                raise InvalidArgumentError(
                    f"the capabilities were learnt for {caps.n_rays} rays; the sensor has {rays}"
                )
        found = resolve_inputs(
            capabilities={} if self.capabilities is None else {"learnt": self.capabilities},
            methods=[r.method for r in self.methods], families=[self.family],
            agent_radius=self.agent_radius,
        )  # fmt: skip
        done = dataclasses.replace(
            self, capabilities_sha=found.capabilities_sha.get("learnt", ""),
            inputs=found.families[self.family],
        )  # fmt: skip
        if self.from_maps is None:
            return done
        if self.maps is not None and Path(self.maps).resolve() == Path(self.from_maps).resolve():
            raise InvalidArgumentError(
                f"--maps and --from-maps are both {self.from_maps}: save the maps elsewhere "
                "(the run would overwrite what it starts from)"
            )
        # Every map the run will start from, checked now (before anything is written),
        # as the strategy will load it.
        for run in self.methods:
            if run.strategy != "causal":
                continue
            for life in range(self.worlds):
                path = causal_map_path(self.from_maps, run, self.family, life, self.seed)
                if not path.is_file():
                    raise InvalidArgumentError(
                        f"{self.from_maps}: no causal map of {run.label} in world "
                        f"{world_identity(self.family, life, self.seed)} ({path.name})"
                    )
                CausalStrategy.load(path, world=world_identity(self.family, life, self.seed),
                                    capabilities=done.capabilities_sha)  # fmt: skip
        # The run's identity: every map of this family and seed in the directory (not
        # only those of the worlds asked for, so that more worlds extend the run).
        h = hashlib.sha256()
        pattern = f"*-{self.family}-life-*-seed-{self.seed}.npz"
        for path in sorted(Path(self.from_maps).glob(pattern)):
            h.update(path.name.encode() + bytes.fromhex(file_sha(path)))
        return dataclasses.replace(done, from_maps_sha=h.hexdigest())

    def identity(self, run: MethodRun) -> dict[str, Any]:
        """What makes an arm's run the same run: not the number of worlds (more worlds
        extend a run), nor any path."""
        spec = method_spec(run.method)
        ident: dict[str, Any] = {
            "experiment": "lifelong", "family": self.family, "tasks": self.tasks,
            "seed": self.seed, "method": run.method, "sensing": run.sensing,
            "strategy": run.strategy, "params": spec.params,
            "agent_radius": self.agent_radius, "code": code_version(),
            "max_steps": "min(1000, ceil(3 optimal + 100))", **self.inputs,
        }  # fmt: skip
        if spec.capabilities is not None:
            ident["capabilities_sha"] = self.capabilities_sha
        if self.from_maps is not None and run.strategy == "causal":
            ident["from_maps_sha"] = self.from_maps_sha
        ident.update(spec.input_hashes())
        return ident

    def run_id(self, run: MethodRun) -> str:
        return run_id(self.identity(run))

    def series(self) -> list[Series]:
        """Every arm's run: its lives 0 .. worlds - 1."""
        return [
            Series(self.run_id(r), "lifelong", r.method, self.identity(r), "lifelong",
                   self.worlds)
            for r in self.methods
        ]  # fmt: skip


def world_identity(family: str, life: int, seed: int) -> str:
    """The name a causal map file records for the world it was learnt in."""
    return f"{family}-life-{life:04d}-seed-{seed}"


def causal_map_path(
    directory: str, run: MethodRun, family: str, life: int, seed: int
) -> Path:
    """Where a run saves (``maps``) and finds (``from_maps``) a life's causal map."""
    name = f"{run.method}-{run.sensing}-{run.strategy}"
    return Path(directory) / f"{name}-{world_identity(family, life, seed)}.npz"


def draw_life(
    family: str, life: int, seed: int, tasks: int, *, agent_radius: float = 0.3
) -> list[Simulator]:
    """The simulators of life ``life``'s tasks, each fresh at t = 0 (see the module)."""
    rng = np.random.default_rng([seed, life])
    world = sample_world(family, rng, name=world_identity(family, life, seed))
    spec = world.obstacles
    sims = []
    start: Any = None
    for t in range(tasks):
        r = np.random.default_rng([seed, life, t + 1])
        w = world if start is None else world.replace(start=start, goal=None)
        s, g = sample_start_goal(w, r, radius=agent_radius, min_distance=10.0)
        kwargs = {} if spec is None else {"spec": spec}
        centers, radii = place_obstacles(
            world, r, keep_clear=np.vstack([s, g]), keep_clear_radius=agent_radius + 1.0,
            **kwargs,
        )  # fmt: skip
        sims.append(
            Simulator(world, s, g, centers, radii, seed=r, agent_radius=agent_radius,
                      sensor=RangeSensor(), speed=spec.speed if spec is not None else 0.6)
        )  # fmt: skip
        start = g
    return sims


def _arm(series: Series) -> MethodRun:
    c = series.config
    return MethodRun(c["method"], c["sensing"], c["strategy"])


def live(
    config: LifelongConfig, run: MethodRun, life: int, sims: list[Simulator],
    optima: list[float],
) -> list[LifeRow]:  # fmt: skip
    """Arm ``run``'s life in world ``life``: its tasks in order, one agent throughout."""
    caps = None
    if method_spec(run.method).capabilities is not None:
        assert config.capabilities is not None
        caps = load_capabilities(config.capabilities, config.capabilities_sha)
    agent = make_agent(run.method, caps)
    ident = world_identity(config.family, life, config.seed)
    steering = getattr(agent, "steering", None)
    if config.from_maps is not None and run.strategy == "causal" and steering is not None:
        steering.causal = CausalStrategy.load(
            causal_map_path(config.from_maps, run, config.family, life, config.seed),
            world=ident, capabilities=config.capabilities_sha,
        )  # fmt: skip
    origin = sims[0].position.copy()
    rows = []
    strategy = run.strategy if run.sensing == "sensor" else "greedy"
    for t, (base, optimal) in enumerate(zip(sims, optima, strict=True)):
        sim = copy.deepcopy(base)
        try:
            res = run_episode(
                agent, sim, sensing=run.sensing, max_steps=step_limit(optimal),
                strategy=strategy, origin=origin,
            )  # fmt: skip
        except MethodError as exc:
            raise MethodError(f"{exc} (life {life}, task {t} of {config.family}, seed "
                              f"{config.seed})") from None  # fmt: skip
        success = res.outcome == "success"
        causal = getattr(steering, "causal", None)
        rows.append(
            LifeRow(
                world=sim.world.name, life=life, task=t, seed=config.seed,
                family=config.family, sensing=run.sensing, outcome=res.outcome,
                success=success, steps=res.steps, path_length=res.path_length,
                optimal_length=optimal,
                excess=res.path_length / optimal - 1 if success and optimal > 0 else math.nan,
                decision_us=res.decision_us,
                unfamiliar=float(res.counters.get("unfamiliar", math.nan)),
                grown=int(res.counters.get("grown", 0)),
                options=0 if causal is None else causal.map.n_options,
                strategy=run.strategy,
            )  # fmt: skip
        )
    causal = getattr(steering, "causal", None)
    if config.maps is not None and causal is not None:
        Path(config.maps).mkdir(parents=True, exist_ok=True)
        causal.save(causal_map_path(config.maps, run, config.family, life, config.seed),
                    world=ident, capabilities=config.capabilities_sha)  # fmt: skip
    return rows


def run_life(
    config: LifelongConfig, group: Any, life: int, todo: list[Series]
) -> list[tuple[Series, list[LifeRow]]]:
    """World ``life``: its tasks drawn and their optima computed once, then the life of
    each series in ``todo``."""
    check_family_inputs(config.family, config.inputs)
    try:
        sims = draw_life(config.family, life, config.seed, config.tasks,
                         agent_radius=config.agent_radius)  # fmt: skip
    except InvalidWorldError:  # recorded as skipped, so that the run goes on (and ends)
        return [(s, _skipped(config, _arm(s), life)) for s in todo]
    optima = [optimal_to_goal(s) for s in sims]
    return [(s, live(config, _arm(s), life, sims, optima)) for s in todo]


def _skipped(config: LifelongConfig, run: MethodRun, life: int) -> list[LifeRow]:
    """The rows of a life whose world has no valid chain of tasks (counted in no rate)."""
    nan = math.nan
    return [
        LifeRow(
            world=world_identity(config.family, life, config.seed), life=life, task=t,
            seed=config.seed, family=config.family, sensing=run.sensing,
            outcome="skipped", success=False, steps=0, path_length=nan, optimal_length=nan,
            excess=nan, decision_us=nan, unfamiliar=nan, grown=0, options=0,
            strategy=run.strategy,
        )  # fmt: skip
        for t in range(config.tasks)
    ]


def run_lifelong(
    config: LifelongConfig,
    output: str | os.PathLike[str],
    *,
    workers: int = 1,
    scheduler: str | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> dict[MethodRun, str]:
    """Run (or resume) Experiment 3 into the results file ``output``; returns the run id
    of each arm."""
    config = config.resolved()
    series = config.series()
    run_series(config, output, series, work=run_life, unit="lives", workers=workers,
               scheduler=scheduler, progress=progress, chunk=1)  # fmt: skip
    return {run: s.run_id for run, s in zip(config.methods, series, strict=True)}
