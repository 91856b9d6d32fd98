from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from copi.errors import InvalidArgumentError
from copi.learning import (
    Operator,
    PermutationAutomaton,
    SymmetryGroup,
    reduce_landmarks,
    ring_operators,
)
from copi.reports import fig2_operators
from copi.world import RangeSensor, World, random_world

RING = SymmetryGroup.generate(ring_operators(32))


def test_fig2_automaton_has_the_papers_transitions() -> None:
    """The paper's Fig. 2 (1-based there, 0-based here): states 1-4 are walls rotated by o,
    5 is speed, 6-7 swapped by p."""
    fa = PermutationAutomaton.from_operators(fig2_operators())
    assert fa.n_states == 7
    expected: dict[tuple[int, int], set[tuple[int, int]]] = {}
    for a, b in itertools.product(range(4), range(2)):
        walls = [(k - a) % 4 for k in range(4)]  # o^a . s reads wall k from (k - a) mod 4
        targets = [5, 6] if b == 0 else [6, 5]
        seq = [*walls, 4, *targets]
        for u, v in zip(seq[:-1], seq[1:], strict=True):
            expected.setdefault((u, v), set()).add((a, b))
    assert {k: set(v) for k, v in fa.transitions.items()} == expected
    # ring transitions inside 1-4 follow the rotation; 5 leads to 6 or 7; 6 and 7 swap
    assert {(u, v) for (u, v) in fa.transitions if u < 4 and v < 4} == {
        (0, 1),
        (1, 2),
        (2, 3),
        (3, 0),
    }
    assert {v for (u, v) in fa.transitions if u == 4} == {5, 6}


@pytest.mark.parametrize("label", list(itertools.product(range(4), range(2))))
def test_fig2_automaton_recognises_each_group_element(label) -> None:
    fa = PermutationAutomaton.from_operators(fig2_operators())
    chi1 = np.array([2.0, 3.5, 1.0, 7.0, 0.3, 4.0, 9.0])
    chi2 = chi1[fa.permutation(label)]
    assert fa.accept(chi1, chi2, tol=1e-9) == [label]
    noisy = chi2 + np.random.default_rng(0).uniform(-0.05, 0.05, 7)
    assert fa.accept(chi1, noisy, tol=0.1) == [label]


def test_fig2_automaton_rejects_what_no_operator_explains() -> None:
    fa = PermutationAutomaton.from_operators(fig2_operators())
    chi1 = np.array([2.0, 3.5, 1.0, 7.0, 0.3, 4.0, 9.0])
    swapped_walls = chi1[[1, 0, 2, 3, 4, 5, 6]]  # a transposition is not a rotation
    assert fa.accept(chi1, swapped_walls, tol=1e-9) == []
    speed_moved = chi1[[4, 1, 2, 3, 0, 5, 6]]
    assert fa.accept(chi1, speed_moved, tol=1e-9) == []


OPERATOR_SETS = {"fig2": fig2_operators(), "ring8": ring_operators(8), "ring12": ring_operators(12)}


@settings(max_examples=200, deadline=None)
@given(
    which=st.sampled_from(sorted(OPERATOR_SETS)),
    seed=st.integers(0, 2**31),
    levels=st.integers(1, 4),
    noise=st.floats(0.0, 0.5),
    tol=st.floats(0.0, 0.6),
)
def test_fast_path_agrees_with_the_automaton(which, seed, levels, noise, tol) -> None:
    ops = OPERATOR_SETS[which]
    fa = PermutationAutomaton.from_operators(ops)
    group = SymmetryGroup.generate(ops)
    labels = list(itertools.product(*(range(o.order) for o in ops)))
    # the products of powers the automaton enumerates are the whole group here
    assert {fa.permutation(lab).tobytes() for lab in labels} == {p.tobytes() for p in group.perms}
    rng = np.random.default_rng(seed)
    chi1 = rng.integers(0, levels, fa.n_states).astype(float)  # few levels: many ties
    lab = labels[int(rng.integers(len(labels)))]
    chi2 = chi1[fa.permutation(lab)] + rng.uniform(-noise, noise, fa.n_states)
    by_automaton = {fa.permutation(x).tobytes() for x in fa.accept(chi1, chi2, tol)}
    by_group = {group.perms[g].tobytes() for g in group.matches(chi1, chi2, tol)}
    assert by_automaton == by_group


def test_ring_group_is_the_square_with_shortest_words() -> None:
    assert len(RING) == 8
    assert RING.words[0] == "" and max(len(w) for w in RING.words) <= 3
    dets = np.round(np.linalg.det(RING.matrices)).tolist()
    assert dets.count(1.0) == 4 and dets.count(-1.0) == 4


@settings(max_examples=50, deadline=None)
@given(a=st.integers(0, 7), b=st.integers(0, 7))
def test_group_composes_and_inverts(a: int, b: int) -> None:
    s = np.random.default_rng(a * 8 + b).normal(size=32)
    ab = RING.compose(a, b)
    np.testing.assert_array_equal(RING.apply(ab, s), RING.apply(a, RING.apply(b, s)))
    np.testing.assert_allclose(RING.matrices[ab], RING.matrices[a] @ RING.matrices[b])
    np.testing.assert_array_equal(RING.apply(RING.inverse(a), RING.apply(a, s)), s)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31), g=st.integers(0, 7))
def test_plane_action_matches_the_permutation_of_scans(seed: int, g: int) -> None:
    """Turning the world (and the agent) by g's matrix turns the scan by g's permutation."""
    world = random_world(seed)
    rng = np.random.default_rng(seed)
    xmin, ymin, xmax, ymax = world.bounds
    while True:
        p = rng.uniform([xmin, ymin], [xmax, ymax])
        if world.contains(p):
            break
    m = RING.matrices[g]
    turned = World(world.boundary @ m.T, name="turned")
    sensor = RangeSensor()
    before = sensor.scan(world, p)
    after = sensor.scan(turned, m @ p)
    np.testing.assert_allclose(after, RING.apply(g, before), atol=1e-9)


def test_too_large_a_group_is_refused() -> None:
    n = 12
    cycle = Operator("c", np.roll(np.arange(n), 1))
    swap = Operator("s", np.r_[[1, 0], np.arange(2, n)])  # these generate all 12! perms
    with pytest.raises(InvalidArgumentError, match="more than 5000 permutations"):
        SymmetryGroup.generate([cycle, swap], max_elements=5000)
    with pytest.raises(InvalidArgumentError, match="must be a permutation"):
        Operator("bad", [0, 0, 1])


def test_reduction_finds_the_templates_and_elements() -> None:
    rng = np.random.default_rng(3)
    base = rng.uniform(0, 10, size=(3, 32))
    landmarks, truth = [], []
    for t in range(3):
        for g in rng.choice(8, size=4, replace=False):
            landmarks.append(RING.apply(RING.inverse(int(g)), base[t]) + rng.normal(0, 0.01, 32))
            truth.append((t, int(g)))
    red = reduce_landmarks(np.array(landmarks), RING, tol=0.1)
    assert len(red.templates) == 3
    for i, (t, g) in enumerate(truth):
        j = int(red.templates[red.template_of[i]])
        t_j, g_j = truth[j]
        assert t_j == t  # same underlying context
        # landmark = g^-1 . base, template = g_j^-1 . base, so template = (g_j^-1 g) . landmark
        assert red.element[i] == RING.compose(RING.inverse(g_j), g)
        # largest of 32 differences of two N(0, 0.01) noises: below 5 sigma = 0.071
        assert red.residual[i] < 0.071
    assert len(reduce_landmarks(np.array(landmarks), RING, tol=0.0).templates) == len(landmarks)


@settings(max_examples=60, deadline=None)
@given(
    which=st.sampled_from(sorted(OPERATOR_SETS)),
    seed=st.integers(0, 2**31),
    tol=st.floats(0.0, 1.5),
)
def test_reduction_is_what_the_automaton_accepts(which, seed, tol) -> None:
    """Every landmark -> (template, g) is accepted by the automaton with that tolerance,
    and no template accepts another (so a landmark becomes a template only when none
    could take it)."""
    ops = OPERATOR_SETS[which]
    fa = PermutationAutomaton.from_operators(ops)
    group = SymmetryGroup.generate(ops)
    rng = np.random.default_rng(seed)
    base = rng.integers(0, 3, size=(3, fa.n_states)).astype(float)
    pts = base[rng.integers(0, 3, 12)]
    pts = np.array([p[group.perms[rng.integers(len(group))]] for p in pts])
    pts += rng.uniform(-0.5, 0.5, pts.shape)
    red = reduce_landmarks(pts, group, tol=tol)
    for j, p in enumerate(pts):
        t = pts[red.templates[red.template_of[j]]]
        accepted = {fa.permutation(lab).tobytes() for lab in fa.accept(p, t, tol)}
        assert group.perms[red.element[j]].tobytes() in accepted
        assert red.residual[j] <= tol
    for a, b in itertools.combinations(red.templates, 2):
        assert fa.accept(pts[a], pts[b], tol) == []
