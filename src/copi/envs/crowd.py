"""Many agents among each other as a PettingZoo ParallelEnv (``copi/Crowd-v0``): the crowd
of ``copi crowd`` (:class:`copi.world.crowd.Crowd`), every agent a learner's."""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray
from pettingzoo import ParallelEnv

from copi._validation import positive_int
from copi.errors import InvalidArgumentError
from copi.world import rasterize
from copi.world.crowd import Crowd, check_density, crowd_room

__all__ = ["CrowdEnv", "parallel_env"]


class CrowdEnv(ParallelEnv):  # type: ignore[misc]
    """``agents`` agents, ``agent_0`` .. ``agent_{n-1}``, in a square room at ``density``
    agents per square agent step, each with a goal (:class:`copi.world.crowd.Crowd`).

    Observations (float32)
        Each agent's 32 range readings (walls and the other agents' discs, in agent steps,
        clipped to the sensor's 10) and its goal relative to it (2): 34 values.
    Actions (float32 in [-1, 1])
        A velocity (2 values; norm clipped to 1).
    Rewards
        Each step, the distance gained toward the goal; +10 on reaching it, -10 on a
        contact with another agent.
    Episode
        An agent terminates at its goal or at its first contact, and leaves the room;
        the others are truncated after ``max_steps``.

    ``reset(seed=s)`` places the crowd from seed s (as ``copi crowd`` places run 0 of
    seed s); the infos say ``is_success`` and ``contact``.
    """

    metadata = {"name": "copi/Crowd-v0", "render_modes": ["rgb_array"], "is_parallelizable": True}

    def __init__(
        self,
        render_mode: str | None = None,
        *,
        agents: int = 20,
        density: float = 0.1,
        max_steps: int = 200,
    ) -> None:
        if render_mode not in (None, "rgb_array"):
            raise InvalidArgumentError(
                f"render_mode must be 'rgb_array' or None; got {render_mode!r}"
            )
        self.render_mode = render_mode
        self.room = crowd_room(agents, density)
        self.density = check_density(density)
        self.max_steps = positive_int(max_steps, "max_steps")
        self.possible_agents = [f"agent_{i}" for i in range(int(agents))]
        self._index = {a: i for i, a in enumerate(self.possible_agents)}
        self.agents: list[str] = []
        side = self.room.bounds[2]
        max_range = 10.0
        self._obs_space = spaces.Box(
            np.r_[np.zeros(32), -side, -side].astype(np.float32),
            np.r_[np.full(32, max_range), side, side].astype(np.float32),
            dtype=np.float32,
        )
        self._act_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.crowd: Crowd | None = None

    def _agent(self, agent: Any) -> str:
        if agent not in self._index:
            raise InvalidArgumentError(
                f"agent must be one of agent_0 .. agent_{len(self.possible_agents) - 1}; "
                f"got {agent!r}"
            )
        return str(agent)

    def observation_space(self, agent: str) -> spaces.Space[Any]:
        self._agent(agent)
        return self._obs_space

    def action_space(self, agent: str) -> spaces.Space[Any]:
        self._agent(agent)
        return self._act_space

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, NDArray[np.float32]], dict[str, dict[str, Any]]]:
        del options  # none (PettingZoo's API test sends some)
        if seed is None:
            seed = int(np.random.default_rng().integers(2**31))
        self.crowd = Crowd.draw(self.room, len(self.possible_agents),
                                np.random.default_rng([int(seed), 0]))  # fmt: skip
        self.agents = list(self.possible_agents)
        return self._observations(), {a: {} for a in self.agents}

    def _observations(self) -> dict[str, NDArray[np.float32]]:
        c = self.crowd
        assert c is not None
        side = self.room.bounds[2]
        rel = np.clip(c.goals - c.positions, -side, side)
        obs = np.concatenate([np.minimum(c.ranges, 10.0), rel], axis=1).astype(np.float32)
        return {a: obs[self._index[a]] for a in self.agents}

    def step(self, actions: dict[str, Any]) -> tuple[dict[str, Any], ...]:
        c = self.crowd
        if c is None or not self.agents:
            raise InvalidArgumentError("call reset() before step(), and again after an episode "
                                       "ends")  # fmt: skip
        if not isinstance(actions, dict):
            raise InvalidArgumentError(
                f"step needs a dict of actions by agent; got {type(actions).__name__}"
            )
        extra = sorted(set(map(str, actions)) - set(self.agents))
        if extra:
            raise InvalidArgumentError(f"step got actions of {', '.join(extra[:3])}, which are "
                                       "not among the agents still in the room")  # fmt: skip
        act = np.zeros((c.n_agents, 2))
        for a in self.agents:
            if a not in actions:
                raise InvalidArgumentError(f"step needs an action for each agent still in the "
                                           f"room; {a}'s is missing")  # fmt: skip
            try:
                v = np.asarray(actions[a], dtype=np.float64)
            except (TypeError, ValueError):
                v = np.asarray([np.nan])
            if v.shape != (2,) or not np.isfinite(v).all():
                raise InvalidArgumentError(
                    f"{a}'s action must be 2 finite numbers (its action space is "
                    f"{self._act_space}); got {v.tolist() if v.size <= 8 else v.shape}"
                )
            act[self._index[a]] = np.clip(v, -1.0, 1.0)
        before = np.hypot(*(c.goals - c.positions).T)
        res = c.step(act)
        after = np.hypot(*(c.goals - c.positions).T)
        truncated = c.t >= self.max_steps
        obs = self._observations()
        rewards, terms, truncs, infos = {}, {}, {}, {}
        for a in self.agents:
            i = self._index[a]
            rewards[a] = float(before[i] - after[i] + 10.0 * res.reached[i]
                               - 10.0 * res.contact[i])  # fmt: skip
            terms[a] = bool(res.left[i])
            truncs[a] = truncated and not terms[a]
            infos[a] = {"is_success": bool(res.reached[i] and not res.contact[i]),
                        "contact": bool(res.contact[i])}  # fmt: skip
        self.agents = [a for a in self.agents if not (terms[a] or truncs[a])]
        return obs, rewards, terms, truncs, infos

    def render(self) -> NDArray[np.uint8] | None:
        """The room as an RGB image (400 x 400): every agent still in it a blue disc,
        agent_0 red with its goal."""
        if self.render_mode is None or self.crowd is None:
            return None
        c = self.crowd
        others = c.active.copy()
        others[0] = False
        return rasterize(self.room, width=400, centers=c.positions[others], radii=c.radius,
                         position=c.positions[0] if c.active[0] else None,
                         goal=c.goals[0], agent_radius=c.radius)  # fmt: skip

    def close(self) -> None:
        self.crowd = None


def parallel_env(**kwargs: Any) -> CrowdEnv:
    """``copi/Crowd-v0`` (PettingZoo's module-level constructor convention)."""
    return CrowdEnv(**kwargs)
