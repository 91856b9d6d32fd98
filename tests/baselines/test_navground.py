"""navground's behaviours as peers (an optional extra: these tests need it, except the
one that checks what happens without it)."""

from __future__ import annotations

import sys

import pytest

from copi.baselines import NavgroundAgent, NavgroundMissingError, navground_available
from copi.errors import InvalidArgumentError
from copi.methods import make_agent, method_spec
from copi.runs import make_task, run_episode
from copi.world import Simulator
from tests.baselines._support import EMPTY_PAIRS, empty, head_on, run
from tests.common import PILLARS


@pytest.fixture
def navground():
    return pytest.importorskip("navground")


@pytest.mark.parametrize("start, goal", EMPTY_PAIRS)
@pytest.mark.parametrize("name", ["navground-hl", "navground-hrvo", "navground-orca"])
def test_navground_reaches_the_goal_in_an_empty_room(navground, name, start, goal):
    sim = empty(start, goal)
    d = sim.distance
    res = run(name, sim, "oracle", max_steps=100)
    assert res.outcome == "success"
    # ORCA slows down within its horizon of a wall: 22 steps for 9 to a goal a step
    # from one. HL and HRVO go nearly straight.
    bound = 3 * d if name == "navground-orca" else 1.3 * d + 5
    assert res.steps <= bound


@pytest.mark.parametrize("x, y", [(12.0, 10.0), (16.0, 10.0), (12.0, 10.2), (16.0, 9.8)])
@pytest.mark.parametrize("name", ["navground-hl", "navground-hrvo", "navground-orca"])
def test_navground_dodges_a_disc_coming_head_on(navground, name, x, y):
    res = run(name, head_on(x, y), "oracle", max_steps=60)
    assert res.outcome == "success"
    assert res.min_clearance > 0.1


@pytest.mark.parametrize("y", [10.0, 10.3])
@pytest.mark.parametrize("name", ["navground-hl", "navground-hrvo", "navground-orca"])
def test_navground_never_touches_a_standing_disc(navground, name, y):
    res = run(name, head_on(10.0, y, speed=0.0), "oracle", max_steps=60)
    assert res.outcome != "collision"
    assert res.min_clearance > 0
    if name != "navground-orca":
        # ORCA stops for good in front of a disc exactly on its line (y = 10: a
        # symmetric deadlock); HL and HRVO pass it.
        assert res.outcome == "success"


@pytest.mark.parametrize("level", ["sensor", "map"])
@pytest.mark.parametrize("name", ["navground-hl", "navground-hrvo"])
def test_navground_refuses_to_run_below_oracle(navground, name, level):
    sim = empty((3, 3), (17, 15))
    message = f"{name} needs sensing level 'oracle' or above; asked to run at '{level}'"
    with pytest.raises(InvalidArgumentError, match=message):
        run_episode(make_agent(name), sim, sensing=level, max_steps=5)
    with pytest.raises(InvalidArgumentError, match=message):
        make_agent(name).reset(make_task(sim, level))


@pytest.mark.parametrize("name", ["navground-hl", "navground-hrvo"])
def test_navground_is_the_same_on_the_same_episode(navground, name):
    def once():
        return run(name, Simulator.from_world(PILLARS, seed=7), "oracle", max_steps=120)

    a, b = once(), once()
    assert (a.outcome, a.steps, a.path_length, a.min_clearance) == (
        b.outcome, b.steps, b.path_length, b.min_clearance,
    )  # fmt: skip


def test_navground_refuses_an_unknown_behaviour(navground):
    with pytest.raises(Exception, match="behavior must be one of HL, HRVO, ORCA; got 'RVO'"):
        NavgroundAgent("RVO")


def test_without_navground_its_peers_say_so_and_the_rest_still_work(monkeypatch):
    for key in [k for k in sys.modules if k == "navground" or k.startswith("navground.")]:
        monkeypatch.setitem(sys.modules, key, None)
    monkeypatch.setitem(sys.modules, "navground", None)
    monkeypatch.setitem(sys.modules, "navground.core", None)
    assert not navground_available()
    for name in ("navground-hl", "navground-hrvo", "navground-orca"):
        assert not method_spec(name).available()
        with pytest.raises(
            InvalidArgumentError,
            match=f"{name} needs navground, which is not installed: "
            "pip install 'copi\\[peers\\]'",
        ):
            make_agent(name)
    with pytest.raises(NavgroundMissingError, match="navground is not installed"):
        NavgroundAgent("HL")
    for name in ("straight", "compass-guard", "vfh", "dwa", "tangent-bug", "replan"):
        assert method_spec(name).available()
        level = "oracle" if name == "replan" else "sensor"
        res = run(name, empty((3, 3), (17, 15)), level, max_steps=40)
        assert res.outcome == "success"
