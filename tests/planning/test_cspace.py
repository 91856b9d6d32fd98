from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from copi.errors import InvalidQueryError
from copi.planning import (
    VisibilityGraph,
    configuration_space,
    length_error_bound,
    shortest_path,
)
from copi.world import Simulator, World, random_world
from tests.common import CORRIDOR, PILLARS, U_TRAP


def _snapshot(seed: int, radius: float):
    world = random_world(seed) if seed % 4 else PILLARS
    sim = Simulator.from_world(world, seed, agent_radius=max(radius, 1e-3))
    return world, sim.position, sim.goal, sim.centers, sim.radii


def _feasible(world: World, path: np.ndarray, radius: float, centers, radii) -> None:
    walls = shapely.MultiLineString([s.reshape(2, 2) for s in world.segments])
    line = shapely.LineString(path) if len(path) > 1 else shapely.Point(path[0])
    assert world.polygon.buffer(1e-9).covers(line)
    assert walls.distance(line) >= radius - 1e-7
    for c, r in zip(centers, radii, strict=True):
        assert line.distance(shapely.Point(c)) >= radius + r - 1e-7


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), radius=st.sampled_from([0.0, 0.1, 0.3, 0.6]))
def test_paths_stay_out_of_grown_obstacles(seed: int, radius: float) -> None:
    world, s, g, c, r = _snapshot(seed, radius)
    try:
        plan = shortest_path(world, s, g, radius=radius, centers=c, radii=r)
    except InvalidQueryError:
        assume(False)  # the goal lies under a frozen obstacle in this snapshot
        return
    if not plan.found:
        return
    _feasible(world, plan.path, radius, c, r)
    assert plan.length >= np.hypot(*(s - g)) - 1e-9
    assert np.hypot(*np.diff(plan.path, axis=0).T).sum() == pytest.approx(plan.length)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), quad_segs=st.sampled_from([2, 4, 16]))
def test_length_is_bracketed_by_inner_and_outer_polygons(seed: int, quad_segs: int) -> None:
    radius = 0.3
    world, s, g, c, r = _snapshot(seed, radius)
    outer = configuration_space(world, radius=radius, centers=c, radii=r, quad_segs=quad_segs)
    inner = configuration_space(
        world, radius=radius, centers=c, radii=r, quad_segs=quad_segs, conservative=False
    )
    try:
        hi = shortest_path(world, s, g, radius=radius, centers=c, radii=r, quad_segs=quad_segs)
    except InvalidQueryError:
        assume(False)
        return
    lo = VisibilityGraph.from_geometry(inner).shortest_path(s, g)
    assert outer.area <= inner.area
    if hi.found:
        assert lo.found
        # lo <= true optimum <= hi always; hi / lo - 1 <= the documented bound when the two
        # spaces have the same topology (where a gap between two discs is open inside and
        # closed outside, the outer path must go another way round; hypothesis found such
        # a snapshot, seed 10000 with quad_segs 2, where the ratio is 8.8 % > 8.2 %)
        assert lo.length <= hi.length + 1e-9
        if _topology(outer) == _topology(inner):
            assert hi.length / lo.length - 1 <= length_error_bound(quad_segs) + 1e-9


def _topology(space) -> tuple[int, int]:  # type: ignore[no-untyped-def]
    """(connected parts, holes) of a polygonal free space."""
    parts = shapely.get_parts(space)
    return len(parts), int(shapely.get_num_interior_rings(parts).sum())


def test_around_one_corner_against_the_exact_length() -> None:
    # A disc of radius 0.3 from (2, 2) over a wall whose top corners are (4, 8) and
    # (6, 8): tangent, quarter-ish arc, straight, arc, tangent (computed by hand).
    w = World([[0, 0], [10, 0], [10, 10], [0, 10]], [[[4, 0.5], [6, 0.5], [6, 8], [4, 8]]])
    r = 0.3
    d = math.hypot(2, 6)
    tangent = math.sqrt(d * d - r * r)
    to_start = math.atan2(-6, -2) % (2 * math.pi)
    touch = to_start - math.acos(r / d)
    arc = r * (touch - math.pi / 2)
    exact = 2 * (tangent + arc) + 2
    for quad_segs in (4, 16, 64):
        got = shortest_path(w, [2, 2], [8, 2], radius=r, quad_segs=quad_segs).length
        assert exact <= got <= exact * (1 + length_error_bound(quad_segs))


def test_no_path_is_an_answer_not_an_error() -> None:
    plan = shortest_path(CORRIDOR, [2, 1.5], [38, 1.5], radius=0.3, centers=[[20, 1.5]], radii=1.2)
    assert not plan.found and plan.length == math.inf
    free = shortest_path(CORRIDOR, [2, 1.5], [38, 1.5], radius=0.3)
    assert free.length == pytest.approx(36.0)


@pytest.mark.parametrize(
    ("start", "kwargs", "message"),
    [
        ([20, 6], {}, r"start \(20, 6\) must lie in the free space; it is inside an obstacle"),
        (
            [20, 4.8],
            {"radius": 0.3},
            r"start \(20, 4.8\) is 0.2 from a wall; an agent of radius 0.3",
        ),
        (
            [20, 15],
            {"radius": 0.3, "centers": [[20.5, 15]], "radii": [0.5]},
            r"start \(20, 15\) overlaps obstacle 0",
        ),
        ([45, 15], {}, r"start \(45, 15\) must lie in the free space; .* 5 from the nearest"),
    ],
)
def test_bad_queries_say_why(start, kwargs, message) -> None:
    with pytest.raises(InvalidQueryError, match=message):
        shortest_path(U_TRAP, start, [20, 28], **kwargs)


def test_the_u_trap_path() -> None:
    plan = shortest_path(U_TRAP, U_TRAP.start, U_TRAP.goal)
    assert plan.length == pytest.approx(13.0)  # straight out of the open top
    around = shortest_path(U_TRAP, [20, 2], [20, 15])
    # from below the U to inside it: around an outer corner (10, 5) or (30, 5), then
    # in through the top corners (12, 25) or (28, 25)
    expected = math.hypot(10, 3) + 20 + 2 + math.hypot(8, 10)
    assert around.length == pytest.approx(expected)
