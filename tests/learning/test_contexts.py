"""Contexts that see motion (issue: capabilities that earn their keep, item 2): the
context [reading, its change], the symmetry acting on both blocks alike, the learning
chain on that space, the learnt agent recognising such contexts, and refusals."""

from __future__ import annotations

import copy
import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from copi.cli import main
from copi.core import Observation, Task
from copi.errors import CapabilitiesFormatError, InvalidArgumentError
from copi.learning import Capabilities, LearnParams, SymmetryGroup, learn, ring_operators
from copi.learning._contexts import (
    MOTION_CLIP,
    block_operators,
    motion_contexts,
    previous_in_world,
)
from copi.methods import (
    ABLATIONS,
    check_preset_capabilities,
    make_agent,
    method_spec,
    parse_methods,
)
from copi.online import ContextController, CopiAgent, LearntAgent
from copi.runs import draw_episode, run_episode


@pytest.fixture(scope="module")
def moving() -> Capabilities:
    return learn(LearnParams(worlds=6, steps=150, directions=16, safety=True, probe_worlds=8,
                             probe_steps=60, motion=True))  # fmt: skip


readings = st.lists(st.floats(0.0, 10.0), min_size=32, max_size=32).map(np.array)


@settings(max_examples=40, deadline=None)
@given(s=readings, prev=readings)
def test_a_symmetry_acts_on_the_reading_and_its_change_alike(s, prev) -> None:
    ring = SymmetryGroup.generate(ring_operators(32))
    both = SymmetryGroup.generate(block_operators(ring_operators(32), 2))
    assert len(both) == len(ring) and np.allclose(both.matrices, ring.matrices)
    x = motion_contexts(s, prev)
    for g in range(len(ring)):
        # turning the context = the context of the turned reading after the turned one
        assert np.array_equal(both.apply(g, x), motion_contexts(ring.apply(g, s), ring.apply(g, prev)))
    change = x[32:]
    assert np.all(np.abs(change) <= MOTION_CLIP)
    assert np.allclose(change, np.clip(s - prev, -MOTION_CLIP, MOTION_CLIP))


def test_the_change_is_taken_within_a_world_only() -> None:
    r = np.arange(12.0).reshape(6, 2)
    world = np.array([0, 0, 0, 1, 1, 2])
    prev = previous_in_world(r, world)
    assert np.array_equal(prev[[0, 3, 5]], r[[0, 3, 5]])  # a world's first: no change
    assert np.array_equal(prev[[1, 2, 4]], r[[0, 1, 3]])


def test_the_chain_is_learnt_on_contexts_that_see_motion(moving, tmp_path) -> None:
    n = 32
    assert moving.motion and moving.n_rays == n and moving.nodes.shape[1] == 2 * n
    assert moving.landmarks.points.shape[1] == 2 * n and moving.group.perms.shape[1] == 2 * n
    assert (moving.nodes[:, :n] >= 0).all() and (np.abs(moving.nodes[:, n:]) <= MOTION_CLIP).all()
    # every landmark maps onto its template through its element, on both blocks
    tol = moving.stats["symmetry_tolerance"]
    red, pts = moving.reduction, moving.landmarks.points
    for j in range(len(pts)):
        t = pts[red.templates[red.template_of[j]]]
        assert np.abs(moving.group.apply(int(red.element[j]), pts[j]) - t).max() <= tol + 1e-12
    # policies are learnt on the templates' reading blocks, safety priors per template
    assert moving.policies.passable.shape == (len(red.templates), 16)
    assert moving.safety.template_safe.shape == (len(red.templates), 16)
    back = Capabilities.load(moving.save(tmp_path / "m.npz"))
    assert back.equals(moving) and back.motion
    # a file claiming motion whose nodes are readings only is refused
    claimed = dataclasses.replace(moving, params={**moving.params, "motion": False})
    claimed.save(tmp_path / "bad.npz")
    with pytest.raises(CapabilitiesFormatError, match="64 components but 1 x its sensor's 32"):
        Capabilities.load(tmp_path / "bad.npz")  # 64-wide nodes that claim no motion
    tampered = dataclasses.replace(moving, nodes=moving.nodes.copy())
    tampered.nodes[0, 40] = 50.0  # a change beyond the clip
    tampered.save(tmp_path / "far.npz")
    with pytest.raises(CapabilitiesFormatError, match="changes beyond"):
        Capabilities.load(tmp_path / "far.npz")
    with pytest.raises(InvalidArgumentError, match="motion must be True or False"):
        LearnParams(motion=1)
    from copi.online import kernels

    assert kernels.MOTION_CLIP == MOTION_CLIP  # the compiled copy of the constant


def test_the_learnt_agent_recognises_the_context_with_its_motion(moving) -> None:
    agent = LearntAgent(moving, alpha=2.0, beta=0.5, wait=False)
    rng = np.random.default_rng(3)
    s = rng.uniform(0.3, 10.0, (60, 32))
    prev = s + rng.normal(0, 0.8, s.shape)
    want = rng.normal(size=(60, 2))
    actions, nodes = agent.decide_batch(s, prev, want)
    ctx = moving.contexts(s, prev)
    expected = ((ctx[:, None, :] - moving.nodes[None]) ** 2).sum(-1).argmin(1)
    assert np.array_equal(nodes, expected)
    # the same reading after another previous one may be another context
    still = ((s[:, None, :] - moving.nodes[None, :, :32]) ** 2).sum(-1).argmin(1)
    _, nodes_still = agent.decide_batch(s, s, want)
    assert np.array_equal(
        nodes_still, ((moving.contexts(s)[:, None] - moving.nodes[None]) ** 2).sum(-1).argmin(1)
    )
    del still
    # a node's own context (its reading after the reading its change implies) finds that
    # node; the same reading with no change finds another, for nodes that see motion
    r, c = moving.nodes[:, :32], moving.nodes[:, 32:]
    moved = np.flatnonzero(np.abs(c).max(1) > 0.5)
    assert len(moved)
    _, own = agent.decide_batch(r[moved], r[moved] - c[moved], want[: len(moved)])
    assert np.array_equal(own, moved)
    i = int(moved[0])
    task = Task("sensor", 0.3, 0.5, 32, 10.0)
    for prev_i, far in ((r[i] - c[i], False), (r[i], True)):
        agent.reset(task)
        agent._prev = prev_i.copy()
        agent.act(Observation(r[i], np.array([5.0, 0.0])))
        full = ((moving.contexts(r[i], prev_i) - moving.nodes) ** 2).sum(1)
        assert np.isclose(agent._out[3], full.min()) and (agent._out[3] > 0.1) == far
    # one at a time: the agent's own previous reading makes the change
    task = Task("sensor", 0.3, 0.5, 32, 10.0)
    agent.reset(task)
    for i in range(5):
        agent.act(Observation(s[i], np.array([5.0, 0.0])))
        ref = moving.contexts(s[i], s[i - 1] if i else s[i])
        node = int(((ref - moving.nodes) ** 2).sum(1).argmin())
        assert int(agent._out[2]) == node
        assert agent._context == int(moving.node_template[node])


def test_grown_contexts_see_motion_too(moving) -> None:
    agent = LearntAgent(moving, continual=True, grow_every=5, wait=False)
    agent.reset(Task("sensor", 0.3, 0.5, 32, 10.0))
    agent.threshold = 1.0
    rng = np.random.default_rng(0)
    for _ in range(30):
        agent.act(Observation(rng.uniform(0.3, 10.0, 32), np.array([5.0, 0.0])))
    assert agent.n_learnt > 0 and agent._nodes.shape[1] == 64
    grown = agent._nodes[len(moving.nodes) :]
    assert (np.abs(grown[:, 32:]).max(1) > 0.1).all()  # grown from readings with their change


def test_the_chain_and_the_presets_refuse_what_does_not_fit(moving, tmp_path, capsys) -> None:
    with pytest.raises(InvalidArgumentError, match="contexts that see motion"):
        ContextController(moving)
    with pytest.raises(InvalidArgumentError, match="contexts that see motion"):
        CopiAgent(moving, guard=1.2)
    with pytest.raises(InvalidArgumentError, match=(
        r"was learnt for preset learnt-motion \(16 directions, safety priors, contexts that see "
        r"motion\); preset learnt needs 16 directions, safety priors: learn it with copi learn "
        r"--preset learnt, or run it with --preset learnt-motion"
    )):  # fmt: skip
        check_preset_capabilities("learnt", moving)
    still = dataclasses.replace(moving, params={**moving.params, "motion": False})
    with pytest.raises(InvalidArgumentError, match="was learnt for preset learnt "):
        check_preset_capabilities("learnt-motion", still)
    check_preset_capabilities("learnt-motion", moving)
    path = moving.save(tmp_path / "m.npz")
    for args in (
        ["learn", "-o", str(tmp_path / "x.npz"), "--preset", "extended", "--motion"],
        ["learn", "-o", str(tmp_path / "x.npz"), "--motion"],
        ["evaluate", str(path), "-o", str(tmp_path / "r.sqlite"), "--method", "copi-learnt",
         "--worlds", "1"],
        ["evaluate", str(path), "-o", str(tmp_path / "r.sqlite"), "--preset", "extended",
         "--worlds", "1"],
        ["pursuit", str(path), "-o", str(tmp_path / "g.sqlite"), "--preset", "learnt-motion",
         "--games", "1"],
    ):  # fmt: skip
        with pytest.raises(SystemExit) as exit_:
            main(args)
        err = capsys.readouterr().err
        assert exit_.value.code == 2, (args, err)
        assert "Traceback" not in err and err.count("copi: error:") == 1, err
    assert not (tmp_path / "x.npz").exists() and not (tmp_path / "r.sqlite").exists()


def test_the_ablations_are_named_and_run(moving, tmp_path) -> None:
    chosen = parse_methods("ablations")
    names = [r.method for r in chosen]
    assert set(names) == set(ABLATIONS) and {r.sensing for r in chosen} == {"map", "sensor"}
    assert "copi-learnt-motion" not in [r.method for r in parse_methods(None)]
    still = learn(LearnParams(worlds=6, steps=150, directions=16, safety=True, probe_worlds=8,
                              probe_steps=60))  # fmt: skip
    base = draw_episode("crowd", 0, 3)
    runs = {}
    for name in ABLATIONS:
        spec = method_spec(name)
        caps = {"learnt": still, "learnt-motion": moving}.get(spec.capabilities or "")
        agent = make_agent(name, caps)
        sim = copy.deepcopy(base)
        res = run_episode(agent, sim, sensing="map", max_steps=120)
        runs[name] = (res.outcome, res.steps, round(res.path_length, 9))
    assert isinstance(make_agent("copi-learnt-motion", moving), LearntAgent)
    assert make_agent("copi-learnt-priors", still).beta > 0
    assert make_agent("copi-learnt-persist", still).persist > 0
    # each ablation differs from copi-learnt in what its name says and in nothing else
    base_spec = method_spec("copi-learnt")
    differs = {
        name: {k for k in set(method_spec(name).params) | set(base_spec.params)
               if method_spec(name).params.get(k) != base_spec.params.get(k)}
        | ({"capabilities"} if method_spec(name).capabilities != base_spec.capabilities else set())
        for name in ABLATIONS
    }  # fmt: skip
    assert differs["copi-learnt"] == set()
    assert differs["copi-learnt-priors"] == {"beta"}
    assert differs["copi-learnt-persist"] == {"persist"}
    assert differs["copi-learnt-motion"] == {"beta", "capabilities"}
    assert set(runs) == set(ABLATIONS)
    # in the benchmark, on the same episodes, paired against copi-learnt
    from copi.experiments.benchmark import BenchmarkConfig, run_benchmark
    from copi.reports import write_benchmark_report

    caps = {"learnt": str(still.save(tmp_path / "l.npz")),
            "learnt-motion": str(moving.save(tmp_path / "m.npz"))}  # fmt: skip
    methods = tuple(parse_methods("copi-learnt@map,copi-learnt-motion@map,compass-guard@map"))
    cfg = BenchmarkConfig(methods=methods, families=("star",), episodes=3, capabilities=caps)
    run_benchmark(cfg, tmp_path / "a.sqlite", workers=1)
    text = write_benchmark_report(tmp_path / "a.sqlite", tmp_path / "rep").read_text()
    assert "**Reference: copi-learnt** (the default)" in text
    assert "| copi-learnt-motion | map | route | 3 |" in text
    assert "| compass-guard | map | route | 3 |" in text
    # each row is its method's own run on that episode: the same agent (its registered
    # parameters, its preset's capabilities) run directly on episode k of the family
    # within the episode's step limit ends the same way, in as many steps, as far
    from copi.results import ResultsStore
    from copi.runs import optimal_to_goal, step_limit

    with ResultsStore(tmp_path / "a.sqlite", readonly=True) as store:
        rows = store.episodes()
    assert sorted((r.method, r.episode) for r in rows) == sorted(
        (m.method, k) for m in methods for k in range(3))
    learnt = {"learnt": still, "learnt-motion": moving}
    for r in rows:
        sim = draw_episode("star", r.episode, cfg.seed)
        limit = step_limit(optimal_to_goal(sim))
        agent = make_agent(r.method, learnt.get(method_spec(r.method).capabilities or ""))
        direct = run_episode(agent, sim, sensing="map", max_steps=limit)
        assert (r.family, r.sensing, r.outcome, r.steps) == ("star", "map", direct.outcome,
                                                             direct.steps), r  # fmt: skip
        assert r.path_length == pytest.approx(direct.path_length, abs=1e-9), r


def test_contexts_of_another_shape_than_the_sensor_gives_are_refused(moving, tmp_path, capsys):
    # a 64-component context is a 32-ray sensor's reading and change: accepted for 32 rays
    LearntAgent(moving).reset(Task("sensor", 0.3, 0.5, 32, 10.0))
    with pytest.raises(InvalidArgumentError, match="learnt for 32 rays; the sensor has 64"):
        LearntAgent(moving).reset(Task("sensor", 0.3, 0.5, 64, 10.0))
    narrow = learn(LearnParams(worlds=2, steps=50, directions=16, safety=True, probe_worlds=2,
                               probe_steps=20, n_rays=16))  # fmt: skip
    path = narrow.save(tmp_path / "n16.npz")
    with pytest.raises(SystemExit) as exit_:
        main(["lifelong", str(path), "-o", str(tmp_path / "l.sqlite"), "--worlds", "1",
              "--tasks", "2"])  # fmt: skip
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and "learnt for 16 rays; the sensor has 32" in err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "l.sqlite").exists()
