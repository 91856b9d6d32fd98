"""Many agents among each other (``copi crowd``): N agents of one registered method in a
square room, each an obstacle in every other's reading, swept over densities, methods
and seeds into a results store.

Run k at a density places its N agents (starts without overlap, goals at least 10 apart
from them, :func:`copi.world.crowd.place_agents`) from ``default_rng([seed, k])``: every
method meets the same crowd, and a result does not depend on where it ran (this process,
local processes, a Dask cluster; tested). An agent's trip ends at its goal (success) or
its first contact (collision), when it leaves the room; one still going at the step
limit timed out. A steady crowd (``steady``) keeps every agent: a new goal on arrival,
contacts only counted; its rows still tell each agent's first trip.

Each run is one item of :func:`copi.runs.run_series`; its rows (one per agent) go to
table ``lifelong`` as one *life* (the run) of N *tasks* (the agents), committed together,
so that a run is resumed whole or not at all. ``family`` and ``world`` name the room
(``crowd-room-N-dD``), so each density is its own series; ``optimal_length`` is the
straight line to the goal less its tolerance (the shortest path in the empty convex
room) and ``decision_us`` the run's mean time of one agent's decision.

A single run uses ``processes`` processes, the agents shared out among them
(:class:`~copi.experiments._crowd_drive.Team`); in a sweep on local processes or Dask,
each run has one.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from copi._rng import check_seed
from copi._validation import check_count, positive_int
from copi.core import SENSING_LEVELS, check_sensing
from copi.errors import InvalidArgumentError
from copi.experiments._crowd_drive import Team, batched, decision_us, make_driver
from copi.methods import make_agent, method_spec
from copi.results import LifeRow
from copi.runs import Series, code_version, load_capabilities, resolve_inputs, run_id, run_series
from copi.world.crowd import (
    COLLISION,
    MAX_AGENTS,
    SUCCESS,
    Crowd,
    check_density,
    crowd_room,
    place_agents,
)

__all__ = [
    "MAX_AGENT_RUNS",
    "MAX_CROWD_RUNS",
    "MAX_CROWD_STEPS",
    "MAX_DENSITIES",
    "CrowdConfig",
    "CrowdRun",
    "draw_crowd",
    "run_crowd",
    "run_crowds",
]

MAX_CROWD_STEPS = 100_000
"""Most steps of one run (at 20 world steps a second, an hour and a half)."""
MAX_CROWD_RUNS = 1_000
"""Most runs (seeds) per method and density."""
MAX_DENSITIES = 20
"""Most densities of one sweep."""
MAX_AGENT_RUNS = 10_000_000
"""Most agents placed in all (agents x runs x densities): each crowd is placed before
anything is written, so that one that cannot be is refused first."""


@dataclass(frozen=True)
class CrowdConfig:
    """A sweep of crowds: every method at every density, ``runs`` crowds each."""

    agents: int = 1000
    """Agents in each crowd (at most :data:`~copi.world.crowd.MAX_AGENTS`)."""
    methods: tuple[str, ...] = ("copi-learnt",)
    """Registered methods, each driving every agent of its crowds."""
    densities: tuple[float, ...] = (0.1,)
    """Agents per square agent step; the room's side is sqrt(agents / density)."""
    runs: int = 1
    """Crowds per method and density (run k placed from ``default_rng([seed, k])``)."""
    steps: int = 200
    """Step limit of a run."""
    seed: int = 0
    sensing: str | None = None
    """The level every method runs at (sensor, map or oracle); default: each method's
    least level."""
    steady: bool = False
    """Agents stay: a new goal on arrival, contacts counted (rows: each first trip)."""
    agent_radius: float = 0.3
    capabilities: dict[str, str] = field(default_factory=dict)
    """Capabilities file per preset, for copi's methods."""
    capabilities_sha: dict[str, str] = field(default_factory=dict)
    params: dict[str, dict[str, Any]] = field(default_factory=dict)
    """Parameters per method over its registered ones."""
    inputs: dict[str, dict[str, str]] = field(default_factory=dict)
    """Per method, the files it reads (filled in by :meth:`resolved`)."""

    def __post_init__(self) -> None:
        positive_int(self.agents, "agents")
        check_count(self.agents, "agents", MAX_AGENTS)
        positive_int(self.steps, "steps")
        check_count(self.steps, "steps", MAX_CROWD_STEPS)
        positive_int(self.runs, "runs")
        check_count(self.runs, "runs", MAX_CROWD_RUNS)
        check_seed(self.seed)
        if not self.densities:
            raise InvalidArgumentError("densities must name at least one density; got none")
        check_count(len(self.densities), "densities", MAX_DENSITIES)
        dens = tuple(dict.fromkeys(check_density(d) for d in self.densities))
        object.__setattr__(self, "densities", dens)
        check_count(self.agents * self.runs * len(dens), "agents x runs x densities",
                    MAX_AGENT_RUNS)  # fmt: skip
        if not self.methods:
            raise InvalidArgumentError("methods must name at least one method; got none")
        object.__setattr__(self, "methods", tuple(dict.fromkeys(self.methods)))
        if self.sensing is not None and self.sensing not in SENSING_LEVELS[:3]:
            raise InvalidArgumentError(
                f"sensing must be sensor, map or oracle; got {self.sensing!r}"
            )
        for m in self.methods:
            spec = method_spec(m)
            if not spec.available():
                raise InvalidArgumentError(f"{m} needs {spec.missing}")
            if spec.sensing == "future":
                raise InvalidArgumentError(
                    f"{m} needs the future of every moving body (level 'future'); in a crowd "
                    "the others' future depends on what each agent does"
                )
            check_sensing(self.level(m), spec.sensing, method=m)
            if spec.capabilities is not None and spec.capabilities not in self.capabilities:
                raise InvalidArgumentError(f"{m} needs the {spec.capabilities!r} capabilities file")

    def level(self, method: str) -> str:
        """The level ``method`` runs at."""
        return self.sensing or method_spec(method).sensing

    def resolved(self) -> CrowdConfig:
        """With the content hash of each capabilities file (each must load and fit the
        methods that run on it) and of the files each method reads."""
        found = resolve_inputs(capabilities=self.capabilities, methods=self.methods,
                               params=self.params, agent_radius=self.agent_radius)  # fmt: skip
        return dataclasses.replace(self, capabilities_sha=found.capabilities_sha,
                                   inputs=found.methods)  # fmt: skip

    def room(self, density: float) -> str:
        """The name of the room (and of the series' family) at ``density``."""
        return f"crowd-room-{self.agents}-d{density:g}"

    def identity(self, method: str, density: float) -> dict[str, Any]:
        """What makes one (method, density) run the same run: not the number of runs (more
        runs extend it), nor any path."""
        spec = method_spec(method)
        ident: dict[str, Any] = {
            "experiment": "crowd", "family": self.room(density), "agents": self.agents,
            "density": density, "method": method, "sensing": self.level(method),
            "strategy": "greedy", "params": {**spec.params, **self.params.get(method, {})},
            "steps": self.steps, "seed": self.seed, "steady": self.steady,
            "agent_radius": self.agent_radius, "code": code_version(),
        }  # fmt: skip
        if spec.capabilities is not None:
            ident["capabilities_sha"] = self.capabilities_sha.get(spec.capabilities, "")
        ident.update(self.inputs.get(method, {}))
        return ident

    def series(self) -> list[Series]:
        """Every (method, density) run, density by density."""
        return [
            Series(run_id(self.identity(m, d)), "crowd", m, self.identity(m, d), "lifelong",
                   self.runs, group=d)
            for d in self.densities
            for m in self.methods
        ]  # fmt: skip

    def check_placement(self) -> None:
        """Place every crowd of the sweep now: one that cannot be placed without overlap
        is refused before anything is written."""
        for d in self.densities:
            room = crowd_room(self.agents, d, name=self.room(d))
            for k in range(self.runs):
                place_agents(room, self.agents, np.random.default_rng([self.seed, k]),
                             radius=self.agent_radius)  # fmt: skip


def draw_crowd(config: CrowdConfig, density: float, k: int, *, record_every: int = 0) -> Crowd:
    """Crowd k at ``density`` (see the module), fresh at t = 0."""
    room = crowd_room(config.agents, density, name=config.room(density))
    return Crowd.draw(room, config.agents, np.random.default_rng([config.seed, k]),
                      agent_radius=config.agent_radius, record_every=record_every)  # fmt: skip


@dataclass(frozen=True)
class CrowdRun:
    """What one run did."""

    rows: list[LifeRow]
    """One per agent (see the module)."""
    crowd: Crowd
    """Its state at the end (with its frames, if recorded)."""
    steps: int
    """World steps run (fewer than the limit when every agent left)."""
    seconds: float
    """Wall time of those steps (sensing, deciding, moving)."""
    decision_us: float
    """Mean wall time of one agent's decision, microseconds."""
    processes: int

    @property
    def steps_per_s(self) -> float:
        return self.steps / self.seconds if self.seconds > 0 else math.nan


def run_crowd(
    config: CrowdConfig,
    method: str,
    density: float,
    k: int,
    *,
    processes: int = 1,
    record_every: int = 0,
    progress: Callable[[int], None] | None = None,
) -> CrowdRun:
    """Run crowd k at ``density`` with every agent driven by ``method`` for the config's
    steps (or until every agent has left), on ``processes`` processes;
    ``progress(t)`` after each step."""
    crowd = draw_crowd(config, density, k, record_every=record_every)
    goals = crowd.goals.copy()
    preset = method_spec(method).capabilities
    caps = None
    if preset is not None:
        caps = load_capabilities(config.capabilities[preset],
                                 config.capabilities_sha.get(preset, ""))  # fmt: skip
    level = config.level(method)
    params = config.params.get(method, {})

    def make(lo: int, hi: int) -> Any:
        return make_driver(method, caps, params, crowd, level, lo, hi)

    shared = level == "sensor" and batched(make_agent(method, caps, **params))
    with Team(crowd, make, processes, shared=shared) as team:
        t0 = time.perf_counter()
        for t in range(config.steps):
            actions = team.decide()
            # the next step's sensing starts in the other processes while this one keeps
            # the books of this step (not after the last)
            moved = team.moved if t + 1 < config.steps else None
            crowd.step(actions, leave=not config.steady, sense=False, moved=moved)
            if progress is not None:
                progress(t + 1)
            if not crowd.active.any():
                break
        seconds = time.perf_counter() - t0
        crowd.sense()  # the last readings, for whoever looks at the crowd afterwards
    us = decision_us(team)
    rows = _rows(config, method, density, k, crowd, goals, us)
    return CrowdRun(rows=rows, crowd=crowd, steps=crowd.t, seconds=seconds, decision_us=us,
                    processes=team.processes)  # fmt: skip


def _rows(config: CrowdConfig, method: str, density: float, k: int, crowd: Crowd,
          goals: np.ndarray, us: float) -> list[LifeRow]:  # fmt: skip
    """One row per agent: its first trip."""
    straight = np.hypot(*(goals - crowd.starts).T)
    optimal = np.maximum(0.0, straight - crowd.goal_tolerance)
    outcome = np.where(crowd.outcome == SUCCESS, "success",
                       np.where(crowd.outcome == COLLISION, "collision", "timeout"))  # fmt: skip
    steps = np.where(crowd.ended >= 0, crowd.ended, crowd.t)
    length = np.where(np.isnan(crowd.trip_length), crowd.path_length, crowd.trip_length)
    name = config.room(density)
    level = config.level(method)
    rows = []
    for i in range(crowd.n_agents):
        ok = bool(crowd.outcome[i] == SUCCESS)
        rows.append(LifeRow(
            world=name, life=k, task=i, seed=config.seed, family=name, sensing=level,
            outcome=str(outcome[i]), success=ok, steps=int(steps[i]),
            path_length=float(length[i]), optimal_length=float(optimal[i]),
            excess=float(length[i] / optimal[i] - 1) if ok and optimal[i] > 0 else math.nan,
            decision_us=us, unfamiliar=math.nan, grown=None, options=None, strategy="greedy",
        ))  # fmt: skip
    return rows


class CrowdWork:
    """The work of a sweep's item (see :func:`copi.runs.run_series`): run k at a density
    for each method still missing it. In this process (``processes`` > 1 or a step
    progress) a single run may share its agents among processes; it keeps the crowd of
    the first (method, density, run 0) with its frames (``record_every``), for the
    animation."""

    def __init__(
        self,
        *,
        processes: int = 1,
        step_progress: Callable[[int, int], None] | None = None,
        record: tuple[str, float] | None = None,
        record_every: int = 0,
    ) -> None:
        self.processes = processes
        self.step_progress = step_progress
        """``step_progress(j, t)``: step t of the item's j-th run done."""
        self.record = record
        self.record_every = record_every
        self.kept: CrowdRun | None = None

    def __getstate__(self) -> dict[str, Any]:  # to a pool or Dask: nothing of this process
        return {"processes": 1, "step_progress": None, "record": None, "record_every": 0,
                "kept": None}  # fmt: skip

    def __call__(self, config: CrowdConfig, density: float, k: int,
                 todo: list[Series]) -> list[tuple[Series, list[LifeRow]]]:  # fmt: skip
        out = []
        for j, s in enumerate(todo):
            keep = self.record == (s.method, density) and k == 0
            tick = self.step_progress

            def each(t: int, j: int = j, tick: Any = tick) -> None:
                tick(j, t)

            run = run_crowd(config, s.method, density, k, processes=self.processes,
                            record_every=self.record_every if keep else 0,
                            progress=None if tick is None else each)  # fmt: skip
            if keep:
                self.kept = run
            out.append((s, run.rows))
        return out


def run_crowds(
    config: CrowdConfig,
    output: str | os.PathLike[str],
    *,
    workers: int = 1,
    scheduler: str | None = None,
    progress: Callable[[int, int], None] | None = None,
    record_every: int = 0,
) -> tuple[dict[tuple[str, float], str], CrowdRun | None]:
    """Run (or resume) the sweep into the results file ``output``; ``progress(done,
    total)`` in world steps. A sweep of one run here (no scheduler) shares its agents
    among ``workers`` processes; a longer one runs ``workers`` runs at a time (or on the
    Dask cluster at ``scheduler``), one process each. Returns the run id of each (method,
    density) and, when it ran here, run 0 of the first method at the first density (its
    frames recorded every ``record_every`` steps)."""
    config = config.resolved()
    config.check_placement()
    series = config.series()
    total = len(series) * config.runs * config.steps
    single = len(series) * config.runs == 1 and scheduler is None
    here = scheduler is None and (workers == 1 or single)
    runs_done = [0]  # runs stored, as the store loop last said

    def stored(done: int, _total: int) -> None:
        runs_done[0] = done
        if progress is not None:
            progress(done * config.steps, total)

    def stepped(j: int, t: int) -> None:
        if progress is not None:
            progress((runs_done[0] + j) * config.steps + t, total)

    work = CrowdWork(processes=workers if single else 1,
                     step_progress=stepped if here else None,
                     record=(config.methods[0], config.densities[0]) if here else None,
                     record_every=record_every)  # fmt: skip
    run_series(config, output, series, work=work, unit="crowd runs",
               workers=1 if here else workers, scheduler=scheduler, progress=stored,
               chunk=1)  # fmt: skip
    ids = {(s.method, s.group): s.run_id for s in series}
    return ids, work.kept
