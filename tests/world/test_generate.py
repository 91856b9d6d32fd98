from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from copi.errors import InvalidArgumentError, InvalidWorldError
from copi.world import WorldParams, place_obstacles, random_world, sample_start_goal
from tests.common import CORRIDOR, U_TRAP


@settings(max_examples=150, deadline=None)
@given(st.integers(0, 2**63 - 1))
def test_random_worlds_follow_the_paper(seed: int) -> None:
    w = random_world(seed)
    assert 4 <= len(w.boundary) <= 12
    assert w.holes == ()
    assert w.polygon.is_valid and w.polygon.exterior.is_simple
    assert random_world(seed) == w


def test_random_worlds_vary_in_size_shape_and_convexity() -> None:
    worlds = [random_world(np.random.default_rng([0, k])) for k in range(300)]
    sides = np.array([len(w.boundary) for w in worlds])
    areas = np.array([w.area for w in worlds])
    convex = np.array([w.polygon.convex_hull.area - w.area < 1e-9 for w in worlds])
    assert set(sides) == set(range(4, 13))
    assert np.percentile(areas, 90) / np.percentile(areas, 10) > 4
    assert 0.05 < convex.mean() < 0.95


def test_world_params_are_checked() -> None:
    with pytest.raises(InvalidArgumentError, match=r"sides must satisfy 3 <= low <= high"):
        WorldParams(sides=(2, 5))
    assert len(random_world(3, params=WorldParams(sides=(5, 5))).boundary) == 5


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.1, 0.8))
def test_start_and_goal_are_free_connected_and_apart(seed: int, radius: float) -> None:
    w = random_world(seed)
    s, g = sample_start_goal(w, seed, radius=radius, min_distance=10.0)
    assert np.hypot(*(s - g)) >= 10.0
    assert w.contains([s, g]).all()
    assert (w.clearance([s, g]) >= radius).all()
    free = w.polygon.buffer(-radius * 0.999)
    parts = list(getattr(free, "geoms", [free]))
    import shapely

    comp = [shapely.contains_xy(p, *s) for p in parts]
    assert any(c and shapely.contains_xy(p, *g) for c, p in zip(comp, parts, strict=True))


def test_fixed_start_and_goal_are_kept() -> None:
    s, g = sample_start_goal(U_TRAP, 0)
    assert s.tolist() == [20, 15] and g.tolist() == [20, 28]
    half = U_TRAP.replace(goal=None)
    s, g = sample_start_goal(half, 0)
    assert s.tolist() == [20, 15] and np.hypot(*(s - g)) >= 10


def test_impossible_task_is_a_clear_error() -> None:
    with pytest.raises(InvalidWorldError, match="no free start and goal 100 apart"):
        sample_start_goal(CORRIDOR, 0, min_distance=100.0)
    with pytest.raises(InvalidWorldError, match="no free space for a disc of radius 2"):
        sample_start_goal(CORRIDOR, 0, radius=2.0)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_obstacles_start_clear_of_walls_and_agent(seed: int) -> None:
    w = random_world(seed)
    s, _ = sample_start_goal(w, seed)
    c, r = place_obstacles(w, seed, keep_clear=s, keep_clear_radius=1.3)
    assert 10 <= len(r) <= 15 and ((r >= 0.5) & (r <= 1.0)).all()
    assert (w.clearance(c) >= r).all() and w.contains(c).all()
    assert (np.hypot(*(c - s).T) > r + 1.3).all()


def test_a_fixed_start_gets_a_goal_it_can_reach() -> None:
    # two rooms joined by nothing: the goal must be drawn in the start's room
    from copi.world import World

    rooms = World(
        [[0, 0], [30, 0], [30, 10], [0, 10]],
        [[[14, 0.1], [16, 0.1], [16, 9.9], [14, 9.9]]],
        name="two-rooms",
    )
    rooms = rooms.replace(start=[2.0, 5.0])
    for seed in range(20):
        _, goal = sample_start_goal(rooms, seed, radius=0.3, min_distance=5.0)
        assert goal[0] < 14  # the left room: the gap of 0.1 at the walls is too narrow
