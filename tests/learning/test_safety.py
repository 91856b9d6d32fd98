"""Learnt safety priors (issue: capabilities that earn their keep): the compiled network
against numpy, its equivariance under the ring's rotations, template priors through the
symmetry, files, and the learnt agent's ablation (nothing learnt = compass-guard)."""

from __future__ import annotations

import copy
import dataclasses
import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from copi.baselines import CompassGuard
from copi.errors import CapabilitiesFormatError, InvalidArgumentError
from copi.learning import Capabilities, LearnParams, learn, simulated_steps
from copi.learning._safety import (
    SafetyModel,
    predict,
    probe_actions,
    probe_states,
    second_move_clear,
    template_priors,
)
from copi.learning._symmetry import SymmetryGroup, ring_operators
from copi.learning.kernels import (
    kernel_net,
    ring_features,
    safety_features,
    safety_of,
    safety_probabilities,
)
from copi.online import LearntAgent
from copi.runs import draw_episode, run_episode
from copi.world import Simulator, World


@pytest.fixture(scope="module")
def learnt() -> Capabilities:
    return learn(LearnParams(worlds=6, steps=150, directions=16, safety=True, probe_worlds=8,
                             probe_steps=60))  # fmt: skip


def _net(seed: int, hidden: int = 5, rays: int = 32) -> np.ndarray:
    return np.random.default_rng(seed).normal(0, 0.3, (2, hidden + 1, 1 + 4 * rays))


def _probs(
    s: np.ndarray, prev: np.ndarray, net: np.ndarray, n_dir: int = 16, static: np.ndarray | None = None
) -> np.ndarray:
    out = np.empty(n_dir + 1)
    st_ = np.full(len(s), np.inf) if static is None else static
    safety_probabilities(s, prev, st_, kernel_net(net), n_dir, np.empty(8 * len(s)), out)
    return out


readings = st.lists(st.floats(0.0, 10.0), min_size=32, max_size=32).map(np.array)


# ranges that repeat (the sensor's reach, a flat wall) and readings that did not change
runs = st.lists(st.sampled_from([0.5, 2.0, 10.0, 0.0, -0.0]) | st.floats(0.0, 10.0),
                min_size=32, max_size=32).map(np.array)  # fmt: skip


@settings(max_examples=60, deadline=None)
@given(s=runs, prev=runs, same=st.booleans(), shift=st.integers(0, 31),
       walls=st.lists(st.sampled_from([0.0, 0.04, 0.05, 0.06, 1.0, np.inf]), min_size=32,
                      max_size=32).map(np.array))  # fmt: skip
def test_ring_features_equal_the_training_features_bitwise(s, prev, same, shift, walls) -> None:
    """What the kernels evaluate online (each block a ray at a time, exponentials
    skipped where they are not needed) is, to the last bit, what the network was
    trained on; with and without a static reading (here the reading plus 0 to 0.06, 1
    or inf: the hit explained by the static map, just not, or unknown)."""
    prev = s.copy() if same else prev
    n = 32
    for static in (None, s + walls):
        feat = np.empty(8 * n)
        ring_features(s, prev, np.full(n, np.inf) if static is None else static, feat)
        turned = np.concatenate([feat[2 * b * n + shift : 2 * b * n + shift + n] for b in range(4)])
        want = safety_features(s, prev, shift, static=static)
        assert turned.tobytes() == want.tobytes()


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 1000), rays=st.sampled_from([8, 12, 32, 36]),
       hidden=st.sampled_from([1, 5, 16]), shift=st.integers(0, 35),
       zeros=st.floats(0.0, 0.9))  # fmt: skip
def test_the_compiled_network_adds_in_the_order_written(seed, rays, hidden, shift, zeros) -> None:
    """Each hidden unit's sum, bit for bit, is the bias plus every feature's product in
    turn (block by block, ray by ray), as plain Python floats add them: the kernel's
    eight-at-a-time loop and its leftover rays change no rounding (rings of 8, 12, 32
    and 36 rays; a share of the features exactly 0)."""
    rng = np.random.default_rng(seed)
    net = kernel_net(rng.normal(0, 0.3, (2, hidden + 1, 1 + 4 * rays)))
    feat = rng.normal(0, 1, 8 * rays)
    feat[rng.random(8 * rays) < zeros] = 0.0
    shift %= rays
    for k in (0, 1):
        w = net[k]
        z = [float(w[0, u]) for u in range(hidden)]
        for b in range(4):
            for j in range(rays):
                f = float(feat[2 * b * rays + shift + j])
                for u in range(hidden):
                    z[u] += float(w[1 + b * rays + j, u]) * f
        z2 = float(w[4 * rays + 2, 0])
        for u in range(hidden):
            if z[u] > 0.0:
                z2 += float(w[4 * rays + 1, u]) * z[u]
        assert safety_of(net, k, shift, feat, rays) == 1.0 / (1.0 + math.exp(-z2))


def test_the_closeness_block_sees_what_the_static_map_does_not_explain() -> None:
    """A hit at 1 on ray 3: without a map it is close; with a map showing a wall there
    it is the wall's (0); with a map showing the wall at 4 it is something that moves."""
    s = np.full(32, 10.0)
    s[3] = 1.0
    block = slice(2 * 32, 3 * 32)
    unknown = safety_features(s, s, 0)[block]
    wall = safety_features(s, s, 0, static=s)[block]
    far = s.copy()
    far[3] = 4.0
    disc = safety_features(s, s, 0, static=far)[block]
    assert unknown[3] == disc[3] == math.exp(-1.0) and wall[3] == 0.0
    assert np.all(np.delete(wall, 3) == 0.0) and np.all(np.delete(disc, 3) == 0.0)


@settings(max_examples=30, deadline=None)
@given(s=readings, prev=readings, static=readings, seed=st.integers(0, 100),
       k=st.integers(0, 15))  # fmt: skip
def test_the_network_is_one_model_turned_to_each_direction(s, prev, static, seed, k) -> None:
    net = _net(seed)
    p = _probs(s, prev, net, static=static)
    ref = [predict(net[0], safety_features(s, prev, 2 * d, static=static)[None])[0]
           for d in range(16)]  # fmt: skip
    assert np.allclose(p[:16], ref, atol=1e-9)
    assert np.isclose(p[16], predict(net[1], safety_features(s, prev, 0, static=static)[None])[0])
    # the reading turned by k directions: direction d + k now is what d was
    turned = _probs(np.roll(s, 2 * k), np.roll(prev, 2 * k), net, static=np.roll(static, 2 * k))
    assert np.allclose(turned[(np.arange(16) + k) % 16], p[:16], atol=1e-9)


def test_template_priors_read_through_the_symmetry_equal_priors_probed_in_a_turned_world() -> None:
    group = SymmetryGroup.generate(ring_operators(32))
    rng = np.random.default_rng(0)
    m, n_dir = 400, 16
    template = rng.integers(0, 3, m)
    element = rng.integers(0, len(group), m)
    safe = rng.random((m, n_dir)) < 0.7
    table, counts = template_priors(template, group.matrices[element], safe, 3)
    a = 2 * np.pi * np.arange(n_dir) / n_dir
    dirs = np.column_stack([np.cos(a), np.sin(a)])
    for r in range(len(group)):  # turn (or mirror) the whole world by group element r
        rot = group.matrices[r]
        moved = np.argmax((dirs @ rot.T) @ dirs.T, axis=1)  # direction d goes to moved[d]
        safe_turned = np.empty_like(safe)
        safe_turned[:, moved] = safe
        # a context seen in the turned world maps to the same template by g R^-1
        mats = group.matrices[element] @ np.linalg.inv(rot)
        t2, c2 = template_priors(template, mats, safe_turned, 3)
        assert np.allclose(t2, table) and np.array_equal(c2, counts)
    assert counts.sum() == m * n_dir and ((table > 0) & (table < 1)).all()


def test_learnt_capabilities_round_trip_and_are_checked(learnt: Capabilities, tmp_path) -> None:
    stage = learnt.stats["stages"][-1]
    assert stage["stage"] == "safety" and 0.5 < stage["heldout_auc"] <= 1.0
    assert learnt.safety is not None and learnt.safety.template_safe.shape == (
        len(learnt.reduction.templates), 16)  # fmt: skip
    path = learnt.save(tmp_path / "l.npz")
    back = Capabilities.load(path)
    assert back.equals(learnt) and np.array_equal(back.safety.net, learnt.safety.net)
    bad = dict(np.load(path))
    bad["safety_net"] = bad["safety_net"][:, :, :-1]
    np.savez(tmp_path / "bad.npz", **bad)
    with pytest.raises(CapabilitiesFormatError, match=r"safety networks have shape \(2, 17, 128\); training makes \(2, 17, 129\)"):
        Capabilities.load(tmp_path / "bad.npz")


def test_the_learnt_agent_needs_safety_priors() -> None:
    caps = learn(LearnParams(worlds=4, steps=100, directions=16))
    with pytest.raises(InvalidArgumentError, match="no safety priors"):
        LearntAgent(caps)


def test_with_nothing_learnt_it_is_compass_guard_step_for_step(learnt: Capabilities) -> None:
    for level in ("map", "sensor"):
        for k in range(6):
            base = draw_episode("polygon", k, 3)
            a, b = copy.deepcopy(base), copy.deepcopy(base)
            ra = run_episode(LearntAgent(learnt, alpha=0.0, beta=0.0, wait=False, guard=1.05), a,
                           sensing=level, max_steps=150)  # fmt: skip
            rb = run_episode(CompassGuard(guard=1.05), b, sensing=level, max_steps=150)
            assert (ra.outcome, ra.steps, ra.path_length) == (rb.outcome, rb.steps, rb.path_length)
            assert np.array_equal(a.position, b.position)


def test_waiting_is_chosen_when_the_network_says_only_waiting_is_safe(learnt) -> None:
    net = np.zeros((2, 2, 129))
    net[0, 1, 0] = -8.0  # every move unsafe
    net[1, 1, 0] = 8.0  # waiting safe
    model = SafetyModel(net, learnt.safety.template_safe, learnt.safety.template_counts)
    agent = LearntAgent(learnt, safety=model, alpha=1.0, wait=True)
    from copi.core import Observation, Task

    agent.reset(Task("sensor", 0.3, 0.5, 32, 10.0))
    v = agent.act(Observation(np.full(32, 10.0), np.array([5.0, 0.0])))
    assert np.array_equal(v, [0.0, 0.0]) and agent.n_waits == 1
    agent.wait = False
    v = agent.act(Observation(np.full(32, 10.0), np.array([5.0, 0.0])))
    assert np.allclose(v, [1.0, 0.0])  # all equally unsafe: the route decides
    with pytest.raises(InvalidArgumentError, match="finite"):
        agent.act(Observation(np.full(32, np.nan), np.array([5.0, 0.0])))


def test_the_networks_see_the_static_reading_only_when_learnt_with_it(learnt) -> None:
    """A wall at 1 on ray 0 that the static map explains: a network learnt with static
    readings is handed them (its closeness block empty: nothing moves), one learnt
    without is not (the wall close, as in learning); the guard sees them either way."""
    from copi.core import Observation, Task

    s = np.full(32, 10.0)
    s[0] = 1.0
    net = _net(4, hidden=16)
    seen = []
    for aware in (False, True):
        model = SafetyModel(net, learnt.safety.template_safe, learnt.safety.template_counts,
                            aware)  # fmt: skip
        agent = LearntAgent(learnt, safety=model, alpha=1.0, wait=True)  # waiting: all judged
        agent.reset(Task("map", 0.3, 0.5, 32, 10.0))
        agent.act(Observation(s, np.array([5.0, 0.0]), static=s.copy()))
        want = _probs(s, s, net, static=s if aware else None)
        assert np.allclose(agent._p, want, atol=1e-12)
        seen.append(agent._p.copy())
    assert not np.allclose(seen[0], seen[1])
    assert np.allclose(seen[0], _probs(s, s, net))  # unaware: as if no map were given


def test_static_aware_capabilities_round_trip_and_the_flag_is_checked(tmp_path) -> None:
    caps = learn(LearnParams(worlds=3, steps=80, directions=16, safety=True, probe_worlds=2,
                             probe_steps=20, safety_static=True))  # fmt: skip
    assert caps.safety is not None and caps.safety.static_aware
    back = Capabilities.load(caps.save(tmp_path / "s.npz"))
    assert back.safety is not None and back.safety.static_aware and back.equals(caps)
    # a model handed in place of the learnt one is recorded as it is
    plain = dataclasses.replace(caps, safety=dataclasses.replace(caps.safety, static_aware=False))
    again = Capabilities.load(plain.save(tmp_path / "p.npz"))
    assert again.safety is not None and not again.safety.static_aware
    bad = dict(np.load(tmp_path / "s.npz"))
    meta = json.loads(str(bad["metadata"]))
    meta["params"]["safety_static"] = "yes"
    bad["metadata"] = np.array(json.dumps(meta))
    np.savez(tmp_path / "bad.npz", **bad)
    with pytest.raises(CapabilitiesFormatError, match="safety_static must be true or false; got 'yes'"):
        Capabilities.load(tmp_path / "bad.npz")
    with pytest.raises(InvalidArgumentError, match="safety_static must be True or False"):
        LearnParams(safety_static=1)


@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_scoring_only_the_promising_directions_chooses_as_scoring_all(learnt, data) -> None:
    from copi.online import _learnt_kernels

    agent = LearntAgent(learnt, alpha=2.0, beta=data.draw(st.sampled_from([0.0, 0.5])),
                        wait=False, guard=1.05)  # fmt: skip
    s = data.draw(readings)
    prev = np.clip(s + data.draw(st.floats(-1.0, 1.0)), 0.0, 10.0)
    static = s + data.draw(st.sampled_from([0.0, 0.5, np.inf]))
    aim = data.draw(st.tuples(st.floats(-5, 5), st.floats(-5, 5)))
    # sharper networks too, so that probabilities near 1 (log near 0) occur
    net = agent._net * data.draw(st.sampled_from([1.0, 20.0]))
    keep = data.draw(st.integers(-1, 15))
    persist = data.draw(st.sampled_from([0.0, 0.05, 0.5]))
    prev_landmark = data.draw(st.integers(-1, int(agent._landmarks.max())))
    aware = data.draw(st.booleans())
    outs = []
    for lazy in (True, False):
        out, p = np.empty(5), np.empty(17)
        _learnt_kernels.decide_learnt(
            s, prev, static, agent._nodes_t, agent._prior, net, aim[0], aim[1], 5.0, 1.05,
            2.0, agent.beta, False, agent._cos, agent._sin, 10.0, agent._compass, np.empty(8 * 32), p, out,
            agent._landmarks, prev_landmark, keep, persist, lazy, aware,
        )  # fmt: skip
        outs.append((out.copy(), p.copy()))
    (a, pa), (b, pb) = outs
    assert np.array_equal(a, b)
    seen = ~np.isnan(pa)
    assert np.array_equal(pa[seen], pb[seen])  # what it evaluated, it evaluated alike


def test_a_batch_decides_as_one_agent_at_a_time(learnt) -> None:
    from copi.learning import explore
    from copi.online import _learnt_kernels

    agent = LearntAgent(learnt, alpha=2.0, beta=0.5, wait=False, guard=1.05)
    r = explore(2, 120, seed=5).readings
    s, prev = r[1:101], r[:100]
    rng = np.random.default_rng(1)
    want = rng.normal(size=(100, 2))
    want[7] = 0.0  # no direction: no motion
    reach = rng.uniform(0.2, 20.0, 100)
    static = np.where(rng.random((100, 32)) < 0.5, s, np.inf)
    for aware in (False, True):
        agent.model = dataclasses.replace(agent.model, static_aware=aware)
        actions, nodes = agent.decide_batch(s, prev, want, reach, static)
        for i in range(100):
            out, p = np.empty(5), np.empty(17)
            _learnt_kernels.decide_learnt(
                s[i], prev[i], static[i], agent._nodes_t, agent._prior, agent._net, want[i, 0],
                want[i, 1], reach[i], 1.05, 2.0, 0.5, False, agent._cos, agent._sin, 10.0,
                agent._compass, np.empty(256), p, out, agent._landmarks, -1, -1, 0.0, True,
                aware,
            )  # fmt: skip
            assert np.array_equal(actions[i], out[:2]) and nodes[i] == out[2]
        assert np.array_equal(actions[7], [0.0, 0.0])
    with pytest.raises(InvalidArgumentError, match="recognise=False needs beta = 0"):
        agent.decide_batch(s, prev, want, reach, static, recognise=False)
    agent.beta = 0.0  # the choice uses no context: the same actions without recognising
    actions, nodes = agent.decide_batch(s, prev, want, reach, static)
    fast, none = agent.decide_batch(s, prev, want, reach, static, recognise=False)
    assert np.array_equal(fast, actions) and (none == -1).all() and (nodes >= 0).all()
    with pytest.raises(InvalidArgumentError, match="previous readings must have shape"):
        agent.decide_batch(s, prev[:3], want)
    bad = s.copy()
    bad[3, 4] = np.nan
    with pytest.raises(InvalidArgumentError, match="readings must be finite"):
        agent.decide_batch(bad, prev, want)


def test_rows_of_shared_arrays_are_decided_as_a_batch(learnt) -> None:
    """decide_rows (a crowd's agents, in place) makes decide_batch's decisions, treats a
    changed goal as a new task (no previous reading) and skips agents out of the world."""
    agent = LearntAgent(learnt, alpha=2.0, wait=False, guard=1.05, beta=0.0)
    rng = np.random.default_rng(3)
    n = 60
    s = rng.uniform(0.3, 10.0, (n, 32))
    s[rng.random((n, 32)) < 0.3] = 10.0
    prev = np.clip(s + rng.normal(0, 0.3, s.shape), 0.0, 10.0)
    pos = rng.uniform(0, 50, (n, 2))
    goals = pos + rng.normal(0, 5, (n, 2))
    goals[5] = pos[5]  # at its goal: no move
    active = rng.random(n) < 0.8
    first = 10  # the rows' state starts at agent 10
    kept_prev = np.full((n, 32), -1.0)
    kept_prev[first:] = prev[first:]
    kept_goal = np.full((n, 2), np.nan)
    kept_goal[first:] = goals[first:]
    new = np.arange(first, n, 2)
    kept_goal[new] += 1.0  # these agents' goals changed: their previous readings are void
    kept_prev[new] = np.clip(s[new] + 3.0, 0.0, 10.0)  # (stale readings, far from these)
    state_p, state_g = kept_prev[first:].copy(), kept_goal[first:].copy()
    actions = np.full((n, 2), 7.0)
    agent.decide_rows(s, pos, goals, active, first, n, state_p, state_g, first, actions)
    rows = np.arange(first, n)
    want = goals[rows] - pos[rows]
    before = kept_prev[rows].copy()
    before[new - first] = s[new]
    expect, _ = agent.decide_batch(s[rows], before, want, np.hypot(*want.T), recognise=False)
    stale, _ = agent.decide_batch(s[rows], kept_prev[rows], want, np.hypot(*want.T),
                                  recognise=False)  # fmt: skip
    on = active[rows]
    assert np.array_equal(actions[rows][on], expect[on])
    assert not np.array_equal(stale[on], expect[on])  # the stale readings would mislead
    assert (actions[:first] == 7.0).all() and (actions[rows][~on] == 7.0).all()
    assert np.array_equal(state_p[on], s[rows][on]) and np.array_equal(state_g[on], goals[rows][on])
    assert np.array_equal(state_p[~on], kept_prev[first:][~on])  # out of the world: untouched
    bad = s.copy()
    bad[first + 8] = np.nan
    active[first + 8] = True
    with pytest.raises(InvalidArgumentError, match=f"agent {first + 8}'s"):
        agent.decide_rows(bad, pos, goals, active, first, n, state_p, state_g, first, actions)
    with pytest.raises(InvalidArgumentError, match=r"positions must have shape \(60, 2\)"):
        agent.decide_rows(s, pos[:-1], goals, active, first, n, state_p, state_g, first, actions)
    with pytest.raises(InvalidArgumentError, match="rows lo .. hi - 1 must lie within"):
        agent.decide_rows(s, pos, goals, active, first - 1, n, state_p, state_g, first, actions)
    agent.beta = 0.5
    with pytest.raises(InvalidArgumentError, match="beta must be 0"):
        agent.decide_rows(s, pos, goals, active, first, n, state_p, state_g, first, actions)


def test_a_policy_lasts_while_the_reading_stays_within_its_landmark(learnt) -> None:
    from copi.online import _learnt_kernels

    agent = LearntAgent(learnt, alpha=2.0, wait=False, guard=1.05, persist=0.05)
    s = np.full(32, 10.0)  # open space: every direction safe alike
    aim = (np.cos(np.radians(10.0)), np.sin(np.radians(10.0)))  # east (d 0) is best aligned
    node = int(np.argmin(((agent._nodes - s) ** 2).sum(1)))
    here = int(agent._landmarks[node])

    def choose(prev_landmark: int, keep: int, persist: float) -> int:
        out, p = np.empty(5), np.empty(17)
        _learnt_kernels.decide_learnt(
            s, s, np.full(32, np.inf), agent._nodes_t, agent._prior, agent._net, aim[0], aim[1],
            5.0, 1.05, 2.0, 0.0, False, agent._cos, agent._sin, 10.0, agent._compass, np.empty(256), p, out,
            agent._landmarks, prev_landmark, keep, persist, True, False,
        )  # fmt: skip
        return int(out[4])

    assert choose(-1, -1, 0.0) == 0
    # cos 12.5 deg (d 1) trails cos 10 deg by 0.009: a bonus of 0.05 keeps d 1 ...
    assert choose(here, 1, 0.05) == 1
    # ... but only within the same landmark, and not for a direction far off the aim
    assert choose(here + 1, 1, 0.05) == 0
    assert choose(here, 4, 0.05) == 0
    with pytest.raises(InvalidArgumentError, match="persist must be a finite number >= 0"):
        LearntAgent(learnt, persist=-1.0)


def test_grown_contexts_follow_their_map_and_weights_are_checked(learnt) -> None:
    from copi.core import Observation, Task

    agent = LearntAgent(learnt, continual=True, grow_every=50, wait=False)
    agent.reset(Task("sensor", 0.3, 0.5, 32, 10.0))
    agent.threshold = 3.0  # a tight familiarity: every noise reading below is unfamiliar
    rng = np.random.default_rng(0)
    base = len(learnt.nodes)
    grown = []
    for _ in range(60):  # noise readings: far from every context, and from each other
        odd = rng.uniform(0.3, 10.0, 32)
        agent.act(Observation(odd, np.array([5.0, 0.0])))
        grown.append(agent._nodes[base:].copy())
    assert agent.n_unfamiliar > 20
    # Between insertions (every 50) the grown nodes keep moving, and the agent follows.
    same_count = [(a, b) for a, b in zip(grown, grown[1:], strict=False) if len(a) == len(b) > 0]
    assert same_count and any(not np.array_equal(a, b) for a, b in same_count)
    for key in ("alpha", "beta"):
        with pytest.raises(InvalidArgumentError, match=f"{key} must be a finite number >= 0"):
            LearntAgent(learnt, **{key: -1.0})


def test_the_learning_samples_counted_are_the_states_probed(learnt: Capabilities) -> None:
    # every second state of 8 walks of 60 steps, each of 17 actions held 3 steps at most
    cost = simulated_steps(learnt.params)
    stage = learnt.stats["stages"][-1]
    assert cost["probes"] == stage["probed_states"] * 17 * 3 == 8 * 30 * 51
    assert cost["exploration"] == learnt.stats["stages"][0]["samples"] == 6 * 150
    assert cost["total"] == 900 + 8 * 60 + cost["probes"]
    odd = simulated_steps({**learnt.params, "probe_steps": 61, "safety": False})
    assert odd["walks"] == odd["probes"] == 0 and odd["total"] == 900


def _head_on(disc_x: float) -> tuple[Simulator, np.ndarray]:
    """An open room; the agent at (20, 20) and a disc of radius 0.5 at (disc_x, 20) coming
    straight at it at 0.8 a step (no turning). Returns the simulator and the probe's
    actions (16 compass directions, then waiting)."""
    w = World([[0, 0], [40, 0], [40, 40], [0, 40]])
    sim = Simulator(w, [20, 20], [35, 35], [[disc_x, 20.0]], [0.5], seed=0, speed=0.8,
                    turn_sd=0.0)  # fmt: skip
    sim.headings[:] = math.pi
    a = 2 * np.pi * np.arange(16) / 16
    return sim, np.vstack([np.column_stack([np.cos(a), np.sin(a)]), np.zeros((1, 2))])


def test_an_escape_probe_judges_the_first_move_by_the_moves_it_leaves() -> None:
    """A disc 3.5 ahead coming at the agent: stepping towards it once touches nothing (the
    gap after it is 1.7 - 0.8 = 0.9) but holding that direction meets it on the second
    step. The hold label says unsafe; the escape label says safe (stepping back then
    clears the disc's next step by 1.1). Moving away is safe by both; a disc 1.6 ahead
    is met by the first step towards it (closest approach 0): unsafe by both."""
    sim, actions = _head_on(23.5)
    seconds = np.ascontiguousarray(np.vstack([actions[:16], 0.5 * actions[:16], [[0, 0]]]))
    hold = probe_actions(sim, actions, 3, "hold", seconds)
    escape = probe_actions(sim, actions, 3, "escape", seconds)
    assert not hold[0] and escape[0]
    assert hold[8] and escape[8]  # west: away from the disc
    near, _ = _head_on(21.6)
    assert not probe_actions(near, actions, 3, "hold", seconds)[0]
    assert not probe_actions(near, actions, 3, "escape", seconds)[0]
    # the probe forks: the simulator itself has not moved
    assert sim.t == 0 and sim.centers[0, 0] == 23.5


def test_second_move_clear_needs_one_move_that_keeps_its_room() -> None:
    """Against the simulator's closest-approach test evaluated here: a disc of radius 0.5
    coming down at 0.8 a step onto the agent (radius 0.3). Waiting is in contact; a step
    east passes it with about 0.29 to spare: a clear move for a room of 0 or 0.2, none for
    0.5. A wall just east of the agent stops that step short: no clear move then."""
    from copi.geometry.kernels import closest_approach

    segs = np.zeros((0, 4))
    moves = np.array([[1.0, 0.0], [0.0, 0.0]])
    c1, c2 = np.array([[20.0, 21.4]]), np.array([[20.0, 20.6]])
    gaps = [closest_approach(20.0, 20.0, dx, dy, 20.0, 21.4, 0.0, -0.8) - 0.8
            for dx, dy in moves]  # fmt: skip
    assert gaps[1] < 0 < 0.2 < gaps[0] < 0.5
    for clear in (0.0, 0.2, 0.5):
        want = any(g >= clear for g in gaps)
        assert second_move_clear(20.0, 20.0, 0.3, segs, c1, c2, np.array([0.5]), moves,
                                 clear) == want  # fmt: skip
    wall = np.array([[20.6, 0.0, 20.6, 40.0]])
    assert not second_move_clear(20.0, 20.0, 0.3, wall, c1, c2, np.array([0.5]), moves, 0.0)


def test_escape_probes_are_counted_and_the_label_is_checked() -> None:
    p = LearnParams(directions=16, safety=True, probe_label="escape")
    # every second state of 60 walks of 150 steps, each of 17 actions once, and the
    # obstacles' two steps alone
    assert simulated_steps(p)["probes"] == 60 * 75 * (17 + 2)
    with pytest.raises(InvalidArgumentError, match="probe_label must be one of hold, escape"):
        LearnParams(safety=True, probe_label="hindsight")
    with pytest.raises(InvalidArgumentError, match="probe label must be one of hold, escape"):
        probe_states("crowd", 1, 2, seed=0, n_directions=16, label="held")
