from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from copi.errors import InvalidArgumentError
from copi.learning import explore
from copi.online import ContextController

READINGS = explore(3, 60, seed=11).readings


def _by_hand(caps, s, want, reach=math.inf):
    """The §III chain written out plainly."""
    node = int(np.argmin(((caps.nodes - s) ** 2).sum(1)))
    landmark = int(caps.landmarks.node_landmark[node])
    template = int(caps.reduction.template_of[landmark])
    g = int(caps.reduction.element[landmark])
    m_inv = np.linalg.inv(caps.group.matrices[g])
    ok = caps.policies.passable[template]
    cand = caps.policies.actions[template] @ m_inv.T
    u = np.asarray(want, float) / np.linalg.norm(want)
    compass = not ok.any()
    if compass:  # no policy here: every compass direction whose step keeps off the hits
        n = len(ok)
        a = 2 * np.pi * np.arange(n) / n
        cand = np.column_stack([np.cos(a), np.sin(a)])
        hit = s < 10.0
        pts = np.column_stack([s[hit] * np.cos(2 * np.pi * np.flatnonzero(hit) / len(s)),
                               s[hit] * np.sin(2 * np.pi * np.flatnonzero(hit) / len(s))])
        wall = min(0.31, s.min() - 1e-6)
        ok = np.ones(n, dtype=bool)
        for d in range(n):
            st_ = 1.0 if reach >= 1.0 else max(cand[d] @ u * reach, 0.5 * reach)
            t = np.clip(pts @ cand[d], 0.0, st_)
            if len(pts) and np.hypot(*(pts - t[:, None] * cand[d]).T).min() < wall:
                ok[d] = False
        if not ok.any():
            return node, landmark, template, g, None, np.zeros(2)
    d = int(np.argmax(np.where(ok, cand @ u, -np.inf)))
    step = 1.0  # a full step, unless the aim is nearer than that: then come level with
    if reach < 1.0:  # it, and go at least half way (a sideways step must not vanish)
        step = max(cand[d] @ u * reach, 0.5 * reach)
    choice = f"compass {caps.policies.names[d]}" if compass else d
    return node, landmark, template, g, choice, cand[d] * step


@settings(max_examples=60, deadline=None)
@given(i=st.integers(0, len(READINGS) - 1), angle=st.floats(0, 2 * np.pi), reach=st.floats(0.1, 20))
def test_the_chain_matches_a_plain_rendition(small_caps, i, angle, reach) -> None:
    caps, _ = small_caps
    ctl = ContextController(caps)
    want = [math.cos(angle), math.sin(angle)]
    action, info = ctl.decide(READINGS[i], want, reach=reach, explain=True)
    node, landmark, template, g, d, expected = _by_hand(caps, READINGS[i], want, reach)
    assert (info.node, info.landmark, info.template) == (node, landmark, template)
    assert info.element == (caps.group.words[g] or "id")
    assert info.choice == (
        None if d is None else d if isinstance(d, str) else caps.policies.names[d]
    )
    np.testing.assert_allclose(action, expected, atol=1e-12)
    assert len(info.candidates) == len(info.candidate_actions)
    assert np.linalg.norm(action) <= 1 + 1e-12


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**31), guard=st.sampled_from([0.0, 1.0]))
def test_batched_equals_one_by_one(small_caps, seed, guard) -> None:
    caps, _ = small_caps
    rng = np.random.default_rng(seed)
    rows = READINGS[rng.choice(len(READINGS), 25)]
    want = rng.normal(size=(25, 2))
    reach = rng.uniform(0.2, 5, 25)
    ctl = ContextController(caps, guard=guard)
    batch, nodes = ctl.decide_batch(rows, want, reach)
    for b in range(25):
        a, info = ctl.decide(rows[b], want[b], reach=reach[b], explain=True)
        np.testing.assert_array_equal(a, batch[b])
        assert info.node == nodes[b]


def test_guard_refuses_a_move_into_a_near_hit(small_caps) -> None:
    caps, _ = small_caps
    s = np.full(caps.n_rays, 10.0)
    s[0] = 0.9  # something right ahead, east
    free = ContextController(caps)
    guarded = ContextController(caps, guard=1.0)
    a_free, info = free.decide(s, [1.0, 0.0], explain=True)
    a_guard, info_g = guarded.decide(s, [1.0, 0.0], explain=True)
    hit = np.array([0.9, 0.0])
    assert np.linalg.norm(a_free - hit) < 1.0  # the plain chain steps within 1 of the hit
    assert info_g.choice != info.choice
    assert np.linalg.norm(a_guard - hit) >= 1.0  # the guarded one keeps the clearance


def test_unfamiliar_readings_are_flagged_and_can_be_learnt(small_caps) -> None:
    caps, _ = small_caps
    ctl = ContextController(caps, continual=True)
    rng = np.random.default_rng(0)
    # a comb of rays alternately touching and free: no world looks like it
    odd = np.tile([0.2, 10.0], caps.n_rays // 2) + rng.uniform(0, 0.1, size=(60, caps.n_rays))
    for s in odd:
        action, info = ctl.decide(s, [0.0, 1.0], explain=True)
        assert info.unfamiliar
    assert ctl.unfamiliar_rate == 1.0
    assert ctl.n_learnt >= 2
    _, info = ctl.decide(odd[-1], [0.0, 1.0], explain=True)
    assert info.node >= len(caps.nodes)  # the reading now has a context of its own
    # the rate counts, over all decisions so far, readings farther from every node than
    # the threshold: 99 % of the training readings are within it
    mixed = np.concatenate([READINGS[:40], odd[:10]])
    d = np.sqrt(((mixed[:, None, :] - caps.nodes[None]) ** 2).sum(-1)).min(1)
    threshold = caps.stats["familiarity_threshold"]
    expected = float((d > threshold).mean())
    assert (d[40:] > threshold).all() and 10 / 50 <= expected < 1
    plain = ContextController(caps)
    assert plain.threshold == threshold and plain.unfamiliar_rate == 0.0
    for s in mixed:
        plain.decide(s, [1.0, 0.0])
    assert plain.unfamiliar_rate == pytest.approx(expected, abs=1e-12)


def test_bad_readings_are_refused(small_caps) -> None:
    caps, _ = small_caps
    ctl = ContextController(caps)
    with pytest.raises(
        InvalidArgumentError, match=r"must have shape \(32,\) \(as the capabilities\); got \(16,\)"
    ):
        ctl.decide(np.ones(16), [1.0, 0.0])
    with pytest.raises(InvalidArgumentError, match="must be finite"):
        ctl.decide(np.r_[np.nan, np.ones(31)], [1.0, 0.0])
    with pytest.raises(InvalidArgumentError, match="guard must be"):
        ContextController(caps, guard=-1)


@pytest.mark.parametrize(
    "call",
    [
        # the two out-of-bounds reads of issue 14: a reach of one value for a batch, and a
        # static reading of 3 rays with a guard
        lambda c, s: c.decide_batch(np.tile(s, (200, 1)), np.ones((200, 2)), reach=[1.0, 2.0]),
        lambda c, s: c.decide(s, [1.0, 0.0], static=[1, 2, 3]),
        lambda c, s: c.decide_batch(np.tile(s, (3, 1)), np.ones((3, 2)), static=np.ones((2, 32))),
        lambda c, s: c.decide_batch(np.tile(s, (3, 1)), np.ones(6)),
        lambda c, s: c.decide(s, [1.0]),
        lambda c, s: c.decide(s, [np.nan, 0.0]),
        lambda c, s: c.decide(s, [1.0, 0.0], reach=np.nan),
        lambda c, s: c.decide(s, [1.0, 0.0], reach=-1.0),
        lambda c, s: c.decide(s, [1.0, 0.0], reach="far"),
        lambda c, s: c.decide(-s, [1.0, 0.0]),
        lambda c, s: c.decide(s + 1j, [1.0, 0.0]),
        lambda c, s: c.decide(s, [1.0 + 2j, 0.0]),
        lambda c, s: c.decide(s, [1.0, 0.0], static=np.full(32, np.nan)),
        lambda c, s: c.decide(s, [1.0, 0.0], static=-s),
        lambda c, s: c.decide(["a"] * 32, [1.0, 0.0]),
        lambda c, s: c.decide_batch(np.tile(s, (2, 1)), np.ones((2, 2)), reach=[np.nan, 1.0]),
        lambda c, s: c.decide_batch(np.tile(-s, (2, 1)), np.ones((2, 2))),
    ],
)
def test_every_entry_point_checks_shapes_and_values(small_caps, call) -> None:
    caps, _ = small_caps
    ctrl = ContextController(caps, guard=1.0)
    with pytest.raises(InvalidArgumentError):
        call(ctrl, np.full(caps.n_rays, 5.0))
    assert ctrl.n_decisions == 0


@pytest.mark.parametrize("bad", [dict(threshold=math.nan), dict(threshold=-1.0),
                                 dict(threshold="x"), dict(guard=math.nan), dict(guard=1j)])  # fmt: skip
def test_bad_controller_parameters_are_refused(small_caps, bad) -> None:
    with pytest.raises(InvalidArgumentError):
        ContextController(small_caps[0], **bad)


def test_a_guarded_agent_resting_against_a_wall_can_still_move() -> None:
    # Found on a Moving AI room map: an agent 0.34 from a wall (0.04 from touching it)
    # refused every step, since each step's path starts where it stands, too near the
    # wall; it stood still for good. A step is judged by whether it brings it nearer.
    from copi.methods import make_agent
    from copi.runs import run_episode
    from copi.world import Simulator, World

    room = World([[0, 0], [20, 0], [20, 20], [0, 20]])
    sim = Simulator(room, [0.34, 10.0], [10.0, 10.0], np.zeros((0, 2)), np.zeros(0))
    res = run_episode(make_agent("compass-guard"), sim, sensing="map", max_steps=30)
    assert res.outcome == "success" and res.no_policy == 0


def test_a_template_with_no_policy_falls_back_to_the_compass(small_caps) -> None:
    caps, _ = small_caps
    ctl = ContextController(caps, guard=1.2)
    ctl._ok[:] = False  # as if every template offered no policy
    s = np.full(caps.n_rays, 9.0)
    action, info = ctl.decide(s, [1.0, 0.2], explain=True)
    assert info is not None and info.choice == f"compass {caps.policies.names[0]}"
    assert action[0] == pytest.approx(1.0) and abs(action[1]) < 1e-12
    # Never into a wall: with a wall 0.4 east the fallback leaves east out.
    s2 = s.copy()
    s2[0] = 0.4
    action2, info2 = ctl.decide(s2, [1.0, 0.0], explain=True)
    assert info2 is not None and info2.choice is not None
    assert action2[0] < 0.9


def test_continual_growth_rate_is_checked() -> None:
    from copi.learning import LearnParams, learn

    caps = learn(LearnParams(worlds=2, steps=40, seed=0))
    with pytest.raises(InvalidArgumentError, match="grow_every must be a positive int; got 0"):
        ContextController(caps, continual=True, grow_every=0)


@settings(max_examples=80, deadline=None)
@given(
    seed=st.integers(0, 2**31),
    angle=st.floats(0, 2 * np.pi),
    step=st.floats(0.05, 1.0),
    walls=st.floats(0.0, 1.0),
)
def test_room_distances_match_a_plain_rendition(seed, angle, step, walls) -> None:
    """The guard's distances (hit points listed once, minima over squared distances rooted
    once) equal the distances measured hit by hit with numpy."""
    from copi.online import kernels

    n = 32
    rng = np.random.default_rng(seed)
    s = np.where(rng.random(n) < 0.2, 10.0, rng.uniform(0.2, 9.9, n))
    static = np.where(rng.random(n) < walls, s, np.inf)  # these hits are walls
    a = 2 * np.pi * np.arange(n) / n
    cos, sin = np.cos(a), np.sin(a)
    hits = np.empty((2, n))
    km, k0 = kernels._hits(s, static, cos, sin, 10.0, hits)
    ax, ay = math.cos(angle), math.sin(angle)
    end, sweep, sweep_all = kernels._room(hits, km, k0, ax, ay, step, 0.0)
    seen = s < 10.0
    moving = seen & (s < static - 0.05)
    pts = np.column_stack([s * cos, s * sin])
    t = np.clip(pts @ [ax, ay], 0.0, step)
    path = np.hypot(pts[:, 0] - t * ax, pts[:, 1] - t * ay)
    after = np.hypot(pts[:, 0] - step * ax, pts[:, 1] - step * ay)
    want = [after[moving].min(initial=np.inf), path[moving].min(initial=np.inf),
            path[seen].min(initial=np.inf)]  # fmt: skip
    np.testing.assert_allclose([end, sweep, sweep_all], want, rtol=1e-12, atol=1e-12)
    assert km == moving.sum() and n - k0 == (seen & ~moving).sum()
    # told to stop below a distance, it stops at a path distance below it, else measures all
    for stop in (0.31, 1.0, 3.0):
        got = kernels._room(hits, km, k0, ax, ay, step, stop)
        if want[2] < stop:
            assert got[0] == got[1] == got[2] < stop and np.isclose(path, got[2]).any()
        else:
            np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31), scale=st.sampled_from([0.01, 1.0, 10.0]))
def test_the_batched_screen_finds_the_exact_nearest_node(seed, scale) -> None:
    """The float32 screen (norms folded into one product) keeps the exact nearest node
    among its candidates, for nodes near one another and far from the origin (where
    float32's error is largest)."""
    from copi.online import kernels
    from copi.online._controller import screen_nodes, screen_products

    rng = np.random.default_rng(seed)
    centre = rng.uniform(5.0, 10.0, 32)
    nodes = centre + scale * rng.normal(size=(300, 32))
    x = centre + scale * rng.normal(size=(40, 32))
    gram, sq = screen_products(x, screen_nodes(nodes))
    nodes_t = np.ascontiguousarray(nodes.T)
    for b in range(len(x)):
        node, d2 = kernels._screened_nearest(x[b], gram[b], sq[b], nodes_t)
        full = ((nodes - x[b]) ** 2).sum(1)
        assert node == int(np.argmin(full))
        assert d2 == pytest.approx(full.min(), rel=1e-12)
