"""FuturesPlanner.lost: each move's share of futures lost at the last plan."""

from __future__ import annotations

import numpy as np

from copi.planning.futures import FuturesPlanner
from copi.world import World

HALL = World([[0, 0], [24, 0], [24, 10], [0, 10]], start=[2, 5], goal=[22, 5])


def test_each_moves_lost_share_is_kept_beside_its_cost() -> None:
    """A disc standing a step and a half ahead in every future: the full step onto it is lost in
    all of them, a full step back in none; a move a wall stops has no share (NaN) and
    no cost (inf); and every cost holds ``loss`` times its share plus the step."""
    pl = FuturesPlanner(horizon=6)
    pl.reset(HALL, np.array([22.0, 5.0]), 0.3, 0.5)
    futures = np.ascontiguousarray(np.broadcast_to([[[[4.5, 5.0]]]], (8, 7, 1, 2)))
    pl.plan(np.array([3.0, 5.0]), futures, np.array([0.6]))
    east = int(np.argmin(np.hypot(*(pl.moves - [1.0, 0.0]).T)))
    west = int(np.argmin(np.hypot(*(pl.moves - [-1.0, 0.0]).T)))
    assert pl.lost[east] == 1.0 and pl.lost[west] == 0.0
    fin = np.isfinite(pl.costs)
    assert np.array_equal(fin, ~np.isnan(pl.lost))
    assert np.all(pl.costs[fin] >= pl.loss * pl.lost[fin] + 1.0 - 1e-9)
    pl.plan(np.array([0.8, 5.0]), futures + [[[[10.0, 0.0]]]], np.array([0.6]))
    assert np.isnan(pl.lost[west]) and pl.costs[west] == np.inf
