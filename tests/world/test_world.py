from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from copi.errors import InvalidWorldError
from copi.geometry import signed_area
from copi.world import ObstacleSpec, World
from tests.common import NAMED, PILLARS, U_TRAP

BOX = [[0, 0], [10, 0], [10, 10], [0, 10]]


@pytest.mark.parametrize(
    ("boundary", "holes", "message"),
    [
        (
            [[0, 0], [4, 4], [4, 0], [0, 4]],
            [],
            "boundary must be a simple polygon; edges 0 and 2 cross at (2, 2)",
        ),
        ([[0, 0], [1, 1], [2, 2]], [], "boundary must enclose an area; its vertices are collinear"),
        ([[0, 0], [1, 1]], [], "boundary must have at least 3 distinct vertices; got 2"),
        ([[0, 0], [1, np.nan], [2, 0]], [], "boundary must be finite; found nan at index (1, 1)"),
        (
            [[0, 0, 0], [1, 1, 1], [2, 0, 0]],
            [],
            "boundary must have shape (n, 2); got shape (3, 3)",
        ),
        (
            BOX,
            [[[8, 8], [12, 8], [12, 9]]],
            "hole 0 must lie strictly inside the boundary; its vertex 1 (12, 8) does not",
        ),
        (
            BOX,
            [[[2, 2], [4, 2], [4, 4], [2, 4]], [[3, 3], [6, 3], [6, 6], [3, 6]]],
            "holes must be disjoint; holes 0 and 1 meet at",
        ),
        (
            BOX,
            [[[2, 2], [4, 4], [4, 2], [2, 4]]],
            "hole 0 must be a simple polygon; edges 0 and 2 cross at (3, 3)",
        ),
        (BOX, np.array([[1, 1], [2, 1], [2, 2]]), "holes must be a list of polygons"),
    ],
)
def test_invalid_geometry_says_what_and_where(boundary, holes, message) -> None:
    with pytest.raises(InvalidWorldError) as err:
        World(boundary, holes, name="w")
    assert str(err.value).startswith(f"world 'w': {message}")


def test_start_and_goal_must_be_free() -> None:
    with pytest.raises(InvalidWorldError, match=r"start \(3, 3\) must lie in the free space"):
        World(BOX, [[[2, 2], [4, 2], [4, 4], [2, 4]]], start=[3, 3])
    with pytest.raises(InvalidWorldError, match=r"goal must have shape \(2,\)"):
        World(BOX, goal=[1, 2, 3])


@settings(max_examples=100, deadline=None)
@given(st.sampled_from(sorted(NAMED)), st.booleans(), st.booleans())
def test_either_orientation_is_accepted_and_normalised(
    name: str, flip_b: bool, flip_h: bool
) -> None:
    w = NAMED[name]
    b = w.boundary[::-1] if flip_b else w.boundary
    holes = [h[::-1] if flip_h else h for h in w.holes]
    again = World(b, holes, name=name)
    assert signed_area(again.boundary) > 0
    assert all(signed_area(h) < 0 for h in again.holes)
    assert again.area == pytest.approx(w.area)
    assert again.polygon.is_valid


def test_world_is_immutable() -> None:
    with pytest.raises(AttributeError):
        PILLARS.name = "x"  # type: ignore[misc]
    with pytest.raises(ValueError):
        PILLARS.boundary[0, 0] = 5.0
    with pytest.raises(ValueError):
        PILLARS.segments[0, 0] = 5.0


def test_contains_and_clearance_agree_with_shapely() -> None:
    rng = np.random.default_rng(0)
    pts = rng.uniform(-2, 42, size=(500, 2))
    poly = U_TRAP.polygon
    expected = shapely.contains_xy(poly, pts[:, 0], pts[:, 1])
    assert (U_TRAP.contains(pts) == expected).all()
    walls = shapely.MultiLineString([s.reshape(2, 2) for s in U_TRAP.segments])
    ref = shapely.distance(walls, shapely.points(pts))
    np.testing.assert_allclose(U_TRAP.clearance(pts), ref, atol=1e-12)
    assert U_TRAP.area == pytest.approx(40 * 30 - (20 * 2 + 2 * 2 * 18))


def test_obstacle_spec_forms() -> None:
    assert ObstacleSpec.from_dict({"count": 12, "radius": 0.75}).to_dict() == {
        "count": 12,
        "radius": 0.75,
        "speed": 0.6,
    }
    assert ObstacleSpec().count == (10, 15)
    with pytest.raises(InvalidWorldError, match="obstacles.count must be whole numbers"):
        ObstacleSpec(count=2.5)  # type: ignore[arg-type]
    with pytest.raises(InvalidWorldError, match="obstacles has unknown keys"):
        ObstacleSpec.from_dict({"cnt": 3})
    with pytest.raises(InvalidWorldError, match="obstacles.radius must be > 0"):
        ObstacleSpec(radius=0.0)  # type: ignore[arg-type]


def test_replace_and_equality() -> None:
    w = U_TRAP.replace(goal=[35.0, 28.0])
    assert w != U_TRAP and w.goal.tolist() == [35.0, 28.0]
    assert w.replace(goal=U_TRAP.goal) == U_TRAP
