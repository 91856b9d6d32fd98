from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from copi.errors import InvalidArgumentError
from copi.learning import LearnParams, learn
from copi.reports import save_watch, watch_episode
from copi.reports._watch import frames
from copi.world import save_worlds
from tests.common import U_TRAP


@pytest.fixture(scope="module")
def caps():  # type: ignore[no-untyped-def]
    return learn(LearnParams(worlds=6, steps=150, seed=1))


def test_copi_steps_are_explained(caps) -> None:  # type: ignore[no-untyped-def]
    w = watch_episode("copi-faithful", caps, episode=1, max_steps=30)
    assert len(w.steps) == w.outcome.steps and w.n_frames == w.outcome.steps + 1
    first = w.steps[0].text
    assert first.startswith("node ") and "template" in first and "policy" in first
    assert w.steps[0].candidates.shape[1] == 2
    pics = frames(w, size=200)
    assert len(pics) == w.n_frames and pics[0].shape[1] == 200
    assert not np.array_equal(pics[0], pics[-1])


def test_copi_learnt_shows_the_direction_and_the_safety_it_chose_by() -> None:
    learnt = learn(LearnParams(worlds=6, steps=150, directions=16, safety=True, probe_worlds=8,
                               probe_steps=60, seed=1))  # fmt: skip
    w = watch_episode("copi-learnt", learnt, family="crowd", episode=2, max_steps=25)
    for step in w.steps:
        head, choice = step.text.split("\n")
        assert head.startswith("node ") and "global direction" in head and "P(safe)" in head
        assert choice.startswith("choice: ")
        assert step.candidates.shape[1] == 2 and len(step.candidates) <= 16
        if choice.startswith("choice: move"):  # the move made is the move named
            heading = float(choice.split("(")[1].split(" deg")[0])
            made = np.degrees(np.arctan2(step.action[1], step.action[0])) % 360
            assert abs((made - heading + 180) % 360 - 180) < 1.0
    scored = [s for s in w.steps if len(s.candidates)]
    assert scored and all("P(safe) 0." in s.text or "P(safe) 1." in s.text for s in scored
                          if "choice: move" in s.text)  # fmt: skip
    # the watched decisions are the agent's own: the same episode unwatched takes the same path
    from copi.methods import make_agent
    from copi.runs import draw_episode, run_episode

    sim = draw_episode("crowd", 2, 0, record=True)
    run_episode(make_agent("copi-learnt", learnt), sim, sensing="map", max_steps=25)
    np.testing.assert_allclose(np.array(sim.path), np.array(w.sim.path))


def test_baselines_say_their_name_and_the_gif_has_every_frame(tmp_path: Path) -> None:
    worlds = tmp_path / "w.json"
    save_worlds([U_TRAP], worlds)
    w = watch_episode("straight", world_file=worlds, max_steps=12)
    assert w.sim.world.name == "u-trap" and w.sensing == "map"
    assert all(s.text.startswith("straight: ") for s in w.steps)
    # the global direction it followed, on the second line (straight heads along it)
    for s in w.steps:
        line = s.text.split("\n")[1]
        assert line.startswith("global direction ")
        if "stays put" not in s.text:
            assert line.split()[-2] == s.text.split("heading ")[1].split()[0]
    gif = save_watch(w, tmp_path / "ep.gif", size=160)
    with Image.open(gif) as im:
        assert im.n_frames == w.n_frames == w.outcome.steps + 1
    png = save_watch(w, tmp_path / "last.png", size=160)
    with Image.open(png) as im:
        assert im.width == 160
    assert watch_episode("replan", max_steps=3).sensing == "oracle"


@pytest.mark.parametrize("method", ["compass-guard", "dwa", "vfh", "tangent-bug"])
def test_every_local_method_shows_its_candidates_and_the_chosen_one_scores_best(
    method: str,
) -> None:
    w = watch_episode(method, family="crowd", episode=3, max_steps=30)
    shown = 0
    for s in w.steps:
        lines = s.text.split("\n")
        assert lines[0].startswith(f"{method}: ") and lines[1].startswith("global direction ")
        assert "candidates" in lines[2] and "score = " in lines[2]
        if "; best: " in lines[2] and len(s.candidates) > 1 and np.hypot(*s.action) > 1e-9:
            # the best candidate named first is the move made (same heading)
            best = float(lines[2].split("; best: ")[1].split(" deg")[0])
            made = np.degrees(np.arctan2(s.action[1], s.action[0])) % 360
            assert abs((made - best + 180) % 360 - 180) < 1.0, (s.text, made)
            shown += 1
    assert shown, f"{method}: no step scored more than one candidate"


def _guard_admits(hits: np.ndarray, moving: np.ndarray, guard: float) -> np.ndarray:
    """Which of the 16 compass moves (full steps of 1) the guard admits, as its rule is
    written (copi.online.ContextController): after the step every moving hit at least
    ``guard`` away, the step's path passing none nearer than half of that and no hit at
    all, wall or not, nearer than 0.31 (the agent's radius and a hair; the nearest hit
    is farther than that here). Worked out here, apart from the kernels."""
    a = 2 * np.pi * np.arange(16) / 16
    admitted = np.ones(16, dtype=bool)
    for d, (ax, ay) in enumerate(zip(np.cos(a), np.sin(a), strict=True)):
        for (px, py), mover in zip(hits, moving, strict=True):
            end = math.sqrt((px - ax) ** 2 + (py - ay) ** 2)
            t = min(max(px * ax + py * ay, 0.0), 1.0)  # the path's point nearest the hit
            path = math.sqrt((px - t * ax) ** 2 + (py - t * ay) ** 2)
            if (mover and (end < guard or path < 0.5 * guard)) or path < 0.31:
                admitted[d] = False
    return admitted


def test_compass_guard_scores_are_the_kernels_own_verdicts() -> None:
    """A move the guard refuses alone is refused among all: the chosen move is the
    best-aligned one the explanation admits (or, when it admits none, an escape). On
    hand-built readings the verdicts are the guard's rule at the registered guard,
    worked out apart from the kernels: a disc ahead just inside the guard refuses the
    move toward it, one right at the guard does not, nor does a wall as near."""
    from copi.baselines import CompassGuard
    from copi.core import Observation, Task
    from copi.methods import make_agent, method_spec
    from copi.runs import draw_episode, make_task

    guard = method_spec("compass-guard").params["guard"]  # what the benchmark runs
    agent = make_agent("compass-guard")
    agent.explain = True
    agent.reset(Task("sensor", 0.3, 0.5, 32, 10.0))
    goal = np.array([20.0, 1.0])  # about +x: move 0 the best-aligned
    # the least distance ahead at which a disc's hit leaves the step along +x at least
    # the guard away (its end 1 ahead: the hit at 1 + guard, to the last bit)
    at = 1.0 + guard
    while at - 1.0 >= guard:
        at = np.nextafter(at, 0.0)
    at = np.nextafter(at, np.inf)
    cases = [(1.0 + 0.9 * guard, False, False), (np.nextafter(at, 0.0), False, False),
             (at, False, True), (1.5, True, True)]  # (distance, a wall?, +x admitted?)
    for distance, wall, ahead in cases:
        ranges = np.full(32, 10.0)
        ranges[0] = distance
        static = ranges.copy() if wall else np.full(32, np.inf)
        action = agent.act(Observation(ranges=ranges, goal=goal, static=static))
        cands, scores, _ = agent.last_candidates
        want = _guard_admits(np.array([[distance, 0.0]]), np.array([not wall]), guard)
        assert want[0] == ahead, (distance, wall)
        assert np.isfinite(scores).tolist() == want.tolist(), (distance, wall, scores)
        best = int(np.argmax(np.where(want, cands @ goal, -np.inf)))  # best-aligned admitted
        np.testing.assert_allclose(action, cands[best], atol=1e-12)

    sim = draw_episode("crowd", 5, 0)
    agent = CompassGuard()
    agent.explain = True
    agent.reset(make_task(sim, "map"))
    refused_some = False
    for _ in range(40):
        pos = sim.position.copy()
        obs = Observation(ranges=sim.ranges.copy(), goal=sim.goal - pos, position=pos,
                          static=sim.sensor.scan(sim.world, pos))  # fmt: skip
        action = agent.act(obs)
        cands, scores, _ = agent.last_candidates
        refused_some |= bool(np.isinf(scores).any())
        if np.isfinite(scores).any():
            best = cands[int(np.argmax(scores))]
            assert np.allclose(action / np.hypot(*action), best, atol=1e-9)
        res = sim.step(action)
        if res.contact or res.reached:
            break
    assert refused_some


def test_bad_inputs(caps, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(InvalidArgumentError, match="copi-faithful needs a capabilities file"):
        watch_episode("copi-faithful")
    with pytest.raises(InvalidArgumentError, match="method must be one of"):
        watch_episode("astar")
    w = watch_episode("straight", max_steps=2)
    with pytest.raises(InvalidArgumentError, match=r"must end in \.gif, \.mp4, \.png; got 'x.avi'"):
        save_watch(w, tmp_path / "x.avi")


def test_mp4_without_ffmpeg_is_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("copi.reports._watch.shutil.which", lambda _: None)
    w = watch_episode("straight", max_steps=2)
    with pytest.raises(InvalidArgumentError, match="writing .mp4 needs ffmpeg on the PATH"):
        save_watch(w, tmp_path / "x.mp4")
    assert not (tmp_path / "x.mp4").exists()
