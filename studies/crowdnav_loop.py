"""CrowdNav's own test of ORCA as the robot, its loop rewritten here from its code, to check
the number published for it independently of copi's simulator (docs/crowdnav.md).

    python studies/crowdnav_loop.py [--episodes 500] [--human-sight 10]

What is CrowdNav's (vita-epfl/CrowdNav, master 20d6780: ``crowd_sim/envs/crowd_sim.py``,
``crowd_sim/envs/policy/orca.py``, ``crowd_nav/test.py``, ``crowd_nav/configs/env.config``),
in metres and seconds: test case i is drawn after ``np.random.seed(1000 + i)`` (numpy's
legacy generator); the robot starts at (0, -4) with its goal at (0, 4); 5 humans start on
the circle of 4 m at a uniform angle moved by uniform noise of +-0.5 m on each axis, a
start drawn again while within 0.8 m of an earlier agent's start or goal, each with its
goal the start mirrored through the centre. Every agent (humans and the robot) runs ORCA
with a time horizon of 5 s, the 10 nearest within 10 m, its radius and the others' 0.01 m
larger than they are (0.3 m), speed 1 m/s, its preferred velocity the unit vector to its
goal, or the vector itself within 1 m; every other agent seen at its velocity of the last
step; the robot is invisible to the humans. A step of 0.25 s: the robot decides, the humans
decide; a collision is the robot's path relative to a human (the human at its last step's
velocity, the robot at its new one) passing within two radii; success is the robot's new
position within its radius of its goal; the episode ends at 24 s (timeout checked first).

What differs: the ORCA solver is navground's copy of RVO2's agent (the one copi's humans
and its ``crowdnav-orca`` use), not Python-RVO2; a solver built for each decision; and
navground caps an agent's speed at that of its preferred velocity where RVO2 caps it at 1
m/s, so that within 1 m of its goal an agent here cannot move aside faster than the
preferred velocity's length (a difference this loop shares with copi's scenario, so it
cannot reveal it).
``--human-sight`` changes how far the humans see each other (10 m is CrowdNav's).
"""

from __future__ import annotations

import argparse
import json
import math
from typing import Any

import numpy as np

RADIUS = 0.3
STEP = 0.25
CIRCLE = 4.0
APART = 2 * RADIUS + 0.2  # two radii and the discomfort distance
HUMANS = 5
LIMIT = 25.0


def _orca(pos: np.ndarray, vel: np.ndarray, goal: np.ndarray,
          others: list[tuple[np.ndarray, np.ndarray]], sight: float) -> np.ndarray:  # fmt: skip
    """One agent's ORCA velocity (CrowdNav's ``ORCA.predict``)."""
    from navground import core

    b: Any = core.behaviors.ORCABehavior()
    b.kinematics = core.kinematics.OmnidirectionalKinematics(max_speed=1.0)
    b.radius = RADIUS + 0.01
    b.safety_margin = 0.0
    b.time_horizon = 5.0
    b.horizon = sight / 2  # navground's neighbour distance is twice its horizon
    b.set("max_neighbors", 10)
    b.position = pos
    b.velocity = vel
    b.environment_state.neighbors = [
        core.Neighbor(position=p, radius=RADIUS + 0.01, velocity=v, id=i)
        for i, (p, v) in enumerate(others)
        if math.hypot(*(p - pos)) <= sight
    ]
    d = goal - pos
    n = math.hypot(*d)
    pref = d / n if n > 1.0 else d
    return np.array(b.desired_velocity_towards_velocity(pref, STEP), dtype=np.float64)


def _passes_within(rel: np.ndarray, move: np.ndarray, gap: float) -> bool:
    """Whether the segment rel .. rel + move passes within ``gap`` of the origin."""
    ll = float(move @ move)
    u = 0.0 if ll == 0.0 else min(1.0, max(0.0, -float(rel @ move) / ll))
    return math.hypot(*(rel + u * move)) < gap


def test_case(i: int, human_sight: float = 10.0) -> tuple[str, float]:
    """CrowdNav's test case i with ORCA as the robot: (outcome, seconds)."""
    np.random.seed(1000 + i)  # CrowdNav's test seeds (its legacy generator, on purpose)
    robot, goal, rv = np.array([0.0, -CIRCLE]), np.array([0.0, CIRCLE]), np.zeros(2)
    hp: list[np.ndarray] = []
    for _ in range(HUMANS):
        while True:
            angle = np.random.random() * np.pi * 2
            nx = (np.random.random() - 0.5) * 1.0
            ny = (np.random.random() - 0.5) * 1.0
            p = np.array([CIRCLE * np.cos(angle) + nx, CIRCLE * np.sin(angle) + ny])
            taken = [robot, goal, *hp, *(-q for q in hp)]
            if all(np.linalg.norm(p - q) >= APART for q in taken):
                break
        hp.append(p)
    hg = [-p for p in hp]
    hv = [np.zeros(2) for _ in hp]
    t = 0.0
    while True:
        a = _orca(robot, rv, goal, list(zip(hp, hv, strict=True)), 10.0)
        ha = [_orca(hp[k], hv[k], hg[k], [(hp[j], hv[j]) for j in range(HUMANS) if j != k],
                    human_sight) for k in range(HUMANS)]  # fmt: skip
        hit = any(_passes_within(hp[k] - robot, (hv[k] - a) * STEP, 2 * RADIUS)
                  for k in range(HUMANS))  # fmt: skip
        if t >= LIMIT - 1:
            return "timeout", t
        if hit:
            return "collision", t
        if np.linalg.norm(robot + a * STEP - goal) < RADIUS:
            return "success", t + STEP
        robot, rv = robot + a * STEP, a
        hp = [hp[k] + ha[k] * STEP for k in range(HUMANS)]
        hv = ha
        t += STEP


def run(episodes: int = 500, human_sight: float = 10.0) -> dict[str, float]:
    """Rates over CrowdNav's test cases 0 .. episodes - 1, and the mean time of successes."""
    out = [test_case(i, human_sight) for i in range(episodes)]
    won = [t for o, t in out if o == "success"]
    return {"episodes": episodes,
            "success": len(won) / episodes,
            "collision": sum(o == "collision" for o, _ in out) / episodes,
            "timeout": sum(o == "timeout" for o, _ in out) / episodes,
            "time": float(np.mean(won)) if won else math.nan}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--episodes", type=int, default=500)
    ap.add_argument("--human-sight", type=float, default=10.0)
    a = ap.parse_args()
    print(json.dumps(run(a.episodes, a.human_sight), indent=2))


if __name__ == "__main__":
    main()
