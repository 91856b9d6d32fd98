"""The planner's grids for a world known only by the walls the agent sees (level sensor):
the clearance grid against Shapely, the open field against straight lines, and the grids
of the map path unchanged."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import LineString, Point

from copi.planning._field import GoalField, clearance_grid
from copi.planning.futures import OFFSETS, RES, FuturesPlanner, _moves_clear
from copi.world import World

coord = st.integers(-600, 600).map(lambda v: v / 100)  # no subnormal lengths


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(coord, coord, coord, coord), min_size=1, max_size=6),
       st.floats(0.5, 4.0))  # fmt: skip
def test_clearance_grid_is_shapely_distance_capped(segs: list, cap: float) -> None:
    s = np.array(segs, dtype=np.float64)
    h, n = 0.5, 25
    got = clearance_grid(s, -6.0, -6.0, h, n, n, cap)
    lines = [LineString([(a, b), (c, d)]) if (a, b) != (c, d) else Point(a, b)
             for a, b, c, d in segs]  # fmt: skip
    for i in range(0, n, 3):
        for j in range(0, n, 3):
            p = Point(-6.0 + j * h, -6.0 + i * h)
            want = min(cap, min(g.distance(p) for g in lines))
            assert math.isclose(got[i, j], want, abs_tol=1e-9)


def test_open_field_leads_straight_on_where_nothing_is_seen() -> None:
    """No wall: the cost to go from any cell is the straight distance to a goal outside
    the box, within the 8-connected grid's 8 %; a wall across the way makes it longer."""
    h, n = 0.5, 41
    goal = np.array([30.0, 4.0])
    empty = np.full((n, n), 100.0)
    f = GoalField.open(empty, -10.0, -10.0, h, goal, 0.3)
    for x, y in ((0.0, 0.0), (-9.0, 7.5), (9.5, -9.5)):
        straight = math.dist((x, y), goal)
        assert straight - 1e-9 <= f.at(x, y) <= 1.08 * straight
    wall = np.array([[5.0, -8.0, 5.0, 8.0]])  # across the way, open at both ends
    blocked = GoalField.open(clearance_grid(wall, -10.0, -10.0, h, n, n, 6.0), -10.0, -10.0,
                             h, goal, 0.3)  # fmt: skip
    assert blocked.at(0.0, 0.0) > f.at(0.0, 0.0) + 4.0
    assert math.isfinite(blocked.at(0.0, 0.0))
    inside = GoalField.open(empty, -10.0, -10.0, h, np.array([2.0, 1.0]), 0.3)
    assert inside.at(2.0, 1.0) < 0.5 and 5.0 <= inside.at(-3.0, 1.0) <= 5.4


def test_map_grids_are_the_moves_checked_quarter_by_quarter() -> None:
    """The compiled check of each move equals the check written out with numpy, on the
    grids of a room with a pillar."""
    room = World([[0, 0], [12, 0], [12, 9], [0, 9]], holes=[[[5, 3], [7, 3], [7, 6], [5, 6]]],
                 start=[1, 1], goal=[11, 8])  # fmt: skip
    pl = FuturesPlanner(horizon=8)
    pl.reset(room, np.array([11.0, 8.0]), 0.3, 0.5)
    free = pl.clear >= pl.r
    ny, nx = pl.ok.shape
    ii, jj = np.mgrid[0:ny, 0:nx]
    for o, (di, dj) in enumerate(OFFSETS):
        good = free[4 * ii, 4 * jj].copy()
        for frac in (1, 2, 3, 4):
            a, b = 4 * ii + di * frac, 4 * jj + dj * frac
            inside = (a >= 0) & (b >= 0) & (a < 4 * ny) & (b < 4 * nx)
            good &= inside & free[np.clip(a, 0, 4 * ny - 1), np.clip(b, 0, 4 * nx - 1)]
        assert np.array_equal(pl.mid_ok[o], good)
    assert np.array_equal(_moves_clear(free, OFFSETS, ny, nx), pl.mid_ok)
    assert 0 < pl.ok.mean() < 1


def test_open_grids_hold_the_window_and_the_walls_seen() -> None:
    pl = FuturesPlanner(horizon=12)
    wall = np.array([[3.0, -4.0, 3.0, 4.0]])
    pl.reset_open(wall, np.array([0.0, 0.0]), np.array([20.0, 0.0]), 0.3, 0.5)
    n = 2 * pl.half + 1
    assert pl.ok.shape[0] >= n and pl.ok.shape[1] >= n
    x = pl.field.x0 + RES * np.arange(pl.ok.shape[1])
    y = pl.field.y0 + RES * np.arange(pl.ok.shape[0])
    near = (np.abs(x[None, :] - 3.0) < 0.3) & (np.abs(y[:, None]) < 3.9)
    assert not pl.ok[near].any() and pl.ok[~near].mean() > 0.9
    m, _ = pl.plan(np.array([0.0, 0.0]), np.zeros((4, 13, 0, 2)), np.zeros(0))
    assert m >= 0 and abs(pl.moves[m][1]) > 0.3  # round the wall, not into it
