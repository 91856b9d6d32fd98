"""The two ablations of copi's own parts: no avoidance at all, and copi's guard without
any learnt capability."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.baselines._common import Steered, unit
from copi.core import Observation, Task
from copi.errors import InvalidArgumentError
from copi.online import kernels

__all__ = ["CompassGuard", "Straight"]


class Straight(Steered):
    """Follow the global direction at full speed, ignoring every obstacle (walls still
    stop the agent). Level ``sensor``; nothing learnt, nothing tuned."""

    name = "straight"

    def steer(
        self, obs: Observation, desired: NDArray[np.float64], reach: float
    ) -> NDArray[np.float64]:
        u, _ = unit(desired)
        self._explained(u[None], [1.0], "the global direction, the only candidate")
        return u * min(1.0, reach)


class CompassGuard(Steered):
    """copi's guard and escape (:class:`copi.online.ContextController` with ``guard``)
    over all compass directions, with no capabilities: every direction is a candidate
    everywhere. The ablation of the learnt part of ``copi-extended``.

    Level ``sensor``; at ``map`` the static reading tells the guard which hits are walls,
    as it does for copi. Hand-written; ``guard`` is tuned.

    Parameters
    ----------
    guard : float
        Clearance a step must keep from moving obstacles' hit points (see
        :class:`copi.online.ContextController`).
    directions : int
        Compass directions offered (16: as ``copi-extended``).
    """

    name = "compass-guard"

    def __init__(self, *, guard: float = 1.2, directions: int = 16) -> None:
        if not (math.isfinite(guard) and guard > 0):
            raise InvalidArgumentError(f"guard must be a finite number > 0; got {guard!r}")
        if int(directions) != directions or directions < 1:
            raise InvalidArgumentError(f"directions must be a positive int; got {directions!r}")
        self.guard = float(guard)
        a = 2 * np.pi * np.arange(int(directions)) / int(directions)
        self._cand = np.ascontiguousarray(np.column_stack([np.cos(a), np.sin(a)])[None])
        self._ok = np.ones((1, int(directions)), dtype=np.bool_)
        self._out = np.empty(5)

    def reset(self, task: Task) -> None:
        super().reset(task)
        self._node = np.zeros((task.n_rays, 1))  # one node at 0, transposed (the kernels' layout)
        self._no_static = np.full(task.n_rays, np.inf)

    def steer(
        self, obs: Observation, desired: NDArray[np.float64], reach: float
    ) -> NDArray[np.float64]:
        static = self._no_static if obs.static is None else obs.static
        out = self._out
        kernels.decide(
            np.asarray(obs.ranges, dtype=np.float64), static, self._node, self._cand, self._ok,
            desired[0], desired[1], reach, self.guard, self.cos, self.sin, self.max_range, out,
        )  # fmt: skip
        if self.explain:
            self._explain_guard(obs, static, desired, reach)
        return out[:2].copy()

    def _explain_guard(self, obs: Observation, static: Any, desired: Any, reach: float) -> None:
        """Each compass move's alignment with the global direction, -inf where the guard
        refuses it (the kernel's own test, :func:`copi.online.kernels.guard_verdicts`)."""
        ranges = np.asarray(obs.ranges, dtype=np.float64)
        u, _ = unit(desired)
        dirs = np.ascontiguousarray(self._cand[0])
        admitted = np.empty(len(dirs), dtype=np.bool_)
        kernels.guard_verdicts(ranges, static, dirs, float(desired[0]), float(desired[1]),
                                reach, self.guard, self.cos, self.sin, self.max_range,
                                admitted)  # fmt: skip
        self._explained(dirs, np.where(admitted, dirs @ u, -np.inf),
                        "alignment with the global direction; -inf: refused by the guard")
