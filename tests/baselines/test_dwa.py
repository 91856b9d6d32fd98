"""The Dynamic Window Approach on the range ring."""

from __future__ import annotations

from tests.baselines._support import empty, head_on, run
from tests.common import WALL


def test_dwa_never_steps_into_a_wall_with_ranges_only():
    # With the goal straight behind the wall and ranges only, DWA is held at the wall's
    # local minimum (a local method's lot); what it must not do is walk into it.
    sim = empty(WALL.start, WALL.goal, WALL)
    res = run("dwa", sim, "sensor", max_steps=300)
    assert sim.blocked == 0
    assert res.outcome != "collision"
    assert sim.position[1] > 11


def test_dwa_goes_round_the_wall_on_the_route_at_map():
    sim = empty(WALL.start, WALL.goal, WALL)
    res = run("dwa", sim, "map", max_steps=60)
    assert res.outcome == "success"
    assert sim.blocked == 0


# Found by this test: DWA measured clearance from where the agent stood, so once a disc
# came within the margin every motion tied; it collided in 3 of these 4 cases.
def test_dwa_dodges_a_disc_coming_head_on():
    cases = [(12.0, 10.0), (16.0, 10.0), (12.0, 10.2), (16.0, 9.8)]
    outcomes = [run("dwa", head_on(x, y), "sensor", max_steps=60).outcome for x, y in cases]
    assert outcomes == ["success"] * 4
