"""The homicidal chauffeur game (paper §IV, second experiment; Isaacs 1965).

A pursuer (a car: speed V_p, minimum turn radius R, turn control u in [-1, 1]) chases an
evader (speed V_e < V_p, any heading phi); capture when they come within ell. The paper
gives the evader's position relative to the pursuer,

    x' = V_e sin(phi) - V_p y u / R,    y' = V_e cos(phi) - V_p + V_p x u / R,

copi simulates the same game in the world frame: the pursuer's arcs are integrated
exactly (constant u over a sub-step is a circular arc of radius R / |u|), the evader
moves straight within a sub-step, and capture is tested on the closest approach within
each sub-step. The two agree with: x the evader's offset to the car's right and y along
the car's heading (:func:`_relative`); phi the evader's heading measured clockwise from
the car's; and u_paper = -u, since copi's u > 0 turns the car left (counter-clockwise,
heading' = u V_p / R) where the paper's turns it right. tests/games/test_chauffeur.py
integrates the paper's equations and checks copi's steps against them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from copi.errors import InvalidArgumentError
from copi.games import _kernels as _k

__all__ = [
    "ChauffeurParams",
    "Pursuer",
    "critical_beta",
    "evader_direction",
    "isaacs_control",
]


def critical_beta(gamma: float) -> float:
    """Isaacs' capture condition: with gamma = V_e / V_p and beta = ell / R, the pursuer
    captures from every initial state iff beta >= sqrt(1 - gamma^2) + gamma asin(gamma) - 1.

    Examples
    --------
    >>> round(critical_beta(0.5), 8)
    0.12782479
    """
    if not 0 <= gamma < 1:
        raise InvalidArgumentError(f"gamma = V_e / V_p must be in [0, 1); got {gamma}")
    return math.sqrt(1 - gamma * gamma) + gamma * math.asin(gamma) - 1


@dataclass(frozen=True)
class ChauffeurParams:
    """Parameters of a game, in agent steps and time steps."""

    evader_speed: float = 1.0
    """V_e: the evader is the navigation agent (at most 1 agent step per time step)."""
    pursuer_speed: float = 1.0 / 0.7
    """V_p > V_e (default gamma = V_e / V_p = 0.7)."""
    turn_radius: float = 4.0
    """R, the pursuer's minimum turn radius."""
    capture_radius: float = 0.8
    """ell; beta = ell / R = 0.2 < beta_crit(0.7) = 0.257: an evader playing well can
    escape in the open plane, so the game is not decided in advance."""
    substeps: int = 10
    """Sub-steps per time step for the pursuer's arc and the capture test."""

    def __post_init__(self) -> None:
        if not 0 < self.evader_speed < self.pursuer_speed:
            raise InvalidArgumentError(
                "need 0 < evader_speed < pursuer_speed; "
                f"got {self.evader_speed}, {self.pursuer_speed}"
            )
        if self.turn_radius <= 0 or self.capture_radius <= 0 or self.substeps < 1:
            raise InvalidArgumentError("turn_radius, capture_radius and substeps must be > 0")

    @property
    def gamma(self) -> float:
        return self.evader_speed / self.pursuer_speed

    @property
    def beta(self) -> float:
        return self.capture_radius / self.turn_radius


def _relative(
    p: NDArray[np.float64], heading: float, e: NDArray[np.float64]
) -> tuple[float, float]:
    """The evader in the pursuer's frame: (x lateral, to the right; y forward)."""
    right, forward = _k.relative(float(p[0]), float(p[1]), float(heading), float(e[0]),
                                 float(e[1]))  # fmt: skip
    return float(right), float(forward)


def isaacs_control(
    p: NDArray[np.float64],
    heading: float,
    e: NDArray[np.float64],
    turn_radius: float,
    dt_turn: float,
) -> float:
    """The pursuer's strategy (Isaacs): turn hard towards the evader, drive straight when
    it is dead ahead, and swerve away first when it is inside a turning circle (where the
    car cannot reach it by turning towards it).

    ``dt_turn`` is the largest heading change per sub-step (V_p dt / R); when the evader
    is nearly ahead, u is just enough to point at it, so the car does not chatter."""
    return float(_k.isaacs_u(float(p[0]), float(p[1]), float(heading), float(e[0]),
                             float(e[1]), float(turn_radius), float(dt_turn)))  # fmt: skip


def evader_direction(
    e: NDArray[np.float64], p: NDArray[np.float64], heading: float, params: ChauffeurParams
) -> NDArray[np.float64]:
    """The evader's game strategy: flee along the line of centres, except when the car
    is close and coming at it, then sidestep across its path into its turning circle.

    On the capture circle, the distance's rate of change is gamma-weighted only by the
    evader's radial component (the car's turn terms cancel), so fleeing radially is the
    best it can do there; further out, running straight away lets the faster car close
    in, while stepping sideways within a turn radius of its path makes it overshoot."""
    x, y = _relative(p, heading, e)
    d = math.hypot(x, y)
    away = (e - p) / d if d > 0 else np.array([1.0, 0.0])
    r = params.turn_radius
    if y > 0 and d < 1.5 * r and abs(x) < r:
        # Ahead and close: step perpendicular to the car's heading, on the side the
        # evader already is (into the turning circle there), keeping away radially.
        c, s = math.cos(heading), math.sin(heading)
        side = 1.0 if x >= 0 else -1.0
        right = np.array([s, -c]) * side  # the car's right (or left) in the world
        v = right + 0.3 * away
        return v / math.hypot(v[0], v[1])  # not np.linalg.norm: BLAS rounds per processor
    return away


class Pursuer:
    """The car: position, heading, and its motion over one time step."""

    def __init__(
        self, position: NDArray[np.float64], heading: float, params: ChauffeurParams
    ) -> None:
        self.position = np.asarray(position, dtype=np.float64).copy()
        self.heading = float(heading)
        self.params = params

    def arc(self, u: float, dt: float) -> NDArray[np.float64]:
        """Displacement over time dt with constant control u (exact circular arc), and
        the heading is advanced by u V_p dt / R: u > 0 turns left (counter-clockwise),
        the opposite of the paper's u (see the module docstring)."""
        p = self.params
        dx, dy, self.heading = _k.arc(self.heading, float(u), p.pursuer_speed, p.turn_radius,
                                      float(dt))  # fmt: skip
        return np.array([dx, dy])
