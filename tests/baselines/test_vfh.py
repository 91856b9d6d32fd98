"""VFH+ on the range ring."""

from __future__ import annotations

import math

import numpy as np
import pytest

from copi.baselines import VFH
from copi.runs import make_task
from tests.baselines._support import empty, run
from tests.common import WALL


@pytest.mark.parametrize("goal", [(10, 19), (1, 10), (18.5, 18.5)])
@pytest.mark.parametrize("level", ["sensor", "map"])
def test_vfh_reaches_a_goal_close_to_a_wall(level, goal):
    # Regression: the wall behind the goal filled the histogram's target sector, so the
    # agent circled in front of a goal in plain sight (timeout after 100 steps, 71 long).
    sim = empty((10, 10) if goal != (18.5, 18.5) else (2, 2), goal)
    d = sim.distance
    res = run("vfh", sim, level, max_steps=100)
    assert res.outcome == "success"
    assert res.steps <= math.ceil(d - 0.5) + 1


@pytest.mark.parametrize("level", ["sensor", "map"])
def test_vfh_goes_round_the_wall_without_touching_it(level):
    sim = empty(WALL.start, WALL.goal, WALL)
    res = run("vfh", sim, level, max_steps=80)
    assert res.outcome == "success"
    assert sim.blocked == 0


def test_vfh_histogram_blocks_the_sectors_a_hit_covers():
    vfh = VFH()
    vfh.reset(make_task(empty((10, 10), (15, 10)), "sensor"))
    ranges = np.full(32, 10.0)
    ranges[8] = 2.0  # one hit straight up (+y), 2 away
    h = vfh.histogram(ranges)
    half = math.asin((0.3 + 0.5) / 2.0)  # enlarged by radius and safety
    phi = 2 * math.pi * np.arange(72) / 72
    near = np.abs(phi - math.pi / 2) <= half
    assert h[near] == pytest.approx((1 - 2.0 / 10) ** 2)
    assert (h[~near] == 0).all()
