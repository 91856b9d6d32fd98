"""The ``learnt`` preset's agent: capabilities whose learnt safety carries the choice."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.errors import InvalidArgumentError
from copi.learning import Capabilities
from copi.learning._safety import SafetyModel, template_directions
from copi.online import _kernels
from copi.online._agent import Observation, Steering, Task

__all__ = ["LearntAgent", "node_priors"]


def node_priors(caps: Capabilities, model: SafetyModel) -> NDArray[np.float64]:
    """Per context-map node, P(safe) of each compass direction in the world frame: its
    template's prior (learnt in the template's frame) read through the node's symmetry
    g (direction d in the world is g d in the template's frame). Shape (n_nodes, D)."""
    mats = caps.group.matrices[caps.node_element]  # (n, 2, 2): world -> template
    idx = template_directions(mats, model.template_safe.shape[1])
    return np.ascontiguousarray(model.template_safe[caps.node_template[:, None], idx])


class LearntAgent:
    """copi's ``learnt`` preset as an :class:`~copi.online.Agent` (paper §II-D, §III).

    Each step the reading is recognised (nearest context-map node, its template and
    symmetry), every compass direction and waiting is scored by the global direction
    and by what the probes taught — the safety network over the reading turned to that
    direction, and the template's prior through the symmetry — and the best one that a
    hand-written guard allows is taken (see :func:`copi.online._kernels.decide_learnt`).
    With ``alpha = beta = 0`` and no waiting this is ``compass-guard``: the ablation of
    everything learnt.

    Parameters
    ----------
    capabilities : Capabilities
        Learnt with safety probes (``copi learn --preset learnt``).
    guard : float
        The hand-written guard's reach (0: none).
    alpha, beta : float
        Weights of the safety network and of the template priors.
    wait : bool
        Standing still is among the behaviours.
    """

    sensing = "sensor"

    def __init__(
        self,
        capabilities: Capabilities,
        *,
        name: str = "copi-learnt",
        guard: float = 1.05,
        alpha: float = 1.0,
        beta: float = 0.0,
        wait: bool = True,
        safety: SafetyModel | None = None,
    ) -> None:
        model = safety if safety is not None else capabilities.safety
        if model is None:
            raise InvalidArgumentError(
                "these capabilities have no safety priors (the learnt preset needs them): "
                "learn them with copi learn --preset learnt"
            )
        self.capabilities = capabilities
        self.name = name
        self.guard = float(guard)
        self.alpha = float(alpha)
        self.beta = float(beta)
        self.wait = bool(wait)
        self.model = model
        self._net = np.ascontiguousarray(model.net, dtype=np.float64)
        self._nodes = np.ascontiguousarray(capabilities.nodes, dtype=np.float64)
        self._prior = node_priors(capabilities, model)
        n = capabilities.n_rays
        a = 2 * np.pi * np.arange(n) / n
        self._cos, self._sin = np.cos(a), np.sin(a)
        self._feat = np.empty(8 * n)
        self._p = np.empty(self._prior.shape[1] + 1)
        self._out = np.empty(5)
        self.steering = Steering()
        self._prev: NDArray[np.float64] | None = None
        self.n_waits = 0
        self.n_decisions = 0

    def reset(self, task: Task) -> None:
        if task.n_rays != self.capabilities.n_rays:
            raise InvalidArgumentError(
                f"the capabilities were learnt for {self.capabilities.n_rays} rays; "
                f"the sensor has {task.n_rays}"
            )
        self.max_range = float(task.max_range)
        self._no_static = np.full(task.n_rays, np.inf)
        self.steering.reset(task)
        self._prev = None
        self.n_waits = 0
        self.n_decisions = 0

    def act(self, obs: Observation) -> NDArray[np.float64]:
        desired, reach = self.steering.aim(obs)
        s = np.asarray(obs.ranges, dtype=np.float64)
        prev = s if self._prev is None else self._prev
        static = self._no_static if obs.static is None else obs.static
        out = self._out
        _kernels.decide_learnt(
            s, prev, static, self._nodes, self._prior, self._net, desired[0], desired[1],
            reach, self.guard, self.alpha, self.beta, self.wait, self._cos, self._sin,
            self.max_range, self._feat, self._p, out,
        )  # fmt: skip
        if out[2] < 0:
            what = "not finite and >= 0" if out[2] == -1 else "static reading not >= 0"
            raise InvalidArgumentError(f"ranges must be finite and >= 0; got a reading {what}")
        self._prev = s.copy()
        self.n_decisions += 1
        self.n_waits += out[4] == -4.0
        return out[:2].copy()

    def counters(self) -> dict[str, Any]:
        """Per-episode diagnostics stored with the result."""
        return {"unfamiliar": 0.0}
