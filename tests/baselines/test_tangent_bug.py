"""TangentBug on the range ring: the one local method that must get out of concavities
with ranges alone."""

from __future__ import annotations

import pytest

from tests.baselines._support import TRAP_GOAL, empty, route_length, run
from tests.common import U_TRAP, WALL


def test_tangent_bug_reaches_the_goal_behind_the_wall_with_ranges_only():
    sim = empty(WALL.start, WALL.goal, WALL)
    res = run("tangent-bug", sim, "sensor", max_steps=150)
    assert res.outcome == "success"
    assert sim.blocked <= 1  # with the tuned follow distance (1.0) it grazes the wall once
    # The wall's far side is out of sight until the agent is at it: a detour, not a
    # wander (48 steps against the 23.6 of the route).
    assert res.path_length <= 2.5 * route_length(WALL, WALL.start, WALL.goal)


def test_tangent_bug_escapes_the_u_trap_with_ranges_only():
    # The straight line ends against the U's bottom; boundary following takes it out
    # of the mouth and round an arm.
    sim = empty(U_TRAP.start, TRAP_GOAL, U_TRAP)
    res = run("tangent-bug", sim, "sensor", max_steps=200)
    assert res.outcome == "success"
    assert sim.blocked == 0
    assert res.path_length <= 2 * route_length(U_TRAP, U_TRAP.start, TRAP_GOAL)


def test_tangent_bug_leaves_the_trap_for_good():
    # Once out of the U it does not fall back into it: the last third of its path stays
    # outside the U's interior (12 < x < 28, 7 < y < 25).
    sim = empty(U_TRAP.start, TRAP_GOAL, U_TRAP)
    sim.record = True
    sim.path = [sim.position.copy()]
    run("tangent-bug", sim, "sensor", max_steps=200)
    tail = sim.path[2 * len(sim.path) // 3 :]
    inside = [12 < x < 28 and 7 < y < 25 for x, y in tail]
    assert not any(inside)


@pytest.mark.parametrize("level", ["sensor", "map"])
def test_tangent_bug_passes_the_wall_quicker_with_the_map(level):
    sim = empty(WALL.start, WALL.goal, WALL)
    res = run("tangent-bug", sim, level, max_steps=150)
    assert res.outcome == "success"
    if level == "map":
        assert res.path_length <= 1.1 * route_length(WALL, WALL.start, WALL.goal)
