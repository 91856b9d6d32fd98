from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from copi.errors import InvalidArgumentError
from copi.geometry.kernels import closest_approach
from copi.world import RandomWalk, RangeSensor, Simulator, random_world
from tests.common import PILLARS, U_TRAP


@settings(max_examples=15, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_agent_and_obstacles_never_enter_walls(seed: int) -> None:
    world = random_world(seed) if seed % 3 else PILLARS
    sim = Simulator.from_world(world, seed)
    walk = RandomWalk(seed=seed, speed=1.5)  # faster than allowed: clipped to 1
    blocked = False
    for _ in range(300):
        before = sim.centers.copy()
        pos = sim.position.copy()
        res = sim.step(walk(blocked))
        blocked = res.blocked
        assert np.hypot(*(sim.position - pos)) <= 1.0 + 1e-12
        assert world.clearance(sim.position) >= sim.agent_radius - 1e-9
        assert world.contains(sim.position)
        assert (world.clearance(sim.centers) >= sim.radii - 1e-9).all()
        moved = np.hypot(*(sim.centers - before).T)
        assert np.all(np.isclose(moved, 0.0) | np.isclose(moved, sim.speed))
    np.testing.assert_allclose(
        sim.ranges, sim.sensor.scan(world, sim.position, sim.centers, sim.radii)
    )


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.floats(-5, 5), min_size=8, max_size=8),
)
def test_closest_approach_matches_dense_sampling(v: list[float]) -> None:
    ax, ay, adx, ady, bx, by, bdx, bdy = v
    t = np.linspace(0, 1, 20001)
    dense = np.hypot(ax + t * adx - bx - t * bdx, ay + t * ady - by - t * bdy).min()
    exact = closest_approach(ax, ay, adx, ady, bx, by, bdx, bdy)
    assert exact <= dense + 1e-12
    # sampling every 1/20000 of the step misses the minimum by at most |v| / 40000
    assert dense - exact <= np.hypot(adx - bdx, ady - bdy) / 40000 + 1e-12


def test_contact_with_a_static_disc_agrees_with_shapely() -> None:
    rng = np.random.default_rng(1)
    for _ in range(300):
        c = rng.uniform(5, 25, size=(1, 2))
        start = c[0] + rng.uniform(-2.5, 2.5, size=2)
        if np.hypot(*(start - c[0])) < 1.0:
            continue
        sim = Simulator(PILLARS.replace(holes=()), start, [1, 1], c, [0.6], seed=0, speed=0.0)
        action = rng.uniform(-1, 1, size=2)
        res = sim.step(action)
        path = shapely.LineString([start, sim.position])
        expected = path.distance(shapely.Point(c[0])) < 0.3 + 0.6
        assert res.contact == expected


def test_same_seed_same_episode() -> None:
    def run(seed: int) -> tuple[np.ndarray, np.ndarray]:
        sim = Simulator.from_world(random_world(seed), seed)
        walk = RandomWalk(seed=seed)
        for _ in range(100):
            sim.step(walk())
        return sim.position, sim.centers

    a, b = run(11), run(11)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert not np.array_equal(a[1], run(12)[1])


def test_goal_reached_and_bad_actions() -> None:
    sim = Simulator(U_TRAP, [20, 26], [20, 28], np.zeros((0, 2)), [], seed=0)
    assert not sim.step([0, 1]).reached
    res = sim.step([0, 5])
    assert res.reached and res.distance == pytest.approx(0.0)
    with pytest.raises(InvalidArgumentError, match="action must be finite"):
        sim.step([np.nan, 0])
    with pytest.raises(InvalidArgumentError, match="action must be a velocity of shape"):
        sim.step(3.0)


def test_sensor_sees_the_moving_obstacles() -> None:
    sensor = RangeSensor(4, 10.0)
    sim = Simulator(U_TRAP, [20, 15], [20, 28], [[23, 15]], [1.0], sensor=sensor, seed=0)
    assert sim.ranges.tolist() == [2.0, 10.0, 8.0, 8.0]


@pytest.mark.parametrize("radius", [float("nan"), -1.0, 0.0, 1j, "big"])
def test_a_bad_agent_radius_is_refused(radius) -> None:
    from copi.errors import InvalidArgumentError
    from copi.world import Simulator, World

    with pytest.raises(InvalidArgumentError, match="agent_radius"):
        Simulator.from_world(World([[0, 0], [30, 0], [30, 30], [0, 30]]), 0, agent_radius=radius)
