from __future__ import annotations

import numpy as np
import pytest
import shapely

from copi.errors import InvalidArgumentError
from copi.learning import (
    ActionPriors,
    AStarLearner,
    ValueIterationLearner,
    compass,
    local_world,
)
from copi.world import RangeSensor, World

SENSOR = RangeSensor()


def _scan(world: World, p) -> np.ndarray:
    return SENSOR.scan(world, p)


# A north-south corridor 3 wide, the agent in the middle: open north and south only.
CORRIDOR_NS = World([[-1.5, -40], [1.5, -40], [1.5, 40], [-1.5, 40]], name="ns")
# A dead end: walls east, west and north, open south.
DEAD_END = World([[-1.5, -40], [1.5, -40], [1.5, 2], [-1.5, 2]], name="dead-end")
# An open room: everything passable.
ROOM = World([[-30, -30], [30, -30], [30, 30], [-30, 30]], name="room")


@pytest.mark.parametrize("learner", [AStarLearner(), ValueIterationLearner()], ids=lambda x: x.name)
@pytest.mark.parametrize(
    ("world", "expected"),
    [
        (CORRIDOR_NS, [False, True, False, True]),
        (DEAD_END, [False, False, False, True]),
        (ROOM, [True] * 4),
    ],
    ids=["corridor", "dead-end", "room"],
)
def test_passable_directions(learner, world, expected) -> None:
    ranges = _scan(world, [0.0, 0.0])
    ps = learner.learn(ranges[None], 10.0, 4)
    assert ps.passable[0].tolist() == expected
    for d in np.flatnonzero(ps.passable[0]):
        assert ps.actions[0, d] @ ps.directions[d] > 0.7  # heads the right way
        assert np.linalg.norm(ps.actions[0, d]) == pytest.approx(1.0)


@pytest.mark.parametrize("learner", [AStarLearner(), ValueIterationLearner()], ids=lambda x: x.name)
def test_policy_paths_stay_in_the_local_world(learner) -> None:
    rng = np.random.default_rng(0)
    box = World([[0, 0], [14, 0], [14, 9], [6, 9], [6, 20], [0, 20]], name="L")
    ranges = np.array([_scan(box, p) for p in ([3, 4], [3, 12], [10, 4])])
    ranges += rng.uniform(-0.2, 0.0, ranges.shape)
    ps = learner.learn(ranges, 10.0, 8)
    for t in range(len(ranges)):
        local = local_world(ranges[t], 10.0)
        walls = shapely.MultiLineString([s.reshape(2, 2) for s in local.segments])
        for d in range(8):
            path = ps.path(t, d)
            if not ps.passable[t, d]:
                assert len(path) == 0 and ps.lengths[t, d] == np.inf
                continue
            line = shapely.LineString(path)
            assert local.polygon.buffer(1e-9).covers(line)
            assert walls.distance(line) >= 0.2  # keeps clear of the walls (radius 0.3, grid 0.5)
            assert ps.lengths[t, d] == pytest.approx(np.hypot(*np.diff(path, axis=0).T).sum())


def test_compass_and_bad_counts() -> None:
    names, vecs = compass(8)
    assert names[2] == "N" and np.allclose(vecs[2], [0, 1])
    with pytest.raises(InvalidArgumentError, match="directions must be 4, 8 or 16"):
        compass(6)


def test_action_priors_count_unblocked_moves() -> None:
    template = np.array([0, 0, 0, 1, 1])
    moves = np.array([[1.0, 0.0], [0.99, 0.1], [0.0, 0.5], [0.0, -1.0], [-1.0, 0.0]])
    pri = ActionPriors.from_moves(template, moves, 2, 4)
    assert pri.counts.tolist() == [[2, 0, 0, 0], [0, 0, 1, 1]]  # the 0.5 step was blocked
    np.testing.assert_allclose(pri.probabilities.sum(1), 1.0)
    assert pri.probabilities[0, 0] == pytest.approx(3 / 6)
