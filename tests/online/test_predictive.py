"""copi-predictive: the learnt parts carry the decision, no hand-written guard."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest

import copi.baselines._simple
import copi.online._learnt_kernels
import copi.online.kernels
from copi.learning import Capabilities
from copi.methods import make_agent
from copi.online import PredictiveAgent
from copi.runs import draw_episode, run_episode
from copi.testing import check_agent
from tests.cli.test_faults import _one_line_error, run

GUARDED = (copi.online.kernels, copi.online._learnt_kernels, copi.baselines._simple)
"""Where copi's hand-written guard lives: the chain's kernels (its verdicts and escape),
the learnt preset's guarded decision, compass-guard."""


def test_no_guard_code_runs(predictive_caps: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every function of the guard's modules replaced by one that fails: episodes of
    copi-predictive in a crowd still run to their end."""
    caps = Capabilities.load(predictive_caps)

    def guard(*args: object, **kwargs: object) -> None:
        raise AssertionError("the hand-written guard was called")

    replaced = 0
    for module in GUARDED:
        for name, value in list(vars(module).items()):
            if callable(value) and getattr(value, "__module__", "") == module.__name__:
                monkeypatch.setattr(module, name, guard)
                replaced += 1
    assert replaced >= 10
    with pytest.raises(Exception, match="guard was called"):
        run_episode(make_agent("compass-guard"), draw_episode("crowd", 0, 1), sensing="map",
                    max_steps=50)  # the stand-ins bite  # fmt: skip
    for k, level in ((0, "map"), (1, "map"), (2, "map"), (0, "sensor"), (1, "sensor")):
        out = run_episode(PredictiveAgent(caps), draw_episode("crowd", k, 1), sensing=level,
                          max_steps=200)  # fmt: skip
        assert out.outcome in ("success", "collision", "timeout") and out.steps > 0


def test_the_same_episode_gives_the_same_moves(predictive_caps: Path) -> None:
    caps = Capabilities.load(predictive_caps)
    sim = draw_episode("crowd", 2, 1)
    a = run_episode(PredictiveAgent(caps), copy.deepcopy(sim), sensing="map", max_steps=120)
    b = run_episode(PredictiveAgent(caps), copy.deepcopy(sim), sensing="map", max_steps=120)
    assert (a.outcome, a.steps, a.path_length) == (b.outcome, b.steps, b.path_length)


def test_split_is_a_flag_and_runs(predictive_caps: Path) -> None:
    """``split`` takes True or False only (for tracked-mpc too); with it the agent runs
    an episode (what the cut arcs are: tests/learning/test_motion.py)."""
    from copi.baselines import TrackedMPC
    from copi.errors import InvalidArgumentError

    caps = Capabilities.load(predictive_caps)
    for make in (lambda v: PredictiveAgent(caps, split=v), lambda v: TrackedMPC(split=v)):
        for bad in ("yes", 1, None):
            with pytest.raises(InvalidArgumentError, match="split must be True or False"):
                make(bad)
    agent = PredictiveAgent(caps, split=True)
    out = run_episode(agent, draw_episode("crowd", 0, 1), sensing="map", max_steps=60)
    assert out.steps > 0 and agent.tracker.split


def test_it_keeps_the_agent_contract(predictive_caps: Path) -> None:
    caps = Capabilities.load(predictive_caps)
    check_agent(lambda: PredictiveAgent(caps), episodes=2)


@pytest.mark.parametrize("level", ["map", "sensor"])
def test_it_waits_rather_than_walk_into_a_body_crossing_its_way(
    predictive_caps: Path, level: str
) -> None:
    """A corridor; a body crossing it just ahead: the futures say where it will be, and the
    agent lets it pass (no contact), then goes on to the goal. At level sensor too (no
    map, no position): the bodies are told from walls by the agent's own readings."""
    from copi.world import ObstacleSpec, Simulator, World

    caps = Capabilities.load(predictive_caps)
    hall = World([[0, 0], [30, 0], [30, 12], [0, 12]], start=[3, 6], goal=[27, 6])
    outcomes = []
    for seed in range(4):
        sim = Simulator.from_world(hall, seed, obstacles=ObstacleSpec(count=(3, 3), speed=0.6))
        outcomes.append(run_episode(PredictiveAgent(caps), sim, sensing=level,
                                    max_steps=200).outcome)  # fmt: skip
    assert outcomes.count("success") >= 3, outcomes


def test_at_sensor_a_hit_where_its_rays_passed_is_what_moves(predictive_caps: Path) -> None:
    """Level sensor: a hit in cells its rays passed through before is something that
    moved there (unexplained, for the tracker); hits where rays always stopped are walls,
    neighbours joined into segments, and the walls it has learnt by seeing them again
    and again are kept as points; it places itself at minus the relative goal."""
    from copi.core import Observation
    from copi.runs import make_task
    from copi.world import Simulator, World

    caps = Capabilities.load(predictive_caps)
    agent = PredictiveAgent(caps)
    room = World([[-20, -20], [20, -20], [20, 20], [-20, 20]], start=[0, 0], goal=[10, 0])
    task = make_task(Simulator.from_world(room, 0), "sensor")
    agent.reset(task)
    n, far = task.n_rays, task.max_range
    goal = np.array([10.0, 0.0])
    ring = np.full(n, 5.0)
    ring[0] = far  # nothing along +x yet
    agent.sees(Observation(ranges=ring, goal=goal))
    now = ring.copy()
    now[0] = 3.0  # something came where the ray passed
    p, static, segs = agent.sees(Observation(ranges=now, goal=goal))
    assert np.array_equal(p, -goal)
    assert static[0] == far and np.array_equal(static[1:], now[1:])
    ends = segs.reshape(-1, 2, 2) - p
    assert np.allclose(np.hypot(*ends.reshape(-1, 2).T), 5.0)  # only the ring's hits
    assert len(segs) == (n - 2) + (n - 1)  # neighbours joined, and each hit itself
    assert len(agent._remembered(p)) == 0  # seen twice: not learnt yet
    for _ in range(25):  # the same walls, again and again: learnt, and kept as walls
        p, static, segs = agent.sees(Observation(ranges=ring, goal=goal))
    kept = agent._remembered(p)
    assert len(kept) > n and np.allclose(kept[:, :2], kept[:, 2:])  # points
    assert np.all(np.abs(np.hypot(*(kept[:, :2] - p).T) - 5.0) < 0.8)  # the ring's cells
    assert any(np.allclose(row, k) for k in kept for row in segs)  # among the walls


def test_a_small_group_of_hits_moves_together_a_wall_does_not() -> None:
    """One hit of a body fell in seen space: the body's other hits are its own; one hit
    of a long wall did (a ray grazing it before): the wall's other hits stay walls."""
    from copi.online._predictive import _whole_bodies

    n = 32
    ang = 2 * np.pi * np.arange(n) / n
    r = np.full(n, 10.0)
    r[3:6] = 4.0  # a body: three rays' hits, 0.8 apart
    r[10:26] = 5.0 / np.maximum(np.abs(np.cos(ang[10:26] - np.pi)), 0.3)  # a long wall
    hit = r < 10.0
    ends = r[:, None] * np.column_stack([np.cos(ang), np.sin(ang)])
    moved = np.zeros(n, dtype=bool)
    moved[[4, 18]] = True
    out = _whole_bodies(hit, ends, moved)
    assert out[3:6].all() and out[18] and out.sum() == 4


def test_what_it_cannot_run_on_is_one_line(
    predictive_caps: Path, learnt_caps: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = str(tmp_path / "r.sqlite")
    msg = _one_line_error(*run(["evaluate", str(predictive_caps), "--method", "tracked-mpc",
                                "--sensing", "sensor", "-o", out, "--worlds", "1"],
                               capsys)[::2])  # fmt: skip
    assert "tracked-mpc needs sensing level 'map' or above" in msg  # its peer has no sensor
    msg = _one_line_error(*run(["evaluate", str(learnt_caps), "--method", "copi-predictive",
                                "-o", out, "--worlds", "1"], capsys)[::2])  # fmt: skip
    assert "a model of what moves" in msg and "copi learn --preset predictive" in msg
    with pytest.raises(ValueError, match="no model of what moves"):
        PredictiveAgent(Capabilities.load(learnt_caps))
    assert not Path(out).exists()


def test_watch_draws_what_it_expected(predictive_caps: Path, tmp_path: Path) -> None:
    from copi.reports import save_watch, watch_episode

    caps = Capabilities.load(predictive_caps)
    watched = watch_episode("copi-predictive", caps, family="crowd", episode=1, seed=1,
                            max_steps=30)  # fmt: skip
    step = watched.steps[0]
    h = PredictiveAgent(caps).planner.horizon
    assert f"futures of {h} steps drawn from the learnt model" in step.text
    assert "expected cost (steps) of the best moves" in step.text
    assert step.futures is not None and step.futures.shape[1] == h + 1
    assert step.futures.shape[2] >= 1  # the bodies it made out
    plain = save_watch(watched, tmp_path / "ep.png")
    from PIL import Image

    pixels = np.asarray(Image.open(plain).convert("RGB")).reshape(-1, 3)
    pink = np.all(np.abs(pixels.astype(int) - (0xF2, 0xA7, 0xC3)) < 12, axis=1)
    assert pink.sum() == 0  # the last frame: the episode is over, no futures drawn
    from copi.reports._watch import _frame

    first = _frame(watched, 0, np.asarray(watched.sim.path), np.asarray(watched.sim.traces), 480)
    pink = np.all(np.abs(first.reshape(-1, 3).astype(int) - (0xF2, 0xA7, 0xC3)) < 12, axis=1)
    assert pink.sum() > 20  # the first: the futures it expected, drawn
    # at sensor it plans in the goal's frame; what is drawn is in the world's
    blind = watch_episode("copi-predictive", caps, family="crowd", episode=1, seed=1,
                          max_steps=12, sensing="sensor")  # fmt: skip
    path = np.asarray(blind.sim.path)
    seen = [(t, s.futures) for t, s in enumerate(blind.steps) if s.futures is not None
            and s.futures.shape[2]]  # fmt: skip
    assert seen
    for t, fut in seen:
        assert np.hypot(*(fut[:, 0] - path[t]).reshape(-1, 2).T).max() < 11.0


def test_many_agents_decide_at_once_as_one_by_one(predictive_caps: Path) -> None:
    """act_many (threads: the compiled kernels release the GIL) gives each agent the move
    it makes alone, whatever the number of workers."""
    from copi.runs import make_task

    caps = Capabilities.load(predictive_caps)
    sims = [draw_episode("crowd", k, 1) for k in range(4)]

    def agents() -> list[PredictiveAgent]:
        out = []
        for sim in sims:
            a = PredictiveAgent(caps)
            a.reset(make_task(sim, "map"))
            out.append(a)
        return out

    from copi.core import Observation

    obs = [Observation(ranges=s.ranges.copy(), goal=s.goal - s.position,
                       position=s.position.copy(), static=s.sensor.scan(s.world, s.position))
           for s in sims]  # fmt: skip
    alone = np.array([a.act(o) for a, o in zip(agents(), obs, strict=True)])
    for workers in (1, 2, 4):
        assert np.array_equal(PredictiveAgent.act_many(agents(), obs, workers=workers), alone)
    with pytest.raises(ValueError, match="one observation per agent"):
        PredictiveAgent.act_many(agents(), obs[:2])
