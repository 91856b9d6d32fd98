"""Straight (no avoidance) and CompassGuard (copi's guard with no capabilities)."""

from __future__ import annotations

import math

import pytest

from copi.baselines import CompassGuard
from copi.errors import InvalidArgumentError
from tests.baselines._support import empty, head_on, run
from tests.common import WALL


@pytest.mark.parametrize("level", ["sensor", "map", "oracle"])
def test_straight_takes_whole_steps_along_the_line(level):
    sim = empty((3, 3), (17, 15))
    res = run("straight", sim, level, max_steps=40)
    assert res.outcome == "success"
    # Whole steps until the centre is within the tolerance of the goal.
    assert res.steps == math.ceil(math.hypot(14, 12) - 0.5)
    assert res.path_length == pytest.approx(res.steps, abs=1e-9)
    assert res.smoothness == pytest.approx(0.0, abs=1e-6)


def test_straight_presses_against_a_wall_across_its_way_until_timeout():
    sim = empty(WALL.start, WALL.goal, WALL)
    res = run("straight", sim, "sensor", max_steps=300)
    assert res.outcome == "timeout"
    assert sim.blocked >= 290  # every step after the ninth is into the wall
    assert sim.position == pytest.approx([15, 14 - 0.3], abs=1e-6)


def test_straight_gets_round_the_wall_on_the_route_at_map():
    sim = empty(WALL.start, WALL.goal, WALL)
    assert run("straight", sim, "map", max_steps=60).outcome == "success"


def test_compass_guard_never_steps_into_the_wall_with_ranges_only():
    # At 'sensor' every hit is a hazard: the guard stops short of the wall rather than
    # walk into it (and, with no way round in view, stays there: a local method's lot).
    sim = empty(WALL.start, WALL.goal, WALL)
    res = run("compass-guard", sim, "sensor", max_steps=300)
    assert sim.blocked == 0
    assert res.outcome != "collision"
    assert sim.position[1] > 11  # it went up to the wall, not nowhere


# Found by this test: a quantised direction pressed into the wall's corner for 290 of 300
# steps (the guard never counted walls); a guarded step now keeps its path off every hit.
def test_compass_guard_gets_round_the_wall_on_the_route_at_map():
    sim = empty(WALL.start, WALL.goal, WALL)
    res = run("compass-guard", sim, "map", max_steps=100)
    assert res.outcome == "success"


# Found by this test: the guard kernel cut each step to its projection on the aim, ~0 for
# a direction perpendicular to it, and the agent stood at (8, 10) for good.
@pytest.mark.parametrize("level", ["sensor", "map"])
def test_compass_guard_passes_a_standing_disc_of_radius_075(level):
    res = run("compass-guard", head_on(10.0, 10.0, radius=0.75, speed=0.0), level, max_steps=60)
    assert res.outcome == "success"


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"guard": 0.0}, "guard must be a finite number > 0; got 0.0"),
        ({"guard": math.nan}, "guard must be a finite number > 0; got nan"),
        ({"directions": 0}, "directions must be a positive int; got 0"),
        ({"directions": 2.5}, "directions must be a positive int; got 2.5"),
    ],
)
def test_compass_guard_refuses_bad_parameters(kwargs, message):
    with pytest.raises(InvalidArgumentError, match=message.replace(".", r"\.")):
        CompassGuard(**kwargs)
