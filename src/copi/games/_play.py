"""Playing the homicidal chauffeur, in the open plane and in copi's worlds."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi.games import _kernels as _k
from copi.games._chauffeur import ChauffeurParams, Pursuer, evader_direction, isaacs_control

__all__ = ["GameResult", "first_contact", "play_open"]


@dataclass(frozen=True)
class GameResult:
    """How a game ended."""

    captured: bool
    capture_time: float
    """Time of capture (time steps, fractional), or the horizon when not captured."""
    closest: float
    """Least pursuer-evader distance over the game."""
    contacts: int = 0
    """Steps at which the evader touched a moving obstacle."""
    evader_path: list[list[float]] = field(default_factory=list)
    pursuer_path: list[list[float]] = field(default_factory=list)


def first_contact(
    p0: NDArray[np.float64],
    dp: NDArray[np.float64],
    e0: NDArray[np.float64],
    de: NDArray[np.float64],
    ell: float,
) -> tuple[float, float]:
    """For two points moving linearly over tau in [0, 1]: the first tau at which they
    are within ``ell`` (inf if never), and their least distance."""
    tau, closest = _k.first_contact(float(p0[0]), float(p0[1]), float(dp[0]), float(dp[1]),
                                    float(e0[0]), float(e0[1]), float(de[0]), float(de[1]),
                                    float(ell))  # fmt: skip
    return float(tau), float(closest)


def play_open(
    params: ChauffeurParams,
    evader: Any,
    pursuer: Any,
    heading: float,
    *,
    horizon: float,
    dt: float = 0.01,
    evader_policy: Callable[..., NDArray[np.float64]] | None = None,
    record: bool = False,
) -> GameResult:
    """A game in the open plane (no walls), in small time steps ``dt``: the pursuer plays
    :func:`isaacs_control`, the evader ``evader_policy(e, p, heading, params)`` (default
    :func:`evader_direction`) at full speed."""
    policy = evader_policy or evader_direction
    car = Pursuer(np.asarray(pursuer, dtype=np.float64), heading, params)
    e = np.asarray(evader, dtype=np.float64).copy()
    t = 0.0
    closest = math.inf
    ep: list[list[float]] = []
    pp: list[list[float]] = []
    dturn = params.pursuer_speed * dt / params.turn_radius
    while t < horizon:
        u = isaacs_control(car.position, car.heading, e, params.turn_radius, dturn)
        direction = policy(e, car.position, car.heading, params)
        de = params.evader_speed * dt * direction
        dp = car.arc(u, dt)
        tau, near = first_contact(car.position, dp, e, de, params.capture_radius)
        closest = min(closest, near)
        if math.isfinite(tau):
            return GameResult(True, t + tau * dt, closest, 0, ep, pp)
        car.position = car.position + dp
        e = e + de
        t += dt
        if record:
            ep.append(e.tolist())
            pp.append(car.position.tolist())
    return GameResult(False, horizon, closest, 0, ep, pp)


def pursuer_step(
    car: Pursuer,
    e0: NDArray[np.float64],
    de: NDArray[np.float64],
    segments: NDArray[np.float64],
    radius: float,
    control: float | None = None,
) -> tuple[float, float]:
    """Move the car over one time step (``car.params.substeps`` sub-steps) while the
    evader goes from e0 by de in a straight line, steering by Isaacs' strategy at each
    sub-step, or holding ``control`` when given. Walls stop the car (it never passes
    through one; its heading keeps turning as steered); it ignores moving obstacles.
    Returns (tau of capture in [0, 1] or inf, least distance)."""
    params = car.params
    segs = np.ascontiguousarray(segments, dtype=np.float64).reshape(-1, 4)
    x, y, car.heading, tau, closest = _k.pursuer_step(
        float(car.position[0]), float(car.position[1]), float(car.heading),
        float(e0[0]), float(e0[1]), float(de[0]), float(de[1]), segs, float(radius),
        params.pursuer_speed, params.turn_radius, params.capture_radius, params.substeps,
        0.0 if control is None else float(control), control is None,
    )  # fmt: skip
    car.position = np.array([x, y])
    return float(tau), float(closest)
