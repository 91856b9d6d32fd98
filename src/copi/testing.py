"""Conformance checks for methods written elsewhere, as Gymnasium's ``check_env`` is for
environments: :func:`check_agent` runs an agent through short episodes and refuses, in
one line, one that breaks the :class:`~copi.core.Agent` contract.

Examples
--------
>>> import numpy as np
>>> from copi.core import Agent
>>> class Eastward(Agent):
...     name = "eastward"
...     def reset(self, task): pass
...     def act(self, obs): return np.array([1.0, 0.0])
>>> check_agent(Eastward)
>>> class TooFast(Eastward):
...     def act(self, obs): return np.array([3.0, 0.0])
>>> try:
...     check_agent(TooFast)
... except AgentCheckError as err:
...     print(err)  # doctest: +ELLIPSIS
agent 'eastward' at level sensor: act returned a velocity of norm 3 at step 1 of episode 0; ...
"""

from __future__ import annotations

import copy
import json
import math
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

from copi.core import SENSING_LEVELS, Agent, Observation, Sensing, Task, check_sensing
from copi.errors import CopiError

__all__ = ["AgentCheckError", "check_agent"]


class AgentCheckError(CopiError):
    """A method breaks the agent contract; the message says where and how."""


def _episodes(seed: int, n: int) -> list[Any]:
    """n episodes the check runs: an empty room, a room with a pillar and moving discs, a
    long hall (a goal 150 steps away, so that a run of the default limit reaches its
    last step), and worlds of the paper's family (seeded)."""
    from copi.world import ObstacleSpec, Simulator, World, sample_world

    square = np.array([[0, 0], [20, 0], [20, 20], [0, 20]], dtype=np.float64)
    room = World(square, name="check-room")
    pillar = World(np.array([[0, 0], [24, 0], [24, 16], [0, 16]], dtype=np.float64),
                   (np.array([[10, 6], [14, 6], [14, 10], [10, 10]], dtype=np.float64),),
                   name="check-pillar")  # fmt: skip
    hall = World(np.array([[0, 0], [160, 0], [160, 8], [0, 8]], dtype=np.float64),
                 name="check-hall")  # fmt: skip
    sims = [
        Simulator(room, [3, 3], [16, 15], np.zeros((0, 2)), [], seed=seed),
        Simulator.from_world(pillar, np.random.default_rng([seed, 1]),
                             obstacles=ObstacleSpec(count=(4, 4))),
        Simulator(hall, [4, 4], [155, 4], np.zeros((0, 2)), [], seed=seed),
    ]  # fmt: skip
    k = 0
    while len(sims) < n:
        rng = np.random.default_rng([seed, 100 + k])
        sims.append(Simulator.from_world(sample_world("star", rng), rng))
        k += 1
    return sims[:n]


class _Probe(Agent):
    """Wraps the agent under check: records and checks every action it returns."""

    def __init__(self, agent: Agent, level: str, episode: int) -> None:
        self.agent = agent
        self.name = agent.name
        self.sensing = agent.sensing
        self.steers_itself = agent.steers_itself
        self.level = level
        self.episode = episode
        self.actions: list[np.ndarray] = []
        self.outcome: str | None = None

    def _fail(self, what: str) -> AgentCheckError:
        return AgentCheckError(f"agent {self.name!r} at level {self.level}: {what}")

    def reset(self, task: Task) -> None:
        try:
            self.agent.reset(task)
        except CopiError:
            raise
        except Exception as exc:
            raise self._fail(f"reset raised {type(exc).__name__}: {exc}") from None

    def act(self, obs: Observation) -> Any:
        step = len(self.actions) + 1
        where = f"at step {step} of episode {self.episode}"
        frozen = copy.deepcopy(obs)
        try:
            raw = self.agent.act(obs)
        except CopiError:
            raise
        except Exception as exc:
            raise self._fail(
                f"act raised {type(exc).__name__}: {exc} {where} (does it read more than "
                f"level {self.level} gives? it declares {self.agent.sensing!r})"
            ) from None
        for field in ("ranges", "goal", "position", "static", "obstacles", "odometry"):
            a, b = getattr(obs, field), getattr(frozen, field)
            if (a is None) != (b is None) or (a is not None and not np.array_equal(a, b)):
                raise self._fail(f"act changed the observation's {field} in place {where}")
        try:
            action = np.asarray(raw)
        except (TypeError, ValueError):
            raise self._fail(f"act returned {type(raw).__name__}, not a velocity {where}") from None
        if action.shape != (2,):
            raise self._fail(f"act returned shape {action.shape}, expected (2,), {where}")
        if action.dtype.kind not in "iuf":
            raise self._fail(f"act returned {action.dtype} numbers {where}, expected real ones")
        action = action.astype(np.float64)
        if not np.isfinite(action).all():
            raise self._fail(f"act returned {action.tolist()} {where}: not finite")
        norm = math.hypot(action[0], action[1])
        if norm > 1 + 1e-9:
            raise self._fail(
                f"act returned a velocity of norm {norm:g} {where}; at most 1 (one agent "
                "step per time step)"
            )
        self.actions.append(action.copy())
        return action

    def finish(self, outcome: str) -> None:
        self.outcome = outcome
        try:
            self.agent.finish(outcome)
        except Exception as exc:
            raise self._fail(f"finish raised {type(exc).__name__}: {exc}") from None

    def counters(self) -> dict[str, Any]:
        try:
            c = self.agent.counters()
        except Exception as exc:
            raise self._fail(f"counters raised {type(exc).__name__}: {exc}") from None
        if not isinstance(c, dict) or not all(isinstance(k, str) for k in c):
            raise self._fail(f"counters returned {type(c).__name__}, expected a dict by name")
        try:
            json.dumps(c, allow_nan=True)
        except (TypeError, ValueError):
            raise self._fail(f"counters returned values that are not numbers: {c!r}") from None
        return c


def check_agent(
    agent: Agent | Callable[[], Agent] | str,
    *,
    levels: Iterable[Sensing] | None = None,
    capabilities: Any = None,
    episodes: int = 3,
    max_steps: int = 120,
    seed: int = 0,
) -> None:
    """Check that ``agent`` keeps the :class:`~copi.core.Agent` contract; raise
    :class:`AgentCheckError` (one line) at the first breach.

    ``agent``: an Agent class or factory (called for each run), an Agent instance (reset
    between runs), or a registered method's name (built with ``capabilities``). It is run
    for ``episodes`` episodes of at most ``max_steps`` steps (an empty room, a room with a
    pillar and moving discs, a long hall whose goal is farther than the default limit,
    the paper's worlds) at each of ``levels`` (default: every level it may run at, from
    its own), and must:

    - be an Agent with a name and a known sensing level;
    - act on what its declared level gives alone (its least level is among those run);
    - return finite velocities of shape (2,) and norm at most 1, without changing the
      observation it is handed;
    - accept ``finish`` and return counters as a dict of numbers by name;
    - act the same in two runs of the same episode (determinism from the seed).
    """
    for value, name in ((episodes, "episodes"), (max_steps, "max_steps")):
        if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 10_000:
            raise AgentCheckError(f"{name} must be an int in 1 .. 10,000; got {value!r}")
    if isinstance(agent, str):
        from copi.methods import make_agent

        name = agent

        def factory() -> Agent:
            return make_agent(name, capabilities)
    elif isinstance(agent, Agent):
        instance = agent

        def factory() -> Agent:
            return instance
    elif callable(agent):
        factory = agent  # type: ignore[assignment]
    else:
        raise AgentCheckError(
            f"expected an Agent, an Agent factory or a method's name; got {type(agent).__name__}"
        )
    first = factory()
    if not isinstance(first, Agent):
        raise AgentCheckError(
            f"{type(first).__name__} is not a copi.core.Agent: subclass it (reset and act; "
            "finish and counters are optional)"
        )
    if not isinstance(first.name, str) or not first.name:
        raise AgentCheckError(f"{type(first).__name__}.name must be a non-empty str; got "
                              f"{first.name!r}")  # fmt: skip
    if first.sensing not in SENSING_LEVELS:
        raise AgentCheckError(
            f"agent {first.name!r}: sensing must be one of {', '.join(SENSING_LEVELS)}; got "
            f"{first.sensing!r}"
        )
    own = SENSING_LEVELS.index(first.sensing)
    chosen = list(SENSING_LEVELS[own:]) if levels is None else list(levels)
    if not chosen:
        raise AgentCheckError(f"agent {first.name!r}: levels must name at least one level to "
                              "check it at; got none")  # fmt: skip
    for lv in chosen:
        check_sensing(lv, first.sensing, method=first.name)
    from copi.runs import run_episode

    base = _episodes(seed, episodes)
    for level in chosen:
        for i, sim in enumerate(base):
            runs = []
            for _ in range(2):
                probe = _Probe(factory(), level, i)
                run_episode(probe, copy.deepcopy(sim), sensing=level, max_steps=max_steps)
                if probe.outcome is None:
                    raise probe._fail("was not told how the episode ended")
                runs.append(probe.actions)
            a, b = runs
            same = len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
            if not same:
                step = next((k + 1 for k, (x, y) in enumerate(zip(a, b, strict=False))
                             if not np.array_equal(x, y)), min(len(a), len(b)) + 1)  # fmt: skip
                raise AgentCheckError(
                    f"agent {first.name!r} at level {level}: two runs of episode {i} differ "
                    f"at step {step}; an agent must act the same on the same episode (draw "
                    "any randomness from a seed, and reset all state in reset)"
                )
