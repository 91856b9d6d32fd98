"""Many agents among each other (copi.world.crowd): the batched scans through the grid are
RangeSensor's scans with every other agent as a disc, the grid finds what brute force
finds, contacts are closest approaches, placement keeps discs apart, memory is linear."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from copi.errors import InvalidArgumentError
from copi.geometry.kernels import closest_approach
from copi.world import RangeSensor, World
from copi.world._crowd_kernels import clip_actions
from copi.world.crowd import (
    COLLISION,
    GAP_EXACT,
    MAX_DENSITY,
    PLACEMENT_GAP,
    RUNNING,
    SUCCESS,
    Crowd,
    crowd_room,
    place_agents,
)
from tests.common import PILLARS

SENSOR = RangeSensor()


def _brute_scan(crowd: Crowd, b: int) -> np.ndarray:
    """Agent b's reading by RangeSensor.scan, every other agent in the world a disc."""
    others = np.flatnonzero(crowd.active)
    others = others[others != b]
    return SENSOR.scan(crowd.world, crowd.positions[b], crowd.positions[others],
                       np.full(len(others), crowd.radius))  # fmt: skip


def _check_scans(crowd: Crowd) -> None:
    for b in np.flatnonzero(crowd.active):
        assert np.array_equal(crowd.ranges[b], _brute_scan(crowd, b)), b


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    agents=st.integers(2, 160),
    density=st.sampled_from([0.02, 0.1, 0.4, 1.0]),
    seed=st.integers(0, 2**32 - 1),
    moves=st.integers(0, 6),
    cell=st.sampled_from([None, 0.5, 3.0, 40.0]),
)
def test_batched_scans_are_range_sensor_scans_bit_for_bit(
    agents: int, density: float, seed: int, moves: int, cell: float | None
) -> None:
    try:
        crowd = Crowd.draw(crowd_room(agents, density), agents, seed, cell_size=cell)
    except InvalidArgumentError as e:  # a room of a few agents at density 1 is mostly wall band
        assert "lower the density" in str(e) and agents < 10
        assume(False)
    _check_scans(crowd)
    rng = np.random.default_rng(seed)
    for _ in range(moves):  # agents that touch or arrive leave; some overlap on the way
        crowd.step(rng.uniform(-1, 1, (agents, 2)) + 0.3 * (crowd.goals - crowd.positions))
        _check_scans(crowd)


def test_scans_in_a_world_with_holes_and_in_slices() -> None:
    crowd = Crowd.draw(PILLARS, 120, seed=3)
    _check_scans(crowd)
    whole = crowd.ranges.copy()
    crowd.ranges[:] = -1.0
    crowd.index()
    for lo, hi in ((0, 50), (50, 120)):
        crowd.scan(lo, hi)
    assert np.array_equal(crowd.ranges, whole)


def test_a_centre_inside_another_disc_reads_zero() -> None:
    room = crowd_room(2, 0.01)
    crowd = Crowd(room, [[5.0, 5.0], [5.2, 5.0]], [[9.0, 9.0], [1.0, 1.0]])
    assert (crowd.ranges == 0).all()
    _check_scans(crowd)


def test_a_disc_grazing_a_ray_is_read_on_it() -> None:
    # each disc is tested on the rays of its angular window only: a disc just inside the
    # tangent of a ray, at every distance and on every side, must still lower that ray
    rng = np.random.default_rng(0)
    room = crowd_room(2, 0.001)
    (x0, y0, x1, y1), r = room.bounds, 0.3
    o = np.array([(x0 + x1) / 2, (y0 + y1) / 2])
    for _ in range(400):
        i = int(rng.integers(32))
        d = rng.uniform(2 * r + 0.01, 10.0)
        side = rng.choice([-1.0, 1.0])
        a = SENSOR.angles[i] + side * (math.asin(r / d) - rng.uniform(0, 1e-6))
        crowd = Crowd(room, [o, o + d * np.array([math.cos(a), math.sin(a)])],
                      [o + 5.0, o - 5.0], cell_size=float(rng.choice([1.0, 3.0, 7.0])))  # fmt: skip
        assert crowd.ranges[0, i] < SENSOR.max_range
        _check_scans(crowd)


def test_the_grid_finds_the_agents_brute_force_finds() -> None:
    crowd = Crowd.draw(crowd_room(400, 0.3), 400, seed=5)
    crowd.active[::7] = False
    crowd.index()
    for b in range(0, 400, 13):
        for reach in (0.8, 3.0, 10.3):
            d = np.hypot(*(crowd.positions - crowd.positions[b]).T)
            want = np.flatnonzero(crowd.active & (d <= reach))
            want = want[want != b]
            assert sorted(crowd.neighbours(b, reach).tolist()) == want.tolist()


def test_contacts_are_the_closest_approaches_of_the_moves() -> None:
    rng = np.random.default_rng(2)
    for seed in range(4):
        crowd = Crowd.draw(crowd_room(150, 0.8), 150, seed=seed)
        old = crowd.positions.copy()
        res = crowd.step(rng.uniform(-1.5, 1.5, (150, 2)), leave=False)
        new = crowd.positions
        for b in range(150):
            best = math.inf
            for k in range(150):
                if k != b:
                    d = closest_approach(*old[b], *(new[b] - old[b]), *old[k], *(new[k] - old[k]))
                    best = min(best, d - 2 * crowd.radius)
            if best < GAP_EXACT:
                assert res.gap[b] == best
            else:  # at least GAP_EXACT (or inf: none near)
                assert res.gap[b] >= GAP_EXACT
            assert res.contact[b] == (best < 0)


def test_placement_keeps_discs_apart_and_off_the_walls_and_is_seeded() -> None:
    room = crowd_room(800, 1.2)
    starts, goals = place_agents(room, 800, 7)
    d = np.hypot(*(starts[:, None] - starts[None]).T)
    np.fill_diagonal(d, np.inf)
    assert d.min() >= 2 * 0.3 + PLACEMENT_GAP
    assert room.clearance(starts).min() >= 0.3 + PLACEMENT_GAP
    assert room.clearance(goals).min() >= 0.3
    assert np.hypot(*(goals - starts).T).min() >= 10.0
    again = place_agents(room, 800, 7)
    assert np.array_equal(again[0], starts) and np.array_equal(again[1], goals)


def test_agents_that_cannot_be_placed_are_refused_saying_how_many_fit() -> None:
    with pytest.raises(InvalidArgumentError, match=r"cannot place 300 agents .* only \d+ fitted"):
        place_agents(World([[0, 0], [12, 0], [12, 12], [0, 12]]), 300, 0)
    with pytest.raises(InvalidArgumentError, match=f"at most {MAX_DENSITY:g} agents per"):
        crowd_room(100, 3.0)
    with pytest.raises(InvalidArgumentError, match="at most 100,000"):
        crowd_room(100_001, 0.1)


def test_walls_stop_agents_and_trips_end_at_goals_or_contacts() -> None:
    room = World([[0, 0], [30, 0], [30, 30], [0, 30]])
    starts = [[1.0, 15.0], [10.0, 10.0], [20.0, 10.0], [10.0, 25.0], [12.0, 25.0]]
    goals = [[25.0, 15.0], [10.0, 12.0], [25.0, 25.0], [20.0, 25.0], [2.0, 25.0]]
    crowd = Crowd(room, starts, goals)
    crowd.step([[-5.0, 0.0], [0.0, 1.0], [0.0, 1.0], [1.0, 0.0], [-1.0, 0.0]])
    assert crowd.positions[0, 0] >= 0.3  # stopped by the wall (less its tiny gap)
    assert crowd.outcome.tolist() == [RUNNING, RUNNING, RUNNING, COLLISION, COLLISION]
    res = crowd.step([[0.0, 0.0], [0.0, 1.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]])
    assert res.reached.tolist() == [False, True, False, False, False]
    assert crowd.outcome[1] == SUCCESS and crowd.ended[1] == 2
    assert crowd.active.tolist() == [True, False, True, False, False]
    assert crowd.trip_length[1] == pytest.approx(2.0)


def test_a_steady_crowd_keeps_every_agent_and_draws_new_goals() -> None:
    crowd = Crowd.draw(crowd_room(60, 0.05), 60, seed=1)
    first = crowd.goals.copy()
    for _ in range(80):
        crowd.step(crowd.goals - crowd.positions, leave=False)
    assert crowd.active.all()
    arrived = crowd.arrivals > 0
    assert arrived.any()
    assert (crowd.goals[arrived] != first[arrived]).any(axis=1).all()
    assert np.isin(crowd.outcome, [SUCCESS, COLLISION]).sum() >= arrived.sum()


def test_memory_is_linear_in_the_agents() -> None:
    per = [Crowd.draw(crowd_room(n, 0.2), n, seed=0).nbytes / n for n in (1000, 8000)]
    assert per[1] == pytest.approx(per[0], rel=0.05)
    assert per[0] < 2000


def test_actions_are_checked() -> None:
    crowd = Crowd.draw(crowd_room(5, 0.1), 5, seed=0)
    with pytest.raises(InvalidArgumentError, match=r"shape \(5, 2\)"):
        crowd.step(np.zeros((4, 2)))
    bad = np.zeros((5, 2))
    bad[3, 1] = np.nan
    with pytest.raises(InvalidArgumentError, match="agent 3"):
        crowd.step(bad)


@settings(max_examples=40, deadline=None)
@given(rows=st.lists(st.tuples(st.floats(-1e6, 1e6) | st.sampled_from([0.0, 1.0, -1.0]),
                               st.floats(-1e6, 1e6) | st.sampled_from([0.0, 1.0, -1.0]),
                               st.booleans()),
                     min_size=1, max_size=20))  # fmt: skip
def test_actions_are_clipped_as_numpy_clips_them(rows: list[tuple[float, float, bool]]) -> None:
    """The compiled clip is numpy's, bit for bit: an agent out of the world moves by 0,
    an action longer than 1 is divided by its norm (``np.hypot``); a NaN in a row of an
    agent out of the world is ignored, in one in the world reported."""
    a = np.array([r[:2] for r in rows])
    active = np.array([r[2] for r in rows])
    want = np.where(active[:, None], a, 0.0)
    norm = np.hypot(want[:, 0], want[:, 1])
    over = norm > 1.0
    want[over] /= norm[over, None]
    out = np.empty_like(a)
    assert clip_actions(a, active, out) == -1
    assert out.tobytes() == want.tobytes()
    a[0, 1] = np.nan
    assert clip_actions(a, active, out) == (0 if active[0] else -1)


@pytest.mark.parametrize("leave", [False, True])
def test_the_next_step_may_start_once_the_agents_moved(leave: bool) -> None:
    """``moved`` is called once a step, when what the next step reads is settled (the
    positions, new goals, who is in the world, the step's number); in a steady crowd
    before the step's books (the velocities still the last step's), with trips that
    end, after them."""
    crowd = Crowd.draw(crowd_room(80, 0.3), 80, seed=3)
    seen: list[tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []

    def moved() -> None:
        seen.append((crowd.t, crowd.positions.copy(), crowd.goals.copy(),
                     crowd.active.copy(), crowd.velocities.copy()))  # fmt: skip

    for t in range(1, 30):
        before = crowd.velocities.copy()
        crowd.step(crowd.goals - crowd.positions, leave=leave, moved=moved)
        assert len(seen) == t
        step, pos, goals, active, vel = seen[-1]
        assert step == crowd.t == t
        assert np.array_equal(pos, crowd.positions) and np.array_equal(goals, crowd.goals)
        assert np.array_equal(active, crowd.active)
        assert np.array_equal(vel, crowd.velocities if leave else before)
    assert (crowd.arrivals > 0).any()
    if leave:
        assert not crowd.active.all()
