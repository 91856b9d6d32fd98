"""The homicidal chauffeur as a PettingZoo ParallelEnv (``copi/Chauffeur-v0``)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray
from pettingzoo import ParallelEnv

from copi.errors import InvalidArgumentError
from copi.games import ChauffeurGame, ChauffeurParams
from copi.world import render_rgb

__all__ = ["ChauffeurEnv", "parallel_env"]

_BOUND = 1000.0


class ChauffeurEnv(ParallelEnv):  # type: ignore[misc]
    """Two agents, ``pursuer`` and ``evader``, in one of the paper's random worlds.

    Observations (float32)
        pursuer: the evader's position in the car's frame (right, forward), 2 values.
        evader: its 32 range readings, the car's position relative to it (2) and the
        car's heading as (cos, sin) (2): 36 values.
    Actions (float32 in [-1, 1])
        pursuer: the turn control u (1 value; +1 is a hard left).
        evader: a velocity (2 values; norm clipped to 1).
    Rewards
        Each step the evader survives: evader +0.01, pursuer -0.01; at capture: pursuer
        +10, evader -10.
    Episode
        Both terminate at capture; both are truncated after ``max_steps``.

    ``reset(seed=s)`` draws game 0 of seed s (:meth:`ChauffeurGame.draw`); options
    ``{"game": k}`` picks game k, ``{"dynamic": False}`` removes the moving obstacles.
    """

    metadata = {
        "name": "copi/Chauffeur-v0",
        "render_modes": ["rgb_array"],
        "is_parallelizable": True,
    }

    def __init__(
        self,
        render_mode: str | None = None,
        *,
        params: ChauffeurParams | None = None,
        dynamic: bool = True,
        max_steps: int = 300,
    ) -> None:
        if render_mode not in (None, "rgb_array"):
            raise InvalidArgumentError(
                f"render_mode must be 'rgb_array' or None; got {render_mode!r}"
            )
        self.render_mode = render_mode
        self.params = params or ChauffeurParams()
        self.dynamic = dynamic
        self.max_steps = int(max_steps)
        self.possible_agents = ["pursuer", "evader"]
        self.agents: list[str] = []
        self._obs_spaces = {
            "pursuer": spaces.Box(-_BOUND, _BOUND, shape=(2,), dtype=np.float32),
            "evader": spaces.Box(
                np.r_[np.zeros(32), -_BOUND, -_BOUND, -1, -1].astype(np.float32),
                np.r_[np.full(32, 10.0), _BOUND, _BOUND, 1, 1].astype(np.float32),
                dtype=np.float32,
            ),
        }
        self._act_spaces = {
            "pursuer": spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32),
            "evader": spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32),
        }
        self.game: ChauffeurGame | None = None

    def _agent(self, agent: Any) -> str:
        if agent not in self.possible_agents:
            raise InvalidArgumentError(
                f"agent must be one of {', '.join(self.possible_agents)}; got {agent!r}"
            )
        return str(agent)

    def observation_space(self, agent: str) -> spaces.Space[Any]:
        return self._obs_spaces[self._agent(agent)]

    def action_space(self, agent: str) -> spaces.Space[Any]:
        return self._act_spaces[self._agent(agent)]

    def _action(self, actions: Any, agent: str) -> NDArray[np.float64]:
        """``actions[agent]`` checked against the agent's action space (shape, finite)."""
        if not isinstance(actions, dict) or agent not in actions:
            got = sorted(actions) if isinstance(actions, dict) else type(actions).__name__
            raise InvalidArgumentError(
                f"step needs an action for each of {', '.join(self.agents)}; got {got}"
            )
        shape = self._act_spaces[agent].shape
        try:
            a = np.asarray(actions[agent], dtype=np.float64)
        except (TypeError, ValueError):
            raise InvalidArgumentError(
                f"the {agent}'s action must be {shape[0]} number(s); got "
                f"{type(actions[agent]).__name__}"
            ) from None
        if a.shape != shape or not np.isfinite(a).all():
            raise InvalidArgumentError(
                f"the {agent}'s action must be {shape[0]} finite number(s) (its action space "
                f"is {self._act_spaces[agent]}); got {a.tolist() if a.size <= 8 else a.shape}"
            )
        return a

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, NDArray[np.float32]], dict[str, dict[str, Any]]]:
        opts = dict(options or {})  # other keys are ignored (PettingZoo's API test sends some)
        k = int(opts.get("game", 0))
        dynamic = bool(opts.get("dynamic", self.dynamic))
        if seed is None:
            seed = int(np.random.default_rng().integers(2**31))
        self.game = ChauffeurGame.draw(
            int(seed), k, dynamic=dynamic, params=self.params, record=self.render_mode is not None
        )
        self.agents = list(self.possible_agents)
        return self._observations(), {a: {} for a in self.agents}

    def _observations(self) -> dict[str, NDArray[np.float32]]:
        g = self.game
        assert g is not None
        car, e = g.car, g.sim.position
        dx, dy = e - car.position
        c, s = math.cos(car.heading), math.sin(car.heading)
        rel = np.clip([dx * s - dy * c, dx * c + dy * s], -_BOUND, _BOUND)
        back = np.clip(car.position - e, -_BOUND, _BOUND)
        return {
            "pursuer": np.asarray(rel, dtype=np.float32),
            "evader": np.concatenate([g.sim.ranges, back, [c, s]]).astype(np.float32),
        }

    def step(self, actions: dict[str, Any]) -> tuple[dict[str, Any], ...]:
        g = self.game
        if g is None or not self.agents:
            raise InvalidArgumentError(
                "call reset() before step(), and again after an episode ends"
            )
        extra = sorted(set(actions) - set(self.agents)) if isinstance(actions, dict) else []
        if extra:
            raise InvalidArgumentError(
                f"step got actions of {', '.join(map(str, extra))}, which are not among the "
                f"agents ({', '.join(self.agents)})"
            )
        u = float(np.clip(self._action(actions, "pursuer")[0], -1, 1))
        captured = g.step(self._action(actions, "evader"), pursuer_control=u)
        obs = self._observations()
        if captured:
            rewards = {"pursuer": 10.0, "evader": -10.0}
        else:
            rewards = {"pursuer": -0.01, "evader": 0.01}
        truncated = not captured and g.t >= self.max_steps
        terms = {a: captured for a in self.agents}
        truncs = {a: truncated for a in self.agents}
        infos: dict[str, dict[str, Any]] = {a: {"contacts": g.contacts} for a in self.agents}
        if captured or truncated:
            self.agents = []
        return obs, rewards, terms, truncs, infos

    def render(self) -> NDArray[np.uint8] | None:
        """The chase as an RGB image (400 x 400): walls, moving obstacles, the evader
        (red, with its rays and path) and the car (a dark arrowhead along its heading in
        a ring of the capture radius, with its path in grey). There is no goal."""
        if self.render_mode is None or self.game is None:
            return None
        g = self.game
        car = (g.car.position, g.car.heading, self.params.capture_radius)
        path = np.asarray(g.car_path) if g.car_path else None
        return render_rgb(g.sim, goal=False, pursuer=car, pursuer_path=path)

    def close(self) -> None:
        self.game = None


def parallel_env(**kwargs: Any) -> ChauffeurEnv:
    """``copi/Chauffeur-v0`` (PettingZoo's module-level constructor convention)."""
    return ChauffeurEnv(**kwargs)
