"""Peers from navground (PyPI ``navground``, an optional extra): HRVO, HL and ORCA driven
inside copi's simulator at level ``oracle``."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.core import Agent, Observation, Task, check_sensing
from copi.errors import CopiError, InvalidArgumentError
from copi.online import Steering

__all__ = ["NAVGROUND_BEHAVIORS", "NavgroundAgent", "NavgroundMissingError", "navground_available"]

NAVGROUND_BEHAVIORS = {"navground-hrvo": "HRVO", "navground-hl": "HL", "navground-orca": "ORCA"}
"""copi's method names for navground's behaviours."""


class NavgroundMissingError(CopiError):
    """A navground peer was asked for, and navground is not installed."""


def navground_available() -> bool:
    """Whether navground can be imported."""
    try:
        import navground.core  # noqa: F401
    except ImportError:
        return False
    return True


class NavgroundAgent(Agent):
    """One of navground's behaviours as an :class:`copi.online.Agent`.

    The behaviour is given an omnidirectional disc of copi's agent radius and speed 1, the
    world's walls as line obstacles, every moving obstacle as a neighbour (position,
    radius and velocity over the last step), and as target the point the static route
    aims at (the same global direction every ``map``-level method gets). Level
    ``oracle``; navground's defaults, with ``safety_margin`` and ``horizon`` tuned.

    Parameters
    ----------
    behavior : str
        navground's behaviour type: ``HRVO``, ``HL`` or ``ORCA``.
    safety_margin : float
        navground's safety margin, agent steps.
    horizon : float
        How far around the agent navground's behaviour looks, agent steps (navground's
        ``horizon`` is a distance).
    time_horizon : float, optional
        ORCA's and HRVO's time horizon, steps (None: navground's own, 10).
    neighbours : int, optional
        The most neighbours ORCA or HRVO considers (None: navground's own, all of them).
    """

    sensing = "oracle"
    steers_itself = True

    def __init__(
        self,
        behavior: str,
        *,
        safety_margin: float = 0.3,
        horizon: float = 5.0,
        time_horizon: float | None = None,
        neighbours: int | None = None,
    ) -> None:
        if not navground_available():
            raise NavgroundMissingError(
                "navground is not installed: pip install 'copi[peers]' (or navground) "
                "to run its behaviours"
            )
        names = {v: k for k, v in NAVGROUND_BEHAVIORS.items()}
        if behavior not in names:
            raise CopiError(
                f"behavior must be one of {', '.join(sorted(names))}; got {behavior!r}"
            )
        self.behavior = behavior
        self.name = names[behavior]
        self.safety_margin = float(safety_margin)
        self.horizon = float(horizon)
        for key, v in (("time_horizon", time_horizon), ("neighbours", neighbours)):
            if v is not None and not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise InvalidArgumentError(f"{key} must be a positive number or None; got {v!r}")
        self.time_horizon = time_horizon
        self.neighbours = neighbours

    def reset(self, task: Task) -> None:
        check_sensing(task.sensing, self.sensing, method=self.name)
        from navground import core

        self._core = core
        if task.world is None:
            raise InvalidArgumentError(
                f"{self.name} needs the task's world (level 'oracle'); got a task at "
                f"{task.sensing!r} without it"
            )
        b: Any = core.Behavior.make_type(self.behavior)
        b.kinematics = core.kinematics.OmnidirectionalKinematics(max_speed=1.0)
        b.radius = task.agent_radius
        b.optimal_speed = 1.0
        b.horizon = self.horizon
        b.safety_margin = self.safety_margin
        if self.time_horizon is not None and hasattr(b, "time_horizon"):
            b.time_horizon = float(self.time_horizon)
        if self.neighbours is not None and self.behavior in ("ORCA", "HRVO"):
            b.set("max_neighbors", int(self.neighbours))
        segs = task.world.segments
        b.environment_state.line_obstacles = [
            core.LineSegment(np.array(s[:2]), np.array(s[2:])) for s in np.asarray(segs)
        ]
        self.b = b
        self.steering = Steering()
        self.steering.reset(task)
        self.velocity = np.zeros(2)

    def act(self, obs: Observation) -> NDArray[np.float64]:
        assert obs.position is not None and obs.obstacles is not None
        core = self._core
        b = self.b
        desired, reach = self.steering.aim(obs)
        n = math.hypot(desired[0], desired[1])
        if n == 0:
            return np.zeros(2)
        aim = obs.position + desired / n * min(reach, 1e6)
        b.position = np.asarray(obs.position, dtype=np.float64)
        b.velocity = self.velocity
        b.target = core.Target.Point(aim, 0.05)
        b.environment_state.neighbors = [
            core.Neighbor(position=o[:2], radius=float(o[4]), velocity=o[2:4], id=i)
            for i, o in enumerate(np.asarray(obs.obstacles, dtype=np.float64))
        ]
        cmd = b.compute_cmd(1.0, frame=core.Frame.absolute)
        v = np.array(cmd.velocity, dtype=np.float64)
        s = math.hypot(v[0], v[1])
        if s > 1.0:
            v /= s
        if not np.isfinite(v).all():
            v = np.zeros(2)
        self.velocity = v
        return v
