from __future__ import annotations

import numpy as np
import pytest

from copi.core import Observation
from copi.errors import InvalidArgumentError
from copi.methods import make_agent
from copi.online import Mapping, Steering
from copi.runs import make_task, run_episode
from copi.world import Simulator
from tests.baselines._support import TRAP_GOAL, route_length
from tests.common import U_TRAP


def _trap() -> Simulator:
    return Simulator(U_TRAP, U_TRAP.start, TRAP_GOAL, np.zeros((0, 2)), np.zeros(0))


@pytest.mark.parametrize("name", ["compass-guard", "dwa", "vfh"])
def test_mapping_gets_out_of_a_u_trap_with_no_map(name: str) -> None:
    # The goal lies behind the U's bottom: heading for it is a dead end, mapping is not.
    length = route_length(U_TRAP, U_TRAP.start, TRAP_GOAL)
    greedy = run_episode(make_agent(name), _trap(), sensing="sensor", max_steps=300)
    assert greedy.outcome == "timeout"
    sim = _trap()
    mapped = run_episode(make_agent(name), sim, sensing="sensor", max_steps=300,
                       strategy="mapping")  # fmt: skip
    assert mapped.outcome == "success"
    assert mapped.path_length <= 1.5 * length


def test_a_passing_disc_fades_from_the_map_and_a_wall_stays() -> None:
    m = Mapping()
    m.reset(32, 10.0, 0.3)
    here = np.array([0.0, 0.0])
    ranges = np.full(32, 10.0)
    ranges[0] = 3.0  # something 3 east
    for _ in range(3):
        m.update(ranges, here)
    cell = m._index(np.array([[3.0, 0.0]]))[0]
    assert m.occupancy[cell[1], cell[0]] > 0
    ranges[0] = 10.0  # gone: the ray now passes through its cell
    for _ in range(10):
        m.update(ranges, here)
    assert m.occupancy[cell[1], cell[0]] <= 0
    # A wall seen from many places stays through a few grazing misses.
    wall = np.full(32, 10.0)
    wall[8] = 4.0  # north, 4 away
    for _ in range(4):
        m.update(wall, here)
    north = m._index(np.array([[0.0, 4.0]]))[0]
    m.update(np.full(32, 10.0), here)
    assert m.occupancy[north[1], north[0]] > 0


def test_mapping_uses_only_the_sensor_level() -> None:
    sim = _trap()
    task = make_task(sim, "sensor", "mapping")
    assert task.world is None and task.start is None and task.goal is None
    s = Steering()
    s.reset(task)
    assert s.mapping is not None and s.route is None
    # At the map level the route is followed, whatever the sensor-level strategy.
    s.reset(make_task(sim, "map", "mapping"))
    assert s.route is not None and s.mapping is None
    with pytest.raises(InvalidArgumentError, match="sensor strategy must be one of greedy, mapping, causal; got 'astar'"):
        s.reset(make_task(sim, "sensor", "astar"))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"cell": 0.0}, "cell must be a finite number > 0; got 0.0"),
        ({"margin": -1.0}, "margin must be a finite number >= 0; got -1.0"),
        ({"every": 0}, "every must be a positive int; got 0"),
    ],
)
def test_bad_parameters(kwargs: dict, message: str) -> None:
    with pytest.raises(InvalidArgumentError, match=message):
        Mapping(**kwargs)


def test_walls_learnt_on_the_grid_give_a_static_reading() -> None:
    m = Mapping()
    m.reset(32, 10.0, 0.3)
    here = np.array([0.3, -0.2])
    wall = np.full(32, 10.0)
    wall[8] = 4.0  # a wall 4 north
    disc = wall.copy()
    disc[0] = 3.0  # and, for a few steps, a disc 3 east
    for _ in range(3):
        m.update(disc, here)
    for _ in range(30):
        m.update(wall, here)
    s = m.static_reading(here)
    # Never beyond the wall's face, within a cell and a step of it.
    assert 4.0 - m.cell - 0.1 <= s[8] <= 4.0
    assert s[0] == 10.0  # the disc passed: no wall east
    assert (np.delete(s, [7, 8, 9]) == 10.0).all()
    # A wall seen a few times only is not yet learnt.
    fresh = Mapping()
    fresh.reset(32, 10.0, 0.3)
    for _ in range(5):
        fresh.update(wall, here)
    assert fresh.static_reading(here)[8] == 10.0


def test_the_learnt_static_reading_is_handed_on_in_a_life_only() -> None:
    sim = _trap()
    life = make_task(sim, "sensor", "mapping", lifelong=True)
    s = Steering()
    s.reset(life)
    obs = Observation(ranges=sim.ranges.copy(), goal=sim.goal - sim.position,
                      odometry=np.zeros(2))  # fmt: skip
    for _ in range(25):
        s.aim(obs)
    seen = s.observe(obs)
    assert seen.static is not None and seen.static.min() < 10.0
    assert (seen.static <= obs.ranges + 1e-9).all()  # walls only: never beyond a hit
    one = Steering()
    one.reset(make_task(sim, "sensor", "mapping"))
    plain = Observation(ranges=sim.ranges.copy(), goal=sim.goal - sim.position)
    for _ in range(25):
        one.aim(plain)
    assert one.observe(plain) is plain  # one episode: nothing learnt is handed on
