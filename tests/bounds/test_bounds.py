"""The ceilings: the clairvoyant bound and the model-predictive oracle."""

from __future__ import annotations

import copy
import math

import networkx as nx
import numpy as np
import pytest
from scipy import stats

from copi.baselines import CompassGuard, Straight
from copi.bounds import TURN_SD, Clairvoyant, GoalField, ModelOracle
from copi.bounds._kernels import sample_futures
from copi.core import check_sensing
from copi.errors import InvalidArgumentError
from copi.geometry import clearance
from copi.methods import method_spec
from copi.planning.futures import OFFSETS as _OFFSETS
from copi.planning.futures import hindsight_values
from copi.runs import draw_episode, make_task, obstacle_future, run_episode
from copi.world import ObstacleSpec, Simulator, World


def test_future_is_a_level_above_oracle_and_only_it_tells_the_future() -> None:
    assert check_sensing("future", "oracle") == 3
    sim = draw_episode("crowd", 0, 0)
    assert make_task(sim, "oracle").future is None
    task = make_task(sim, "future", max_steps=40)
    assert task.future is not None and task.future.shape == (41, len(sim.radii), 3)
    np.testing.assert_array_equal(task.future[0, :, :2], sim.centers)
    np.testing.assert_array_equal(task.future[:, :, 2], np.broadcast_to(sim.radii, (41, len(sim.radii))))
    assert method_spec("clairvoyant").bound  # solves every episode of every family
    # a reference planner, not a bound: methods that know less match it in most families
    assert not method_spec("model-oracle").bound and not method_spec("dwa").bound
    with pytest.raises(InvalidArgumentError, match="clairvoyant needs sensing level 'future'"):
        run_episode(Clairvoyant(), copy.deepcopy(sim), sensing="oracle", max_steps=10)


@pytest.mark.parametrize("family", ["crowd", "indoor"])
def test_the_discs_future_does_not_depend_on_the_agent(family: str) -> None:
    """Same episode, agents that move differently: the same disc traces, step for step,
    and the same as the future recorded with the agent standing still."""
    base = draw_episode(family, 3, 0)
    base.record = True
    future = obstacle_future(base, 60)
    traces = []
    for agent in (Straight(), CompassGuard()):
        sim = copy.deepcopy(base)
        out = run_episode(agent, sim, sensing="map", max_steps=60, end_on_contact=False)
        assert out.steps > 5
        traces.append(np.array(sim.traces))
    t = min(len(x) for x in traces)
    np.testing.assert_array_equal(traces[0][:t], traces[1][:t])
    # traces recorded from the first step on (``record`` set after the start)
    np.testing.assert_array_equal(traces[0][:t], future[1 : t + 1, :, :2])


@pytest.mark.parametrize(("family", "k"), [("crowd", 0), ("crowd", 5), ("crowd", 11),
                                           ("indoor", 2), ("maps", 4), ("polygon", 7)])
def test_the_clairvoyant_plan_replays_contact_free(family: str, k: int) -> None:
    sim = draw_episode(family, k, 0)
    sim.record = True
    out = run_episode(Clairvoyant(), sim, sensing="future", max_steps=300)
    assert out.outcome == "success" and out.contacts == 0 and out.min_clearance >= 0.0
    assert out.counters["planned"] == 1
    # replayed exactly: the agent's path stays clear of every disc at every step
    path = np.array(sim.path)
    traces = np.array(sim.traces)
    gaps = np.linalg.norm(traces - path[:, None, :], axis=2) - sim.radii - sim.agent_radius
    assert gaps.min() >= 0.0
    assert clearance(path, sim.world.segments).min() >= sim.agent_radius - 1e-9


def _corridor(disc_x: float, heading: float, speed: float, width: float = 4.0) -> Simulator:
    """A corridor ``width`` wide and 30 long; the agent at x = 2, the goal at x = 28; one
    disc of radius 0.9 in the middle (1.1 free on either side of it at width 4)."""
    h = width / 2
    w = World([[0, 0], [30, 0], [30, width], [0, width]], start=[2, h], goal=[28, h])
    sim = Simulator(w, [2, h], [28, h], [[disc_x, h]], [0.9], seed=0, speed=speed,
                    turn_sd=0.0)
    sim.headings[:] = heading
    return sim


def test_the_clairvoyant_waits_for_a_disc_that_blocks_the_way() -> None:
    """A disc parked in a corridor 3 wide (nothing passes it) that leaves after a while:
    the clairvoyant waits and then goes; a disc that never leaves makes it unsolvable."""
    # the disc walks along the corridor away from the agent at 0.6 a step (the corridor is
    # long enough that it does not come back before the agent is home)
    w = World([[0, 0], [60, 0], [60, 2.4], [0, 2.4]], start=[2, 1.2], goal=[28, 1.2])
    away = Simulator(w, [2, 1.2], [28, 1.2], [[6.0, 1.2]], [1.0], seed=0, speed=0.6,
                     turn_sd=0.0)  # fmt: skip
    away.headings[:] = 0.0
    out = run_episode(Clairvoyant(), away, sensing="future", max_steps=200)
    assert out.outcome == "success" and out.min_clearance >= 0
    assert out.steps > (28 - 2 - 0.5) / 1.0 + 5  # held back by the disc
    parked = Simulator(w, [2, 1.2], [28, 1.2], [[6.0, 1.2]], [1.0], seed=0, speed=0.0)
    agent = Clairvoyant()
    out = run_episode(agent, parked, sensing="future", max_steps=60)
    assert out.outcome == "timeout" and agent.counters() == {"planned": 0, "nodes":
                                                             agent.counters()["nodes"], "budget": 0}


def test_the_goal_field_is_the_distance_around_walls() -> None:
    # a wall from (5, 0) to (5, 8) in a 10 x 10 room: from (2, 1) to (8, 1) around its end
    room = World([[0, 0], [4.9, 0], [4.9, 8], [5.1, 8], [5.1, 0], [10, 0], [10, 10],
                  [0, 10]])  # fmt: skip
    f = GoalField(room, np.array([8.0, 1.0]), 0.3)
    around = 2 * math.hypot(3.0, 7.3)  # two straight legs past the wall's end (5, 8.3)
    # the grid is 8-connected: a leg (dx, dy), dx < dy, is at best dy + (sqrt 2 - 1) dx
    # long on it (8 % more here), plus a cell or two where the legs meet the grid
    octile = 2 * (7.3 + (math.sqrt(2.0) - 1.0) * 3.0)
    assert around * 0.97 <= f.at(2.0, 1.0) <= octile + 2 * 0.25
    assert f.at(8.0, 3.0) == pytest.approx(2.0, abs=0.2)


def test_the_motion_model_is_the_simulators() -> None:
    """The oracle's sampled futures and the simulator's own, from one state: the same
    distribution of positions after 1 and 3 steps (two-sample KS tests), in open space and
    against a wall (where both turn discs away by the same rule)."""
    w = World([[0, 0], [40, 0], [40, 40], [0, 40]])
    for start, heading in (([20.0, 20.0], 0.7), ([39.0, 20.0], 0.0)):
        sim = Simulator(w, [2, 2], [30, 30], [start], [0.8], seed=0, speed=0.8)
        sim.headings[:] = heading
        obst = np.array([[*start, 0.8 * math.cos(heading), 0.8 * math.sin(heading), 0.8]])
        o = ModelOracle()
        o.reset(make_task(sim, "oracle"))
        mine = sample_futures(obst, o.segs, 2000, 3, TURN_SD, 4, 7, o.clear, o.field.x0,
                              o.field.y0, o.fine, 0.0)  # fmt: skip
        theirs = np.empty((2000, 3, 2))
        for s in range(2000):
            twin = copy.deepcopy(sim)
            twin.rng = np.random.default_rng(s)
            for t in range(3):
                twin.step(np.zeros(2))
                theirs[s, t] = twin.centers[0]
        for t in (0, 2):
            for axis in (0, 1):
                p = stats.ks_2samp(mine[:, t + 1, 0, axis], theirs[:, t, axis]).pvalue
                assert p > 1e-3, (start, t, axis, p)


def test_the_model_oracle_dodges_a_disc_coming_at_it() -> None:
    """In a corridor 5 wide, a disc of radius 0.9 comes straight at the agent at 0.8 a step
    (no turning): walking straight meets it; the oracle's model says so and it gives way.
    (At width 4, with 0.5 to spare beside the disc, the model's turning of 0.6 rad a step
    makes passing too risky for it: it backs off and follows the disc, and does not pass
    it within 80 steps.)"""
    straight = run_episode(Straight(), _corridor(12.0, math.pi, 0.8, 5.0), sensing="oracle",
                           max_steps=80)  # fmt: skip
    assert straight.outcome == "collision"
    # there is room to pass at the side (2.5 - 0.9 - 2 * 0.3 = 1.0 to spare)
    oracle = run_episode(ModelOracle(), _corridor(12.0, math.pi, 0.8, 5.0), sensing="oracle",
                         max_steps=80)  # fmt: skip
    assert oracle.outcome == "success" and oracle.contacts == 0, oracle


@pytest.mark.parametrize("width", [5.0, 4.0])
def test_the_greedy_oracle_dodges_by_its_two_step_check_alone(width: float) -> None:
    """plan="greedy" plans nothing through the discs' futures: only the first move's
    check (in contact, or no second move clear) keeps it off the disc coming at it; it
    gives way in the corridors 5 and 4 wide and reaches the goal without contact."""
    out = run_episode(ModelOracle(plan="greedy"), _corridor(12.0, math.pi, 0.8, width),
                      sensing="oracle", max_steps=80)  # fmt: skip
    assert out.outcome == "success" and out.contacts == 0, out


def test_the_greedy_oracle_goes_straight_where_nothing_moves_near() -> None:
    """With the only disc far behind it, the greedy plan's value is the distance to go: a
    full step along the corridor each step, home in the least number of steps."""
    sim = _corridor(0.5, math.pi, 0.0, 5.0)  # a disc parked behind the start
    out = run_episode(ModelOracle(plan="greedy"), sim, sensing="oracle", max_steps=80)
    assert out.outcome == "success"
    assert out.steps == math.ceil(28 - 2 - sim.goal_tolerance)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"samples": 0}, "samples must be a whole number in 1 .. 256"),
     ({"horizon": 1}, "horizon must be a whole number in 2 .. 40"),
     ({"risk": math.nan}, "risk must be a number in [0, 10000]"),
     ({"discount": 0.0}, "discount must be a number in (0, 1]"),
     ({"plan": "median"}, "plan must be one of hindsight, mean, greedy; got 'median'"),
     ({"escape": -1.0}, "escape must be a number in [0, 10000]")],
)  # fmt: skip
def test_model_oracle_parameters_are_checked(kwargs: dict, message: str) -> None:
    with pytest.raises(InvalidArgumentError, match=message.replace("[", r"\[").replace(
            "(", r"\(").replace(")", r"\)").replace(".", r"\.")):  # fmt: skip
        ModelOracle(**kwargs)


def test_clairvoyant_parameters_are_checked() -> None:
    with pytest.raises(InvalidArgumentError, match="weight must be a finite number >= 1"):
        Clairvoyant(weight=0.5)
    with pytest.raises(InvalidArgumentError, match="max_nodes must be a whole number"):
        Clairvoyant(max_nodes=0)


def test_obstacles_are_static_when_spec_says_so() -> None:
    # a world with no moving obstacle: the clairvoyant is a static planner
    room = World([[0, 0], [20, 0], [20, 20], [0, 20]], start=[2, 2], goal=[18, 18])
    sim = Simulator.from_world(room, 0, obstacles=ObstacleSpec(count=(0, 0)))
    out = run_episode(Clairvoyant(), sim, sensing="future", max_steps=100)
    assert out.outcome == "success" and out.steps <= math.ceil((16 * math.sqrt(2) - 0.5) * 1.09)


def _hindsight_by_graph(samples, radii, agent_r, margin, res, ok, terminal, goal, offsets,
                        mid_ok, cap):  # type: ignore[no-untyped-def]
    """The hindsight value written independently: per sample, Dijkstra (networkx) on the
    time-expanded graph of the window, from every cell at step 1 to a sink reached at
    the horizon (cost ``terminal``) or at a goal cell (cost 0)."""
    n = ok.shape[0]
    horizon = samples.shape[1] - 1
    ii, jj = np.mgrid[0:n, 0:n]
    total = np.zeros((n, n))
    for s in range(samples.shape[0]):
        blocked = np.zeros((horizon + 1, n, n), dtype=bool)
        for t in range(1, horizon + 1):
            for k, rk in enumerate(radii):
                d = np.hypot(res * jj - samples[s, t, k, 0], res * ii - samples[s, t, k, 1])
                blocked[t] |= d <= agent_r + rk + margin
        g = nx.DiGraph()
        for t in range(1, horizon + 1):
            for i in range(n):
                for j in range(n):
                    if blocked[t, i, j]:
                        continue
                    if t == horizon:
                        if np.isfinite(terminal[i, j]):
                            g.add_edge((t, i, j), "sink", weight=terminal[i, j])
                        continue
                    if not ok[i, j]:
                        continue
                    if goal[i, j]:
                        g.add_edge((t, i, j), "sink", weight=0.0)
                        continue
                    for o, (di, dj) in enumerate(offsets):
                        a, b = i + di, j + dj
                        if 0 <= a < n and 0 <= b < n and mid_ok[o, i, j]:
                            g.add_edge((t, i, j), (t + 1, a, b), weight=1.0)
        dist = nx.single_source_dijkstra_path_length(g.reverse(), "sink")
        for i in range(n):
            for j in range(n):
                total[i, j] += min(dist.get((1, i, j), math.inf), cap)
    return np.where(ok, total / samples.shape[0], math.inf)


@pytest.mark.parametrize(("seed", "n_samples"), [(0, 4), (1, 4), (2, 4), (3, 20), (4, 33)])
def test_hindsight_values_equal_a_shortest_path_per_sampled_future(seed: int,
                                                                    n_samples: int) -> None:  # fmt: skip
    """The model-oracle's planner (hindsight optimisation) against networkx's Dijkstra on
    each sample's time-expanded grid: the same mean cost to go, walls, goal cells, cells
    no way leaves (the cap) and all, on random windows with discs drifting through (as
    many samples as the kernel solves at once, fewer, and more: a last batch part full)."""
    rng = np.random.default_rng(seed)
    n, horizon, res = 9, 5, 0.5
    ok = rng.random((n, n)) > 0.15
    offsets = _OFFSETS
    mid_ok = rng.random((len(offsets), n, n)) > 0.1
    mid_ok[0] = True
    terminal = np.where(ok, rng.uniform(0, 6, (n, n)), math.inf)
    goal = np.zeros((n, n), dtype=bool)
    goal[rng.integers(n), rng.integers(n)] = True
    terminal[goal] = 0.0
    start = rng.uniform(0, res * (n - 1), (1, 1, 3, 2))
    drift = rng.normal(0, 0.4, (n_samples, horizon + 1, 3, 2)).cumsum(axis=1)
    samples = np.ascontiguousarray(start + drift)
    radii = np.array([0.3, 0.5, 0.2])
    cap = 40.0
    got = hindsight_values(samples, radii, 0.3, 0.1, 0.0, 0.0, res, ok, terminal, goal,
                           offsets, mid_ok, cap)[1]  # fmt: skip
    want = _hindsight_by_graph(samples, radii, 0.3, 0.1, res, ok, terminal, goal, offsets,
                               mid_ok, cap)  # fmt: skip
    np.testing.assert_allclose(got, want)
    # the cases the test is for are all there: a capped sample, a goal reached early
    assert np.any((want > cap / 4) & np.isfinite(want)) and np.any(want < horizon - 1)
    # solving only where an agent from the centre can be: the same values there (cells
    # within box + 2 of the centre at step 1), nothing elsewhere
    for box in (0, 1):
        part = hindsight_values(samples, radii, 0.3, 0.1, 0.0, 0.0, res, ok, terminal, goal,
                                offsets, mid_ok, cap, box)[1]  # fmt: skip
        c, r = n // 2, box + 2
        inner = np.zeros((n, n), dtype=bool)
        inner[c - r : c + r + 1, c - r : c + r + 1] = True
        np.testing.assert_array_equal(part[inner], got[inner])
        assert not np.isfinite(part[~inner]).any()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_hindsight_values_solved_where_the_agent_can_be_are_the_whole_windows(seed: int) -> None:
    """On a window as large as the planner's far ahead (41 cells, 14 steps), the values
    solved only on the octagon step 1's square depends on (``box`` 2) are the whole
    window's bit for bit, with walls, goals and discs crossing the octagon's edges (an
    octagon cut one cell too small reads values never solved, and fails)."""
    rng = np.random.default_rng(seed)
    n, horizon, res = 41, 14, 0.5
    ok = rng.random((n, n)) > 0.1
    mid_ok = rng.random((len(_OFFSETS), n, n)) > 0.05
    mid_ok[0] = True
    terminal = np.where(ok, rng.uniform(0, 15, (n, n)), math.inf)
    goal = np.zeros((n, n), dtype=bool)
    goal[rng.integers(n, size=3), rng.integers(n, size=3)] = True
    terminal[goal] = 0.0
    start = rng.uniform(0, res * (n - 1), (1, 1, 12, 2))
    samples = np.ascontiguousarray(start + rng.normal(0, 0.5, (20, horizon + 1, 12, 2))
                                   .cumsum(axis=1))  # fmt: skip
    radii = rng.uniform(0.3, 0.8, 12)
    whole = hindsight_values(samples, radii, 0.3, 0.1, 0.0, 0.0, res, ok, terminal, goal,
                             _OFFSETS, mid_ok, 60.0)[1]  # fmt: skip
    part = hindsight_values(samples, radii, 0.3, 0.1, 0.0, 0.0, res, ok, terminal, goal,
                            _OFFSETS, mid_ok, 60.0, 2)[1]  # fmt: skip
    c = n // 2
    np.testing.assert_array_equal(part[c - 4 : c + 5, c - 4 : c + 5],
                                  whole[c - 4 : c + 5, c - 4 : c + 5])  # fmt: skip


def test_hindsight_values_with_no_disc_solve_one_future_and_count_it_for_all() -> None:
    """With no disc every sampled future is the same: the kernel solves one and counts it
    for each; the values are networkx's, and bit for bit those of the same futures with a
    disc far off the window (which the kernel solves one by one)."""
    rng = np.random.default_rng(7)
    n, horizon, res = 9, 5, 0.5
    ok = rng.random((n, n)) > 0.15
    mid_ok = rng.random((len(_OFFSETS), n, n)) > 0.1
    terminal = np.where(ok, rng.uniform(0, 6, (n, n)), math.inf)
    goal = np.zeros((n, n), dtype=bool)
    goal[1, 2] = True
    terminal[goal] = 0.0
    none = np.zeros((33, horizon + 1, 0, 2))
    got = hindsight_values(none, np.zeros(0), 0.3, 0.1, 0.0, 0.0, res, ok, terminal, goal,
                           _OFFSETS, mid_ok, 40.0)[1]  # fmt: skip
    want = _hindsight_by_graph(none[:2], np.zeros(0), 0.3, 0.1, res, ok, terminal, goal,
                               _OFFSETS, mid_ok, 40.0)  # fmt: skip
    np.testing.assert_allclose(got, want)
    far = np.full((33, horizon + 1, 1, 2), 1e3)
    alike = hindsight_values(far, np.array([0.5]), 0.3, 0.1, 0.0, 0.0, res, ok, terminal,
                             goal, _OFFSETS, mid_ok, 40.0)[1]  # fmt: skip
    np.testing.assert_array_equal(got, alike)


def test_hindsight_values_of_a_known_corridor() -> None:
    """A corridor one cell wide, moves of one cell forward or waiting, the goal two cells
    ahead. In one sampled future the corridor is free (the goal in 2 steps); in the other
    a disc stands on the next cell, then grows over the agent's cell too, so that no way
    is left (the cap). The cost to go is the mean of the two."""
    n, res = 5, 0.5
    ok = np.zeros((n, n), dtype=bool)
    ok[2, :] = True
    goal = np.zeros((n, n), dtype=bool)
    goal[2, 4] = True
    terminal = np.where(ok, 0.5 * (4 - np.arange(n))[None, :], math.inf)
    mid_ok = np.zeros((len(_OFFSETS), n, n), dtype=bool)
    for o, (di, dj) in enumerate(_OFFSETS):
        mid_ok[o, 2, :] = di == 0 and dj in (0, 1)
    samples = np.full((2, 5, 1, 2), -9.0)
    samples[0, 1:3, 0] = [1.5, 1.0]  # on cell (2, 3) at steps 1, 2
    samples[0, 3:, 0] = [1.25, 1.0]  # over cells (2, 2) and (2, 3) from step 3
    v = hindsight_values(samples, np.array([0.2]), 0.1, 0.0, 0.0, 0.0, res, ok, terminal,
                         goal, _OFFSETS, mid_ok, 100.0)[1]  # fmt: skip
    assert v[2, 2] == pytest.approx((100.0 + 2.0) / 2)
    assert v[2, 4] == 0.0 and not np.isfinite(v[0, 0])
