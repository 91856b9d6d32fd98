"""Re-planning on the current snapshot (level ``oracle``)."""

from __future__ import annotations

import pytest

from copi.baselines import Replan
from copi.errors import InvalidArgumentError
from copi.methods import make_agent, parse_methods
from copi.runs import make_task, run_episode
from copi.world import Simulator
from tests.baselines._support import EMPTY_PAIRS, TRAP_GOAL, empty, head_on, route_length, run
from tests.common import PILLARS, U_TRAP


@pytest.mark.parametrize("start, goal", EMPTY_PAIRS)
def test_replan_reaches_the_goal_straight_in_an_empty_room(start, goal):
    sim = empty(start, goal)
    d = sim.distance
    res = run("replan", sim, "oracle", max_steps=100)
    assert res.outcome == "success"
    assert res.steps <= 1.3 * d + 5


def test_replan_plans_out_of_the_trap():
    # Regression: the planned path touched the U's corner (10, 25) exactly; the
    # simulator stopped the agent there, the next plan started inside the configuration
    # space and failed, and the agent stood still until the timeout.
    length = route_length(U_TRAP, U_TRAP.start, TRAP_GOAL)
    sim = empty(U_TRAP.start, TRAP_GOAL, U_TRAP)
    res = run("replan", sim, "oracle", max_steps=int(1.3 * length) + 5)
    assert res.outcome == "success"
    assert sim.blocked == 0


@pytest.mark.parametrize(
    "x, y, speed",
    [
        (12.0, 10.0, 0.6), (16.0, 10.0, 0.6), (12.0, 10.2, 0.6), (16.0, 9.8, 0.6),
        # Standing discs clear of the goal (one at x = 16 would cover it).
        (10.0, 10.0, 0.0), (12.0, 10.3, 0.0),
    ],
)  # fmt: skip
def test_replan_goes_round_a_disc_in_its_way(x, y, speed):
    res = run("replan", head_on(x, y, speed=speed), "oracle", max_steps=60)
    assert res.outcome == "success"
    assert res.min_clearance > 0


@pytest.mark.parametrize("level", ["sensor", "map"])
def test_replan_refuses_to_run_below_oracle(level):
    sim = empty((3, 3), (17, 15))
    message = f"replan needs sensing level 'oracle' or above; asked to run at '{level}'"
    with pytest.raises(InvalidArgumentError, match=message):
        run_episode(make_agent("replan"), sim, sensing=level, max_steps=5)
    # Told the task directly, it refuses too (it used to accept a 'map' task and fail
    # later on an assertion, at its first step, for want of the obstacles).
    with pytest.raises(InvalidArgumentError, match=message):
        Replan().reset(make_task(sim, level))
    with pytest.raises(InvalidArgumentError, match=message):
        parse_methods(f"replan@{level}")


def test_replan_is_the_same_on_the_same_episode():
    def once():
        return run("replan", Simulator.from_world(PILLARS, seed=7), "oracle", max_steps=120)

    a, b = once(), once()
    assert (a.outcome, a.steps, a.path_length, a.min_clearance) == (
        b.outcome, b.steps, b.path_length, b.min_clearance,
    )  # fmt: skip
