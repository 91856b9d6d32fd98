"""The environment PPO learns its local policy in: copi's episodes, copi's factorisation.

An episode is one of copi's navigation episodes (a family's world, task and moving
obstacles, drawn from a training seed no report uses), run at a sensing level; the
global strategy of that level (:class:`~copi.online.Steering`: the route at ``map``, the
goal at ``sensor``) gives the direction, and the agent sees exactly what
:class:`~copi.baselines.PPOAgent` will see (:func:`copi.baselines._ppo.features`, in the
frame of the direction; its action is turned back to the world's frame as the agent turns
it).
Episodes of the homicidal chauffeur (``task="chauffeur"``) take the game's direction for
the evader instead, and end at capture.

With ``observation="copi-local-v3"`` the agent sees one level's reading as
:func:`copi.baselines.features_v3` gives it (the hits the static map does not explain at
``map``, ``frames`` readings stacked, its own last velocity): one policy per level.

Reward, shaped as the field does (progress along the global direction, a contact
penalty, a success bonus, a proximity penalty), with :class:`Reward`'s weights: each step
``progress * (moved . direction) - time - proximity * max(0, 1 - gap / near)``, ``gap``
the least distance between the agent's surface and a moving obstacle's over the step;
at the goal ``+ success``; at a contact ``- contact`` (the episode ends). In the chauffeur
game each step survived earns ``survive`` and a capture or contact costs ``contact``.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from copi._rng import check_seed
from copi.baselines import (
    OBSERVATION,
    OBSERVATION_V3,
    check_layout,
    direction_frame,
    features,
    features_v3,
    observation_size,
    to_world,
)
from copi.core import Observation, check_sensing
from copi.errors import InvalidArgumentError, InvalidWorldError
from copi.games import ChauffeurGame
from copi.online import Steering
from copi.runs import draw_episode, make_task
from copi.world import check_family

__all__ = ["TRAINING_SEED", "LocalPolicyEnv", "Reward"]

TRAINING_SEED = 2
"""Training episodes are episodes of this seed (reports use seed 0, tuning seed 1)."""
EPISODES_PER_FAMILY = 1000
"""Training episodes per family: episodes 0 .. 999 of the training seed, each drawn (and
its static route planned) once per process, then copied at each reset (a reset costs
0.2 ms instead of 15)."""
MAX_POOL = 1_000_000
"""The most training episodes a family's pool may hold (``episodes``; each drawn the
first time it comes up, then kept)."""
MAX_STEPS = 1_000_000
"""The longest episode :class:`LocalPolicyEnv` runs (``max_steps``), in steps."""
_POOL: dict[tuple[str, int, int], Any] = {}


def _names(value: Any, name: str, what: str) -> tuple[str, ...]:
    """``value`` as a non-empty tuple of strings; one clear error otherwise (a lone string
    would be read letter by letter)."""
    if isinstance(value, str) or not isinstance(value, tuple | list) or not value or not all(
        isinstance(v, str) for v in value
    ):
        raise InvalidArgumentError(f"{name} must be a non-empty tuple of {what} names; got "
                                   f"{value!r}")  # fmt: skip
    return tuple(value)


@dataclass(frozen=True)
class Reward:
    """The shaped reward's weights (see the module)."""

    progress: float = 1.0
    time: float = 0.01
    success: float = 10.0
    contact: float = 10.0
    survive: float = 0.05
    proximity: float = 0.0
    """The most a step costs for coming near a moving obstacle (at a touch)."""
    near: float = 1.5
    """Gap, in agent steps, below which the proximity penalty starts."""

    def __post_init__(self) -> None:
        for k, v in vars(self).items():
            if not (isinstance(v, int | float) and math.isfinite(v) and 0 <= v <= 1000):
                raise InvalidArgumentError(f"reward weight {k} must be a number in [0, 1000]; "
                                           f"got {v!r}")  # fmt: skip
        if self.near <= 0:
            raise InvalidArgumentError(f"reward weight near must be above 0; got {self.near!r}")


class LocalPolicyEnv(gymnasium.Env[NDArray[np.float32], NDArray[np.float32]]):
    """copi's episodes of ``families`` at ``levels`` (drawn at random each reset from
    ``self.np_random``), observed as a PPO policy observes them.

    Parameters
    ----------
    families : tuple of str
        Names of registered world families (at least one; episodes of the training seed).
    levels : tuple of str
        Sensing levels to draw from, each "sensor" or "map" (at least one; the chauffeur
        task runs at "map" whatever they are, but for a ``copi-local-v3`` evader).
    task : str
        "navigation" or "chauffeur" (the evader of the homicidal chauffeur).
    reward : Reward, optional
        The shaped reward's weights (default :class:`Reward`'s).
    max_steps : int
        Steps before an episode is truncated, in 1 .. :data:`MAX_STEPS`.
    seed_of_episodes : int
        The seed whose episodes are drawn, in 0 .. 2**63 - 1 (default
        :data:`TRAINING_SEED`).
    observation : str
        ``"copi-local-v2"`` (the ranges and their change, the same at every level) or
        ``"copi-local-v3"`` (one level's reading, stacked; ``levels`` must then name one).
    frames : int
        Readings a ``copi-local-v3`` observation stacks, in 2 .. 16.
    episodes : int
        A family's pool of training episodes: episodes 0 .. episodes - 1 of the seed, one
        drawn at random at each reset, in 1 .. :data:`MAX_POOL` (default
        :data:`EPISODES_PER_FAMILY`).

    Raises
    ------
    InvalidArgumentError
        For any argument outside these (in the constructor, before any episode is drawn);
        at a reset, for a family whose sampler raises or that has no valid episode.
    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        families: tuple[str, ...] = ("star",),
        *,
        levels: tuple[str, ...] = ("sensor", "map"),
        task: str = "navigation",
        reward: Reward | None = None,
        max_steps: int = 500,
        seed_of_episodes: int = TRAINING_SEED,
        observation: str = OBSERVATION,
        frames: int = 2,
        episodes: int = EPISODES_PER_FAMILY,
    ) -> None:
        if task not in ("navigation", "chauffeur"):
            raise InvalidArgumentError(f"task must be navigation or chauffeur; got {task!r}")
        self.families = _names(families, "families", "family")
        for f in self.families:
            check_family(f)
        levels = _names(levels, "levels", "sensing level")
        for lv in levels:
            check_sensing(lv)
            if lv not in ("sensor", "map"):
                raise InvalidArgumentError(f"a local policy runs at sensor or map, not {lv}")
        # the first peer's chauffeur ran at map whatever the levels said (its features are
        # the same at every level); a copi-local-v3 evader runs at the level it is given
        self.levels = levels if task == "navigation" or observation == OBSERVATION_V3 \
            else ("map",)  # fmt: skip
        self.task = task
        if reward is not None and not isinstance(reward, Reward):
            raise InvalidArgumentError("reward must be a copi.envs.local_policy.Reward or None; "
                                       f"got a {type(reward).__name__}")  # fmt: skip
        self.reward = reward or Reward()
        if not (isinstance(max_steps, int | np.integer) and not isinstance(max_steps, bool)
                and 1 <= max_steps <= MAX_STEPS):  # fmt: skip
            raise InvalidArgumentError(f"max_steps must be a positive int, at most {MAX_STEPS:,} "
                                       f"(steps of one episode); got {max_steps!r}")  # fmt: skip
        self.max_steps = int(max_steps)
        if not (isinstance(episodes, int | np.integer) and not isinstance(episodes, bool)
                and 1 <= episodes <= MAX_POOL):  # fmt: skip
            raise InvalidArgumentError(f"episodes must be an int in 1 .. {MAX_POOL:,} (a "
                                       f"family's pool of training episodes); got "
                                       f"{episodes!r}")  # fmt: skip
        self.episodes = int(episodes)
        self._ended: str | None = "not started"
        # the episodes' generator is default_rng([seed_of_episodes, k]): a float, a
        # negative int or a bool would fail there, at the first reset, or draw elsewhere
        self.seed_of_episodes = check_seed(seed_of_episodes, "seed_of_episodes")
        check_layout(observation, frames, self.levels)
        self.observation = observation
        self.v3 = observation == OBSERVATION_V3
        self.frames = int(frames)
        n = 32
        size = observation_size(n, observation, self.levels[0], self.frames)
        self.observation_space = spaces.Box(-1.0, 1.0, shape=(size,), dtype=np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.steering = Steering()
        self._x = np.empty(observation_size(n))
        self._prev: NDArray[np.float64] | None = None
        self._history: list[NDArray[np.float64]] = []
        self._velocity = np.zeros(2)
        self.game: Any = None
        self.direction = np.zeros(2)
        self.reach = 0.0
        """How far the goal (or the route's next corner) lies along :attr:`direction`."""

    # -- episodes ---------------------------------------------------------------------

    def _draw(self) -> None:
        rng = self.np_random
        self.level = self.levels[int(rng.integers(len(self.levels)))]
        k = int(rng.integers(1_000_000))
        if self.task == "chauffeur":
            self.game = ChauffeurGame.draw(self.seed_of_episodes, k, dynamic=True)
            self.sim = self.game.sim
            return
        family = self.families[int(rng.integers(len(self.families)))]
        k = k % self.episodes
        key = (family, k, self.seed_of_episodes)
        if key not in _POOL:
            sim, why = None, ""
            for attempt in range(20):
                try:
                    sim = draw_episode(family, k + self.episodes * attempt,
                                       self.seed_of_episodes)  # fmt: skip
                    break
                except InvalidWorldError as exc:  # a world with no valid task: another one
                    why = str(exc)
                # any other error of copi's is not the episode's but the family's (its
                # sampler raised, or its data is missing): every draw would meet it, and
                # retrying would hide it behind "no valid episode"
            if sim is None:
                raise InvalidArgumentError(f"no valid episode of {family} near episode {k} "
                                           f"in 20 draws (the last: {why})")  # fmt: skip
            routed = Steering()
            routed.reset(make_task(sim, "map"))
            _POOL[key] = (sim, routed)
        sim, routed = _POOL[key]
        self.sim = copy.deepcopy(sim)
        self.game = None
        if self.level == "map":
            self.steering = copy.deepcopy(routed)
        else:
            self.steering = Steering()
            self.steering.reset(make_task(self.sim, self.level))  # type: ignore[arg-type]

    def _observe(self) -> NDArray[np.float32]:
        sim = self.sim
        if self.game is not None:
            wish = np.asarray(self.game.evader_wish(), dtype=np.float64)
            self.direction, reach = wish, 1e3
        else:
            map_level = self.level != "sensor"
            obs = Observation(ranges=sim.ranges, goal=sim.goal - sim.position,
                              position=sim.position if map_level else None)  # fmt: skip
            d, reach = self.steering.aim(obs)
            self.direction = np.asarray(d, dtype=np.float64)
        self.reach = float(reach)
        if self.v3:
            static = sim.sensor.scan(sim.world, sim.position) if self.level == "map" else None
            x = features_v3(sim.ranges, self._history, static, self._velocity, self.direction,
                            reach, sim.sensor.max_range, self.frames)  # fmt: skip
            self._history = [sim.ranges.copy(), *self._history][: self.frames - 1]
            return x.astype(np.float32)
        x = features(sim.ranges, self._prev, self.direction, reach, sim.sensor.max_range,
                     self._x)  # fmt: skip
        self._prev = sim.ranges.copy()
        return x.astype(np.float32)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        # what replays this episode (state): the generator as the episode is drawn, and
        # every action since
        self._drawn_from = copy.deepcopy(self.np_random.bit_generator.state)
        self._drawn_families = self.families  # a curriculum changes them between episodes
        self._actions: list[NDArray[np.float64]] = []
        self._prev = None
        self._history = []
        self._velocity = np.zeros(2)
        self._draw()
        self.t = 0
        self._ended = None
        return self._observe(), {}

    def state(self) -> dict[str, Any]:
        """What brings a fresh environment to this one's state (:meth:`restore`): the
        random generator as this episode was drawn (JSON-able), the families it was drawn
        from (a curriculum's stage may since have changed them) and the actions taken
        since, shape (t, 2). The simulator is deterministic, so replaying them rebuilds
        everything else; nothing is pickled."""
        if self._ended == "not started":
            raise InvalidArgumentError("the environment has not been reset: no state")
        actions = np.array(self._actions, dtype=np.float64).reshape(-1, 2)
        return {"drawn_from": self._drawn_from, "actions": actions, "ended": self._ended,
                "drawn_families": list(self._drawn_families)}  # fmt: skip

    def restore(self, state: dict[str, Any]) -> NDArray[np.float32]:
        """Bring this environment to ``state`` (:meth:`state`) by drawing the same episode
        and replaying its actions; returns the observation there. The families of later
        episodes stay this environment's (a state without ``drawn_families``, from before
        curricula came, was drawn from them too)."""
        try:
            self.np_random = np.random.default_rng()
            self.np_random.bit_generator.state = state["drawn_from"]
            actions = np.asarray(state["actions"], dtype=np.float64).reshape(-1, 2)
            drawn = state.get("drawn_families")
            drawn = self.families if drawn is None else _names(drawn, "families", "family")
            for f in drawn:
                check_family(f)
        except (KeyError, TypeError, ValueError) as exc:
            raise InvalidArgumentError(f"not an environment's state ({exc})") from None
        if len(actions) > self.max_steps or not np.isfinite(actions).all():
            raise InvalidArgumentError("not an environment's state (its actions are not "
                                       "an episode's)")  # fmt: skip
        families, self.families = self.families, drawn
        try:
            obs, _ = self.reset()
        finally:
            self.families = families
        for a in actions:
            obs, *_ = self.step(a)
        self._ended = state.get("ended")
        return obs

    def step(
        self, action: NDArray[np.floating[Any]]
    ) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        if self._ended is not None:
            why = "call reset() first" if self._ended == "not started" else (
                f"the episode has ended ({self._ended}); call reset()")  # fmt: skip
            raise gymnasium.error.ResetNeeded(why)
        given = np.asarray(action)
        if given.shape != (2,) or given.dtype.kind not in "iuf":
            raise InvalidArgumentError(f"action must be 2 real numbers of shape (2,); got "
                                       f"{given.dtype} values of shape {given.shape}")  # fmt: skip
        a: NDArray[np.float64] = given.astype(np.float64)
        if not np.isfinite(a).all():
            raise InvalidArgumentError(f"action must be 2 finite numbers; got {a.tolist()}")
        self._actions.append(a.copy())
        a = np.clip(a, -1.0, 1.0)
        norm = math.hypot(a[0], a[1])
        if norm > 1.0:
            a /= norm
        n = self.sim.sensor.n_rays
        a = to_world(a, direction_frame(self.direction, n), n)
        self._velocity = a
        w = self.reward
        before = self.sim.position.copy()
        u = self.direction
        un = math.hypot(u[0], u[1])
        self.t += 1
        info: dict[str, Any] = {}
        if self.game is not None:
            captured = self.game.step(a)
            contact = self.game.contacts > 0
            reward = w.survive
            terminated = captured or contact
            if terminated:
                reward -= w.contact
            info["is_success"] = False
            truncated = not terminated and self.t >= self.max_steps
            info["survived"] = truncated
            if terminated or truncated:
                self._ended = "terminated" if terminated else "truncated"
            return self._observe(), float(reward), terminated, truncated, info
        res = self.sim.step(a)
        moved = self.sim.position - before
        reward = w.progress * (float(moved @ u) / un if un > 0 else 0.0) - w.time
        if w.proximity > 0 and res.min_gap < w.near:
            reward -= w.proximity * (1.0 - max(0.0, res.min_gap) / w.near)
        terminated = bool(res.reached or res.contact)
        if res.reached and not res.contact:
            reward += w.success
        if res.contact:
            reward -= w.contact
        info["is_success"] = bool(res.reached and not res.contact)
        truncated = not terminated and self.t >= self.max_steps
        if terminated or truncated:
            self._ended = "terminated" if terminated else "truncated"
        return self._observe(), float(reward), terminated, truncated, info
