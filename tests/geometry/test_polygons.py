from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from copi.errors import InvalidArgumentError
from copi.geometry import as_ring, orient, ring_crossings, ring_segments, signed_area

coords = st.lists(
    st.tuples(st.integers(0, 6), st.integers(0, 6)), min_size=3, max_size=9, unique=True
)


@settings(max_examples=300, deadline=None)
@given(coords)
def test_crossings_agree_with_shapely_simplicity(points: list[tuple[int, int]]) -> None:
    ring = np.array(points, dtype=float)
    if abs(signed_area(ring)) == 0:
        return
    simple = shapely.LinearRing(ring).is_simple
    assert (not ring_crossings(ring)) == simple


@settings(max_examples=100, deadline=None)
@given(coords)
def test_orientation_and_area(points: list[tuple[int, int]]) -> None:
    ring = np.array(points, dtype=float)
    shape = shapely.Polygon(ring)
    if not shape.exterior.is_simple or shape.area == 0:
        return
    area = signed_area(ring)
    assert abs(area) == pytest.approx(shape.area)
    assert (area > 0) == shape.exterior.is_ccw
    assert signed_area(orient(ring, ccw=True)) == pytest.approx(abs(area))
    assert signed_area(orient(ring, ccw=False)) == pytest.approx(-abs(area))


def test_segments_close_the_ring() -> None:
    segs = ring_segments(np.array([[0, 0], [1, 0], [0, 1]], dtype=float))
    assert segs.tolist() == [[0, 0, 1, 0], [1, 0, 0, 1], [0, 1, 0, 0]]


def test_a_spike_folding_back_is_a_crossing() -> None:
    assert ring_crossings([[0, 0], [4, 0], [4, 4], [4, 2], [0, 4]])


def test_as_ring_refuses_too_few_vertices() -> None:
    with pytest.raises(InvalidArgumentError, match="at least 3 distinct vertices; got 2"):
        as_ring([[0, 0], [1, 1], [0, 0]])
