"""FuturesPlanner(together=g): g futures valued as one in the hindsight."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from copi.planning.futures import FuturesPlanner
from copi.world import World

HALL = World([[0, 0], [24, 0], [24, 10], [0, 10]], start=[2, 5], goal=[22, 5])


def _futures(seed: int, n: int = 8, bodies: int = 3, steps: int = 9) -> np.ndarray:
    """Random walks of ``bodies`` discs round the agent's way, ``n`` futures."""
    rng = np.random.default_rng(seed)
    start = rng.uniform([4, 2], [12, 8], size=(bodies, 2))
    moves = rng.normal(0, 0.6, size=(n, steps - 1, bodies, 2))
    walk = np.concatenate([np.zeros((n, 1, bodies, 2)), np.cumsum(moves, axis=1)], axis=1)
    return np.ascontiguousarray(start[None, None] + walk)


def _plan(together: int, futures: np.ndarray) -> tuple[int, np.ndarray]:
    pl = FuturesPlanner(horizon=8, together=together)
    pl.reset(HALL, np.array([22.0, 5.0]), 0.3, 0.5)
    m, _ = pl.plan(np.array([3.0, 5.0]), futures, np.full(futures.shape[2], 0.6))
    return m, pl.costs.copy()


def test_alike_futures_valued_together_are_one() -> None:
    one = _futures(0, n=2)
    alike = np.ascontiguousarray(np.repeat(one, 4, axis=0))  # each future four times in a row
    m1, c1 = _plan(1, alike)
    m4, c4 = _plan(4, alike)
    assert m1 == m4 and np.allclose(c1, c4, equal_nan=True)


@settings(max_examples=15, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from([2, 4, 8]))
def test_valuing_futures_together_never_makes_a_move_cheaper(seed: int, g: int) -> None:
    """A group's way must clear the discs of each of its futures, so no cell's value,
    and no move's cost, drops below what the futures valued alone give."""
    fut = _futures(seed)
    _, alone = _plan(1, fut)
    _, together = _plan(g, fut)
    finite = np.isfinite(alone)
    assert np.array_equal(finite, np.isfinite(together))
    assert np.all(together[finite] >= alone[finite] - 1e-9)


def test_together_is_checked() -> None:
    for bad in (0, 1.5, 65):
        with pytest.raises(ValueError, match="together must be a whole number in 1 .. 64"):
            FuturesPlanner(together=bad)  # type: ignore[arg-type]
