"""The homicidal chauffeur in copi's worlds: walls, and (optionally) moving obstacles."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from copi._rng import Seed
from copi.errors import InvalidWorldError
from copi.games._chauffeur import ChauffeurParams, Pursuer, evader_direction
from copi.games._play import pursuer_step
from copi.world import (
    ObstacleSpec,
    RangeSensor,
    Simulator,
    World,
    WorldParams,
    place_obstacles,
    random_world,
)

__all__ = ["ChauffeurGame", "GAME_WORLDS"]

GAME_WORLDS = WorldParams(size=(22.0, 35.0))
"""Worlds for the game: the paper's polygons, from the larger half of the sizes (a car
with a turn radius of 4 needs room)."""

PURSUER_RADIUS = 0.3
"""The car's size against walls (it stops at them, as the agent does)."""


class ChauffeurGame:
    """One game: a :class:`~copi.world.Simulator` for the evader (walls, moving obstacles,
    its sensor) and a :class:`Pursuer` playing Isaacs' strategy.

    Each time step the evader's velocity is chosen first (by the caller), the world
    moves it (walls stop it, moving obstacles may touch it), and the car drives over the
    same time step in ``params.substeps`` arcs, steering at the evader's position along
    its straight move; capture is the first moment they are within the capture radius.
    Walls stop the car too; moving obstacles do not (it is the agent's problem, not the
    car's).

    Use :meth:`draw` for a random game; the same (seed, dynamic=False/True) pair gives
    the same world and starts, with or without obstacles.
    """

    def __init__(
        self,
        world: World,
        evader: Any,
        pursuer: Any,
        heading: float,
        centers: Any,
        radii: Any,
        *,
        params: ChauffeurParams | None = None,
        sensor: RangeSensor | None = None,
        seed: Seed = None,
        record: bool = False,
    ) -> None:
        self.params = params or ChauffeurParams()
        self.world = world
        evader = np.asarray(evader, dtype=np.float64)
        self.sim = Simulator(
            world,
            evader,
            evader,  # no goal in this game
            centers,
            radii,
            seed=seed,
            sensor=sensor,
            record=record,
            goal_tolerance=-1.0,
        )
        self.car = Pursuer(np.asarray(pursuer, dtype=np.float64), heading, self.params)
        self.t = 0
        self.captured = False
        self.capture_time = math.nan
        self.closest = math.inf
        self.contacts = 0
        self.record = record
        self.car_path: list[NDArray[np.float64]] = [self.car.position.copy()] if record else []

    @classmethod
    def draw(
        cls,
        seed: int,
        k: int,
        *,
        dynamic: bool,
        params: ChauffeurParams | None = None,
        sensor: RangeSensor | None = None,
        record: bool = False,
    ) -> ChauffeurGame:
        """Game k of a run: world, evader start, car start and heading from
        default_rng([seed, k]); obstacles (if ``dynamic``) from default_rng([seed, k, 1])."""
        params = params or ChauffeurParams()
        rng = np.random.default_rng([seed, k])
        world = random_world(rng, params=GAME_WORLDS, name=f"game-{k:05d}")
        xmin, ymin, xmax, ymax = world.bounds
        pts = rng.uniform([xmin, ymin], [xmax, ymax], size=(400, 2))
        pts = pts[world.contains(pts) & (world.clearance(pts) > 1.0)]
        if len(pts) < 2:
            raise InvalidWorldError(f"world {world.name!r}: no room for a game")
        evader = pts[0]
        far = pts[np.hypot(*(pts - evader).T) >= 2 * params.turn_radius]
        pursuer = far[0] if len(far) else pts[np.argmax(np.hypot(*(pts - evader).T))]
        heading = float(rng.uniform(0, 2 * np.pi))
        obs_rng = np.random.default_rng([seed, k, 1])
        if dynamic:
            centers, radii = place_obstacles(
                world, obs_rng, spec=ObstacleSpec(), keep_clear=np.vstack([evader, pursuer]),
                keep_clear_radius=1.3,
            )  # fmt: skip
        else:
            centers, radii = np.zeros((0, 2)), np.zeros(0)
        return cls(
            world, evader, pursuer, heading, centers, radii,
            params=params, sensor=sensor, seed=obs_rng, record=record,
        )  # fmt: skip

    def evader_wish(self) -> NDArray[np.float64]:
        """The game strategy's direction for the evader now (unit vector)."""
        return evader_direction(self.sim.position, self.car.position, self.car.heading, self.params)

    def step(self, evader_velocity: Any, pursuer_control: float | None = None) -> bool:
        """Advance one time step with the evader's velocity (norm clipped to its speed)
        and the car steering by Isaacs' strategy (or holding ``pursuer_control``);
        returns whether the evader was captured in it."""
        v = np.asarray(evader_velocity, dtype=np.float64)
        speed = self.params.evader_speed
        norm = math.hypot(v[0], v[1])
        if norm > speed:
            v = v * (speed / norm)
        before = self.sim.position.copy()
        res = self.sim.step(v)
        self.contacts += res.contact
        tau, near = pursuer_step(
            self.car,
            before,
            self.sim.position - before,
            np.asarray(self.world.segments),
            PURSUER_RADIUS,
            pursuer_control,
        )
        self.closest = min(self.closest, near)
        if self.record:
            self.car_path.append(self.car.position.copy())
        if math.isfinite(tau):
            self.captured = True
            self.capture_time = self.t + tau
        self.t += 1
        return self.captured
