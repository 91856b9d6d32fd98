from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from copi.errors import InvalidArgumentError
from copi.geometry import cast_rays, ring_angles
from copi.geometry.reference import cast_rays_numpy, cast_rays_shapely
from copi.world import random_world
from tests.common import PILLARS, U_TRAP

ANGLES = ring_angles(32)


def _scene(seed: int, n_discs: int):
    """A random world, an origin in it and discs around, from one seed."""
    rng = np.random.default_rng(seed)
    world = random_world(rng)
    xmin, ymin, xmax, ymax = world.bounds
    while True:
        o = rng.uniform([xmin, ymin], [xmax, ymax])
        if world.contains(o):
            break
    c = o + rng.uniform(-8, 8, size=(n_discs, 2))
    r = rng.uniform(0.3, 1.2, size=n_discs)
    return world, o, c, r


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), max_range=st.floats(2.0, 60.0))
def test_walls_agree_with_shapely(seed: int, max_range: float) -> None:
    world, o, _, _ = _scene(seed, 0)
    got = cast_rays(o, ANGLES, world.segments, max_range=max_range)
    ref = cast_rays_shapely(o, ANGLES, world.segments, max_range=max_range)
    np.testing.assert_allclose(got, ref, atol=1e-9, rtol=1e-9)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_discs=st.integers(1, 15))
def test_discs_agree_with_fine_shapely_circles(seed: int, n_discs: int) -> None:
    world, o, c, r = _scene(seed, n_discs)
    got = cast_rays(o, ANGLES, world.segments, c, r)
    ref = cast_rays_shapely(o, ANGLES, world.segments, c, r, quad_segs=256)
    # Shapely's circle is a 1024-gon inscribed in the true one: it reads at most
    # r (1 - cos(pi / 1024)) / sin(incidence) farther. Rays grazing a disc (perpendicular
    # distance within 2 % of r) are left out, where the polygon may be missed entirely.
    d = np.column_stack([np.cos(ANGLES), np.sin(ANGLES)])
    v = c[None, :, :] - o[None, None, :]
    along = (v * d[:, None, :]).sum(-1)
    perp = np.abs(v[..., 0] * d[:, None, 1] - v[..., 1] * d[:, None, 0])
    grazing = ((np.abs(perp - r) < 0.02 * r) & (along > 0)).any(axis=1)
    np.testing.assert_allclose(got[~grazing], ref[~grazing], atol=2e-4)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_discs=st.integers(0, 15))
def test_compiled_equals_plain_numpy(seed: int, n_discs: int) -> None:
    world, o, c, r = _scene(seed, n_discs)
    origins = np.vstack([o, o + 0.5, o - [0.25, 0.7]])
    got = cast_rays(origins, ANGLES, world.segments, c, r)
    ref = cast_rays_numpy(origins, ANGLES, world.segments, c, r)
    np.testing.assert_allclose(got, ref, atol=1e-9)


def test_batched_equals_one_by_one() -> None:
    rng = np.random.default_rng(5)
    origins = rng.uniform(1, 29, size=(50, 2))
    c, r = rng.uniform(0, 30, size=(10, 2)), rng.uniform(0.5, 1, size=10)
    batch = cast_rays(origins, ANGLES, PILLARS.segments, c, r)
    single = np.array([cast_rays(o, ANGLES, PILLARS.segments, c, r) for o in origins])
    np.testing.assert_array_equal(batch, single)
    assert batch.shape == (50, 32)


def test_inside_disc_reads_zero_and_empty_scene_reads_max() -> None:
    assert cast_rays([0, 0], ANGLES, np.zeros((0, 4)), [[0.2, 0]], 1.0).tolist() == [0.0] * 32
    assert cast_rays([0, 0], ANGLES, np.zeros((0, 4)), max_range=7).tolist() == [7.0] * 32


def test_known_ranges_in_the_u_trap() -> None:
    # From (20, 15): east 8 to the right arm (x = 28), south 8 to the bar (y = 7),
    # north 10 (clipped; open top of the U, wall at y = 30 is 15 away).
    ranges = cast_rays([20, 15], ring_angles(4), U_TRAP.segments)
    np.testing.assert_allclose(ranges, [8.0, 10.0, 8.0, 8.0])


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"origins": [[0, np.nan]]}, "origins must be finite; found nan at index (0, 1)"),
        ({"origins": [1, 2, 3]}, "origins must have shape (2,) or (n, 2); got shape (3,)"),
        ({"segments": [[0, 0, 1]]}, "segments must have shape (m, 4); got shape (1, 3)"),
        ({"max_range": -1}, "max_range must be a finite number > 0; got -1.0"),
        ({"centers": [[0, 0]], "radii": [-1.0]}, "radii must be >= 0; got -1.0"),
        ({"centers": [[0, 0]], "radii": [1.0, 2.0]}, "radii must have shape (1,); got shape (2,)"),
    ],
)
def test_bad_arguments_say_what_was_expected(kwargs: dict, message: str) -> None:
    args = {"origins": [1.0, 1.0], "angles": ANGLES, "segments": PILLARS.segments} | kwargs
    with pytest.raises(InvalidArgumentError) as err:
        cast_rays(**args)
    assert str(err.value) == message
