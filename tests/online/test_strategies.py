from __future__ import annotations

import math

import numpy as np
import pytest

from copi.errors import InvalidArgumentError
from copi.geometry import move_discs
from copi.online import Greedy, Route, make_strategy
from tests.common import U_TRAP


def _follow(strategy, world, start, goal, steps=200):
    p = np.array(start, float)
    strategy.reset(world, p, goal, 0.3)
    length = 0.0
    for _ in range(steps):
        d, reach = strategy.aim(p)
        if reach < 1e-9:
            break
        v = d / np.linalg.norm(d) * min(1.0, reach)
        q, _ = move_discs(p, v, world.segments, 0.3)
        length += np.linalg.norm(q - p)
        p = q
    return p, length


def test_route_reaches_the_goal_around_walls() -> None:
    start, goal = [20.0, 2.0], [20.0, 15.0]  # from below the U into it: around the arms
    p, length = _follow(Route(), U_TRAP, start, goal)
    assert np.linalg.norm(p - goal) < 1e-6
    assert length == pytest.approx(math.hypot(10.3, 3) + 20 + 2 + math.hypot(8, 10), rel=0.05)


def test_greedy_gets_stuck_where_route_does_not() -> None:
    start, goal = [20.0, 2.0], [20.0, 15.0]
    p, _ = _follow(Greedy(), U_TRAP, start, goal)
    assert np.linalg.norm(p - goal) > 5  # pressed against the bottom of the U


def test_route_replans_when_pushed_off() -> None:
    r = Route()
    r.reset(U_TRAP, [20.0, 2.0], [20.0, 15.0], 0.3)
    r.aim(np.array([20.0, 2.0]))
    d, _ = r.aim(np.array([35.0, 20.0]))  # far from the planned route, right of the U
    assert r.replans >= 1
    assert np.isfinite(d).all()


def test_make_strategy() -> None:
    assert make_strategy("greedy").name == "greedy"
    with pytest.raises(InvalidArgumentError, match="strategy must be 'route' or 'greedy'"):
        make_strategy("astar")
