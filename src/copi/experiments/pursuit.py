"""Experiment 2 (paper §IV, Fig. 5): the homicidal chauffeur played through the learnt
capabilities, in stationary and dynamic worlds."""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from copi._rng import check_seed
from copi._validation import check_count, non_negative, positive_int
from copi.core import Agent, Observation, Task
from copi.errors import InvalidArgumentError
from copi.games import ChauffeurGame, ChauffeurParams
from copi.methods import (
    PRESETS,
    check_preset_capabilities,
    make_agent,
    method_spec,
    preset_of,
)
from copi.online import ContextController
from copi.results import GameRow
from copi.runs import (
    MAX_EPISODES,
    checked_act,
    code_version,
    load_capabilities,
    resolve_inputs,
    run_one,
)
from copi.world import RangeSensor

__all__ = [
    "EVADERS",
    "PursuitConfig",
    "pursue",
    "resolve_evader",
    "run_game",
    "run_games",
]


EVADERS = ("capability", "learnt", "game")
"""How the evader plays the game's direction (see :attr:`PursuitConfig.evader`); any
registered method of level sensor may play it too, by its name."""


@dataclass(frozen=True)
class PursuitConfig:
    """One run of Experiment 2."""

    capabilities: str | None
    """Capabilities file (its content hash enters the run id); None for an evader that
    needs none."""
    evader: str = "capability"
    """"capability": the game's direction instantiated through the ContextController
    (walls and obstacles avoided); "learnt": instantiated through the learnt preset's
    agent (:class:`~copi.online.LearntAgent`, capabilities with safety priors); "game":
    the game's direction as the velocity; or a registered method of level sensor (e.g.
    ``ppo``), instantiating it as a local policy under the game's direction."""
    dynamic: bool = True
    """Moving obstacles (10-15) or a stationary world."""
    games: int = 100
    seed: int = 0
    """Game k draws world and starts from default_rng([seed, k]), obstacles from
    default_rng([seed, k, 1]): a stationary and a dynamic run play the same games."""
    horizon: int = 300
    """Time steps the evader must survive."""
    guard: float = 1.2
    """The capability evader's guard (see ContextController); as Experiment 1's extended
    mode (the learnt preset's is 1.05)."""
    gamma: float = 0.7
    """V_e / V_p (V_e = 1 agent step per time step)."""
    turn_radius: float = 4.0
    capture_radius: float = 0.8
    record: int = 3
    """Games (the first ones) whose trajectories are stored for Fig. 5."""
    contact_ends: bool = True
    """A contact with a moving obstacle ends the game as a loss for the evader (outcome
    "collision"), as a collision ends a navigation episode; False lets the game go on
    (the older rule, under which a contact had no consequence)."""
    capabilities_sha: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        if self.evader not in EVADERS:
            try:
                spec = method_spec(self.evader)
            except InvalidArgumentError:
                raise InvalidArgumentError(
                    f"evader must be one of {', '.join(EVADERS)} or a method of level sensor; "
                    f"got {self.evader!r}"
                ) from None
            if spec.sensing != "sensor":
                raise InvalidArgumentError(f"the evader {self.evader} needs level "
                                           f"{spec.sensing}; the game gives sensor")  # fmt: skip
            needs = spec.capabilities is not None
        else:
            needs = self.evader != "game"
        if needs and self.capabilities is None:
            raise InvalidArgumentError(f"the {self.evader} evader needs a capabilities file")
        for name in ("games", "horizon"):
            positive_int(getattr(self, name), name)
        check_count(self.games, "games", MAX_EPISODES)
        check_count(self.horizon, "horizon", 100_000)
        check_count(self.games * self.horizon, "games x horizon (steps in all)", 100_000_000)
        check_seed(self.seed)
        non_negative(self.guard, "guard")
        self.params()  # validates gamma and the radii

    def resolved(self) -> PursuitConfig:
        """With the capabilities file's content hash (checked to load:
        :func:`copi.runs.resolve_inputs`)."""
        if self.capabilities is None:
            return self
        found = resolve_inputs(capabilities={"evader": self.capabilities})
        return dataclasses.replace(self, capabilities_sha=found.capabilities_sha["evader"])

    def identity(self) -> dict[str, Any]:
        """What makes two runs the same run: the configuration without the capabilities'
        path, with its content and copi's version, and for an evader that is a registered
        method, the files it reads and where it comes from."""
        d = dataclasses.asdict(self)
        del d["capabilities"]
        d["code"] = code_version()
        if self.evader not in EVADERS:  # a registered method: its weights, where it is from
            d.update(method_spec(self.evader).input_hashes())
        return d

    @property
    def method(self) -> str:
        return f"{self.evader}-{'dynamic' if self.dynamic else 'static'}"

    def params(self) -> ChauffeurParams:
        if not 0 < self.gamma < 1:
            raise InvalidArgumentError(f"gamma must be in (0, 1); got {self.gamma}")
        return ChauffeurParams(
            evader_speed=1.0,
            pursuer_speed=1.0 / self.gamma,
            turn_radius=self.turn_radius,
            capture_radius=self.capture_radius,
        )


def run_game(config: PursuitConfig, k: int, agent: Agent | None = None) -> GameRow:
    """Game k of a run; depends only on (config, k). ``agent``: play the evader through
    this agent instead of the one ``config.evader`` names (e.g. a policy in training)."""
    caps = load_capabilities(config.capabilities, config.capabilities_sha) if config.capabilities \
        else None  # fmt: skip
    params = config.params()
    n_rays = caps.n_rays if caps is not None else 32
    reach = float(caps.params.get("max_range", 10.0)) if caps is not None else 10.0
    sensor = RangeSensor(n_rays, reach)
    game = ChauffeurGame.draw(
        config.seed,
        k,
        dynamic=config.dynamic,
        params=params,
        sensor=sensor,
        record=k < config.record,
    )
    controller = None
    if agent is None and config.evader == "capability":
        assert caps is not None
        controller = ContextController(caps, guard=config.guard)
    elif agent is None and config.evader != "game":
        agent = _evader_agent(caps, config, sensor)
    elif agent is not None:
        agent.reset(Task(sensing="map", agent_radius=0.3, goal_tolerance=0.0,
                         n_rays=sensor.n_rays, max_range=sensor.max_range))  # fmt: skip
    while game.t < config.horizon and not game.captured:
        wish = game.evader_wish()
        static = sensor.scan(game.world, game.sim.position) if config.guard > 0 else None
        if agent is not None:
            # The game's direction as a far goal (no slowing down for a near one).
            norm = float(np.hypot(*wish))
            far = np.asarray(wish, dtype=np.float64) * (1e3 / norm) if norm > 0 else wish
            obs = Observation(ranges=game.sim.ranges.copy(), goal=far, static=static,
                              direction=far / 1e3 if norm > 0 else np.zeros(2))
            velocity = checked_act(agent, obs, game.t + 1)
        elif controller is None:
            velocity = wish
        else:
            velocity, _ = controller.decide(game.sim.ranges, wish, static=static)
        game.step(velocity)
        if config.contact_ends and game.contacts and not game.captured:
            break
    trajectory = None
    if game.record:
        trajectory = {
            "world": game.world.to_dict(),
            "evader": np.asarray(game.sim.path).round(4).tolist(),
            "pursuer": np.asarray(game.car_path).round(4).tolist(),
            "traces": np.asarray(game.sim.traces).round(4).tolist(),
            "radii": game.sim.radii.tolist(),
            "captured": game.captured,
        }
    if game.captured:
        outcome, survival = "captured", game.capture_time
    elif game.contacts:
        outcome = "collision"
        survival = float(game.t) if config.contact_ends else float(config.horizon)
    else:
        outcome, survival = "escaped", float(config.horizon)
    return GameRow(
        game=k,
        world=game.world.name,
        seed=config.seed,
        dynamic=config.dynamic,
        captured=game.captured,
        capture_time=game.capture_time,
        survival=survival,
        contacts=game.contacts,
        closest=game.closest,
        gamma=params.gamma,
        beta=params.beta,
        outcome=outcome,
        trajectory=trajectory,
    )


def resolve_evader(
    caps: Any,
    where: str,
    *,
    preset: str | None = None,
    evader: str | None = None,
    guard: float | None = None,
) -> tuple[str, float]:
    """The evader and guard a pursuit run plays with (``copi pursuit``), as
    :func:`copi.methods.resolve` settles them for navigation: the preset's
    (or, without one, the mode the capabilities were learnt for) evader and guard; a
    ``--guard`` contradicting a preset, an evader the preset does not play, or a file
    learnt for another mode is refused. A registered method (``--evader
    ppo-chauffeur-sensor``) plays as :class:`PursuitConfig` plays it, with this run's
    guard where it is registered with one."""
    if evader is not None and evader not in EVADERS:
        # a registered method of level sensor (PursuitConfig checks the level), under the
        # game's direction; the capabilities' mode plays no part, the guard only where the
        # method is registered with one
        try:
            method_spec(evader)
        except InvalidArgumentError:
            raise InvalidArgumentError(f"evader must be one of {', '.join(EVADERS)} or a "
                                       f"registered method of level sensor; got "
                                       f"{evader!r}") from None  # fmt: skip
        if preset is not None:
            raise InvalidArgumentError(f"--preset {preset} plays the preset's evader; got "
                                       f"--evader {evader}")  # fmt: skip
        return evader, float(PursuitConfig(capabilities=None, evader="game").guard
                             if guard is None else guard)  # the config's default guard
    name = preset if preset is not None else preset_of(caps)
    if name == "learnt-motion":
        raise InvalidArgumentError(
            "the pursuit game plays presets faithful, extended and learnt; "
            f"{'got' if preset else where + ' was learnt for'} learnt-motion"
        )
    if preset is not None:
        check_preset_capabilities(preset, caps, where)
        if guard is not None and guard != PRESETS[preset].guard:
            raise InvalidArgumentError(
                f"--guard {guard:g} contradicts --preset {preset} (guard "
                f"{PRESETS[preset].guard:g})"
            )
    learnt = name == "learnt"
    kind = evader or ("learnt" if learnt else "capability")
    if kind == "learnt" and not learnt:
        raise InvalidArgumentError(
            f"--evader learnt plays the learnt preset's agent; {where} was learnt for "
            f"{'preset ' + name if name else 'no preset'}: learn it with copi learn --preset "
            "learnt"
        )
    if kind == "capability" and learnt and preset is not None:
        raise InvalidArgumentError("--preset learnt plays the learnt evader, not --evader "
                                   "capability")  # fmt: skip
    base = PRESETS[name].guard if name is not None else PRESETS["extended"].guard
    return kind, float(base if guard is None else guard)


def _evader_agent(caps: Any, config: PursuitConfig, sensor: RangeSensor) -> Agent:
    """The evader's method (``learnt``: copi-learnt) with its registered parameters and,
    where it is registered with a guard, this run's; a method registered with none (a
    PPO policy played as trained: guard 0) keeps none. Told a task with no map (it is
    handed the static reading each step, as the capability evader is)."""
    name = "copi-learnt" if config.evader == "learnt" else config.evader
    spec = method_spec(name)
    extra = {"guard": config.guard} if spec.params.get("guard", 0.0) > 0.0 else {}
    agent = make_agent(name, caps if spec.capabilities else None, **extra)
    agent.reset(Task(sensing="map", agent_radius=0.3, goal_tolerance=0.0,
                     n_rays=sensor.n_rays, max_range=sensor.max_range))  # fmt: skip
    return agent


def run_games(config: PursuitConfig, games: list[int]) -> list[GameRow]:
    return [run_game(config, k) for k in games]


def pursue(
    config: PursuitConfig,
    output: str | os.PathLike[str],
    *,
    workers: int = 1,
    scheduler: str | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> str:
    """Run (or resume) Experiment 2 into ``output``; returns the run id."""
    config = config.resolved()
    return run_one(
        config, config.identity(), output, experiment="pursuit", method=config.method,
        table="games", total=config.games, item=run_game, unit="games", chunk=8,
        workers=workers, scheduler=scheduler, progress=progress,
    )  # fmt: skip
