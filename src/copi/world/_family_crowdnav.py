"""CrowdNav's scenarios as world families: ``circle-crossing`` and ``square-crossing``.

CrowdNav (Chen, Liu, Kreiss & Alahi, ICRA 2019; github.com/vita-epfl/CrowdNav,
``crowd_nav/configs/env.config`` and ``crowd_sim/envs/crowd_sim.py``) is the field's
standard crowd-navigation scenario: 5 humans driven by ORCA toward goals of their own,
the robot invisible to them, a time step of 0.25 s and a limit of 25 s. Its settings, in
metres and seconds (:data:`CROWDNAV`), become copi's units here: one agent step is what
the robot may move in one time step, ``v_pref x time_step`` = 0.25 m, so every length is
multiplied by :data:`STEPS_PER_METRE` (the humans' radius of 0.3 m is 1.2 agent steps,
the circle's radius of 4 m is 16) and one time step is 0.25 s.

What is CrowdNav's (its code, read for this): the robot starts at (0, -4) with its goal
at (0, 4); in circle crossing each human starts on the circle of 4 m at a uniform angle,
moved by uniform noise of +-0.5 m on each axis, with its goal the start mirrored through
the centre, a start drawn again while it is nearer than 0.8 m (two radii and the
discomfort distance) to an earlier agent's start or goal; in square crossing each human
starts on one side of the y axis and has its goal on the other, uniform in a 10 m
square, drawn again while nearer than 0.8 m to another's start (or goal). Humans' ORCA:
time horizon 5 s, the 10 nearest neighbours within 10 m, a radius 0.01 m larger than
theirs, speed 1 m/s; the robot is invisible to them; a human at its goal stays there.
Success is the robot within its radius (0.3 m) of its goal; the episode ends at 24 s (96
decisions).

What differs, said plainly: CrowdNav draws its 500 test episodes from numpy's legacy
generator seeded 1000 + i; copi draws episode k from ``default_rng([seed, k])`` (the
same distribution, other draws); humans are navground's ORCA, not Python-RVO2's, whose
speed is capped at that of its preferred velocity (RVO2's at 1 m/s), and navground's
humans stop at their goals (CrowdNav's keep avoiding the others there); copi's world has
walls 10 m out (CrowdNav's has none; no human comes near them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from copi.world._world import ObstacleSpec, World

__all__ = ["CROWDNAV", "STEPS_PER_METRE", "CrowdNavSettings", "circle_crossing",
           "square_crossing"]  # fmt: skip


@dataclass(frozen=True)
class CrowdNavSettings:
    """CrowdNav's ``env.config`` (metres, seconds), and what its humans' ORCA uses."""

    time_step: float = 0.25
    time_limit: float = 25.0
    human_num: int = 5
    radius: float = 0.3
    """Humans' and the robot's radius."""
    v_pref: float = 1.0
    circle_radius: float = 4.0
    square_width: float = 10.0
    discomfort_dist: float = 0.2
    time_horizon: float = 5.0
    """ORCA's (``crowd_sim/envs/policy/orca.py``), seconds."""
    max_neighbors: int = 10
    neighbor_dist: float = 10.0
    """How far ORCA sees the others, metres (RVO2's neighbour distance)."""
    radius_extra: float = 0.01
    """ORCA sees every agent 0.01 m larger than it is (so two, 0.02 m farther apart:
    navground's safety margin, added once to the sum of radii, is twice this)."""
    half_width: float = 10.0
    """copi's walls, this far from the centre (CrowdNav has none)."""


CROWDNAV = CrowdNavSettings()
STEPS_PER_METRE = 1.0 / (CROWDNAV.v_pref * CROWDNAV.time_step)
"""Agent steps in a metre: one step is what the robot moves in one time step at 1 m/s."""


def _spec(starts: list[np.ndarray], goals: list[np.ndarray]) -> ObstacleSpec:
    c, s = CROWDNAV, STEPS_PER_METRE
    return ObstacleSpec(
        count=(len(starts), len(starts)), radius=(c.radius * s, c.radius * s),
        speed=c.v_pref * c.time_step * s,
        behaviour="orca", sees_agent=False, time_horizon=c.time_horizon / c.time_step,
        safety_margin=2 * c.radius_extra * s, neighbours=c.max_neighbors,
        sight=c.neighbor_dist * s, new_goals=False,
        positions=tuple(tuple(p * s) for p in starts), goals=tuple(tuple(g * s) for g in goals),
    )  # fmt: skip


def _world(starts: list[np.ndarray], goals: list[np.ndarray], name: str) -> World:
    c, s = CROWDNAV, STEPS_PER_METRE
    h = c.half_width * s
    return World(np.array([[-h, -h], [h, -h], [h, h], [-h, h]]), name=name,
                 start=np.array([0.0, -c.circle_radius * s]),
                 goal=np.array([0.0, c.circle_radius * s]),
                 obstacles=_spec(starts, goals))  # fmt: skip


def _robot() -> tuple[np.ndarray, np.ndarray]:
    return np.array([0.0, -CROWDNAV.circle_radius]), np.array([0.0, CROWDNAV.circle_radius])


def circle_crossing(rng: np.random.Generator, *, name: str | None = None) -> World:
    """CrowdNav's circle crossing (``generate_circle_crossing_human``), in copi's units."""
    c = CROWDNAV
    apart = 2 * c.radius + c.discomfort_dist
    start, goal = _robot()
    taken = [start, goal]  # every earlier agent's start and goal, the robot's first
    starts: list[np.ndarray] = []
    for _ in range(c.human_num):
        while True:
            angle = rng.random() * 2 * math.pi
            noise = (rng.random(2) - 0.5) * c.v_pref
            p = c.circle_radius * np.array([math.cos(angle), math.sin(angle)]) + noise
            if all(np.hypot(*(p - q)) >= apart for q in taken):
                break
        starts.append(p)
        taken += [p, -p]
    return _world(starts, [-p for p in starts], name or f"circle-crossing-{c.human_num}h")


def square_crossing(rng: np.random.Generator, *, name: str | None = None) -> World:
    """CrowdNav's square crossing (``generate_square_crossing_human``), in copi's units."""
    c = CROWDNAV
    apart = 2 * c.radius + c.discomfort_dist
    half = c.square_width / 2
    start, goal = _robot()
    starts, goals = [start], [goal]
    mine_s: list[np.ndarray] = []
    mine_g: list[np.ndarray] = []
    for _ in range(c.human_num):
        sign = -1.0 if rng.random() > 0.5 else 1.0
        while True:
            p = np.array([rng.random() * half * sign, (rng.random() - 0.5) * c.square_width])
            if all(np.hypot(*(p - q)) >= apart for q in starts):
                break
        while True:
            g = np.array([rng.random() * half * -sign, (rng.random() - 0.5) * c.square_width])
            if all(np.hypot(*(g - q)) >= apart for q in goals):
                break
        starts.append(p)
        goals.append(g)
        mine_s.append(p)
        mine_g.append(g)
    return _world(mine_s, mine_g, name or f"square-crossing-{c.human_num}h")
