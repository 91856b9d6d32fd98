from __future__ import annotations

import numpy as np
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from copi.geometry import clearance, move_discs
from copi.world import random_world
from tests.common import PILLARS, U_TRAP


@settings(max_examples=80, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    radius=st.floats(0.05, 1.0),
    vx=st.floats(-3, 3),
    vy=st.floats(-3, 3),
)
def test_a_moving_disc_never_enters_a_wall(seed: int, radius: float, vx: float, vy: float) -> None:
    rng = np.random.default_rng(seed)
    world = random_world(rng) if seed % 2 else PILLARS
    xmin, ymin, xmax, ymax = world.bounds
    pts = rng.uniform([xmin, ymin], [xmax, ymax], size=(200, 2))
    ok = world.contains(pts) & (world.clearance(pts) >= radius)
    if not ok.any():
        return
    start = pts[ok][0]
    end, blocked = move_discs(start, [vx, vy], world.segments, radius)
    # Independent check with Shapely: the swept path keeps the disc off every wall.
    walls = shapely.MultiLineString([s.reshape(2, 2) for s in world.segments])
    path = shapely.LineString([start, end]) if np.any(end != start) else shapely.Point(start)
    assert walls.distance(path) >= radius - 1e-7
    travelled = np.hypot(*(end - start))
    if blocked:
        # Stopped at the contact: the disc touches a wall there.
        assert abs(walls.distance(shapely.Point(end)) - radius) < 1e-6
        assert travelled < np.hypot(vx, vy)
    else:
        np.testing.assert_allclose(end, start + [vx, vy], atol=1e-12)


def test_a_disc_against_a_wall_slides_along_it_and_leaves_it() -> None:
    wall = [[0.0, 0.0, 10.0, 0.0]]
    start = np.array([5.0, 0.5])
    along, blocked = move_discs(start, [1.0, 0.0], wall, 0.5)
    assert not blocked and along.tolist() == [6.0, 0.5]
    away, blocked = move_discs(start, [0.0, 1.0], wall, 0.5)
    assert not blocked and away.tolist() == [5.0, 1.5]
    into, blocked = move_discs(start, [0.0, -1.0], wall, 0.5)
    assert blocked and np.allclose(into, start)


def test_batched_moves_and_clearance() -> None:
    pos = np.array([[20.0, 15.0], [20.0, 15.0], [5.0, 28.0]])
    vel = np.array([[0.0, -10.0], [10.0, 0.0], [0.0, 0.5]])
    new, blocked = move_discs(pos, vel, U_TRAP.segments, 0.3)
    np.testing.assert_allclose(new[0], [20.0, 7.3], atol=1e-8)
    np.testing.assert_allclose(new[1], [27.7, 15.0], atol=1e-8)
    np.testing.assert_allclose(new[2], [5.0, 28.5])
    assert blocked.tolist() == [True, True, False]
    np.testing.assert_allclose(clearance(new, U_TRAP.segments), [0.3, 0.3, 1.5], atol=1e-8)
