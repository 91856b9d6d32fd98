from __future__ import annotations

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.distance import directed_hausdorff, pdist

from copi.errors import InvalidArgumentError
from copi.learning import GrowingNeuralGas, explore, skeletonize


def _random_graph(seed: int, n: int = 25, dim: int = 3):
    rng = np.random.default_rng(seed)
    pos = rng.normal(size=(n, dim))
    g = nx.random_geometric_graph(n, 0.45, seed=int(rng.integers(1 << 30)))
    edges = np.array(list(g.edges), dtype=np.int64).reshape(-1, 2)
    return pos, edges


def _replay(pos, edges, merges):
    """Brute force: contract by the given merges, checking that each contracted edge was
    a shortest edge of the current graph, and return the node sets after each step."""
    nodes = {i: pos[i] for i in range(len(pos))}
    adj = {i: set() for i in range(len(pos))}
    for u, v in edges:
        if u != v:
            adj[int(u)].add(int(v))
            adj[int(v)].add(int(u))
    sets = [np.array(list(nodes.values()))]
    for u, v, w in merges:
        lengths = [np.linalg.norm(nodes[a] - nodes[b]) for a in adj for b in adj[a] if a < b]
        if not lengths:  # no edge left: the closest pair of live nodes (of other pieces)
            live = list(nodes)
            lengths = [np.linalg.norm(nodes[a] - nodes[b]) for a in live for b in live if a < b]
        assert np.linalg.norm(nodes[u] - nodes[v]) == pytest.approx(min(lengths))
        nodes[w] = (nodes.pop(u) + nodes.pop(v)) / 2
        adj[w] = (adj.pop(u) | adj.pop(v)) - {u, v}
        for b in adj[w]:
            adj[b] = (adj[b] - {u, v}) | {w}
        sets.append(np.array(list(nodes.values())))
    assert not any(adj.values()) and len(nodes) == 1  # contracted to one node
    return sets


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**31))
def test_contraction_and_hausdorff_agree_with_brute_force(seed: int) -> None:
    pos, edges = _random_graph(seed)
    lm = skeletonize((pos, edges))
    sets = _replay(pos, edges, lm.merges)
    expected = [max(directed_hausdorff(pos, s)[0], directed_hausdorff(s, pos)[0]) for s in sets]
    np.testing.assert_allclose(lm.curve, expected, atol=1e-12)
    # the chosen refinement: its nodes are the landmarks
    chosen = sets[lm.k]
    assert sorted(map(tuple, chosen.round(12))) == sorted(map(tuple, lm.points.round(12)))


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**31), st.integers(1, 25))
def test_members_and_graph_distance_landmarks(seed: int, want: int) -> None:
    pos, edges = _random_graph(seed)
    g = nx.Graph()
    g.add_nodes_from(range(len(pos)))
    g.add_edges_from(map(tuple, edges))
    lm = skeletonize((pos, edges), n_landmarks=want)  # pieces are joined at the end
    assert lm.n_landmarks == want
    # each landmark is the mean-of-midpoints of its members: it lies in their hull box
    for j in range(want):
        own = pos[lm.members == j]
        assert len(own) >= 1
        assert (lm.points[j] >= own.min(0) - 1e-12).all() and (
            lm.points[j] <= own.max(0) + 1e-12
        ).all()
        assert lm.members[lm.anchors[j]] == j
    # d_G assignment: no landmark anchor is fewer hops away than the chosen one
    hops = {j: nx.single_source_shortest_path_length(g, int(a)) for j, a in enumerate(lm.anchors)}
    for i in range(len(pos)):
        mine = hops[int(lm.node_landmark[i])].get(i, np.inf)
        assert all(mine <= hops[j].get(i, np.inf) for j in hops)


def _clusters(m: int, c: int, r: float, gap: float, seed: int):
    """m clusters of c nodes, each in a square of half-side r (complete graph inside),
    centred ``gap`` apart on a line and chained by one edge between neighbours."""
    rng = np.random.default_rng(seed)
    centres = np.c_[gap * np.arange(m), np.zeros(m)]
    pos = np.concatenate([ctr + rng.uniform(-r, r, size=(c, 2)) for ctr in centres])
    edges = [(a * c + i, a * c + j) for a in range(m) for i in range(c) for j in range(i + 1, c)]
    edges += [(a * c, (a + 1) * c) for a in range(m - 1)]
    return pos, np.array(edges), np.repeat(np.arange(m), c)


@pytest.mark.parametrize(("m", "c", "seed"), [(2, 5, 0), (4, 12, 1), (6, 25, 2), (9, 40, 3)])
def test_knee_is_where_the_clusters_are_contracted(m: int, c: int, seed: int) -> None:
    """An H curve whose knee is known. Within-cluster edges (length <= w = 2 sqrt(2) r) are
    all shorter than the gaps, so the first k0 = m (c - 1) contractions merge every
    cluster into one node and keep H <= w; any later one joins two clusters and makes
    H >= gap / 2 - w. With K = mc - 1 contractions in all and h(K) between gap / 2 - w
    and the diameter D of the nodes, the normalised x - y is at least k0 / K - w / (gap / 2
    - w) at k0, below (k0 - 1) / K before and below 1 - (gap / 2 - w) / D after: when the
    premises below hold, the knee is k0 and the landmarks are the clusters."""
    r, gap = 1e-4, 3.0
    pos, edges, cluster = _clusters(m, c, r, gap, seed)
    w = 2 * np.sqrt(2) * r
    big_k, k0 = m * c - 1, m * (c - 1)
    diameter = pdist(pos).max()  # h(K): the last node lies in the nodes' hull
    at_k0 = k0 / big_k - w / (gap / 2 - w)
    assert at_k0 > (k0 - 1) / big_k  # premise: the flat part rises to k0
    assert at_k0 > 1 - (gap / 2 - w) / diameter  # premise: every jump after k0 is too high
    lm = skeletonize((pos, edges))
    assert lm.k == k0 and lm.n_landmarks == m
    # every cluster became exactly one landmark
    assert len({(int(a), int(b)) for a, b in zip(cluster, lm.members, strict=True)}) == m


def test_knee_agrees_with_a_direct_reading_of_the_definition() -> None:
    """On a real context map: recompute the knee from the curve alone, as the point of
    the normalised running-max curve farthest (perpendicular distance) below its chord."""
    rng = np.random.default_rng(0)
    X = np.concatenate([rng.normal(c, 0.3, size=(800, 4)) for c in (0.0, 3.0, 6.0)])
    gng = GrowingNeuralGas(random_state=0).fit(X)
    lm = skeletonize(gng)
    assert len(lm.merges) == len(gng.nodes_) - 1 and len(lm.curve) == len(lm.merges) + 1
    h = np.array([max(lm.curve[: i + 1]) for i in range(len(lm.curve))])
    pts = np.c_[np.linspace(0, 1, len(h)), h / h[-1]]
    chord, d = pts[-1] - pts[0], pts - pts[0]
    below = (chord[1] * d[:, 0] - chord[0] * d[:, 1]) / np.hypot(*chord)  # signed distance
    assert lm.k == int(np.argmax(below))
    assert lm.n_landmarks == len(gng.nodes_) - lm.k
    assert 1 < lm.n_landmarks < len(gng.nodes_) // 4


def test_landmark_counts_are_stable_over_map_and_exploration_seeds() -> None:
    """10 worlds x 300 steps grow a 62-node map. Over 30 map seeds on the same readings
    the knee gave 5-16 landmarks, over 30 exploration seeds 6-13 (the curvature rule:
    12-59 and 5-59). Five of each must stay in 4-18 landmarks, and the knee must spread
    less than the curvature rule over the map seeds."""
    readings = explore(10, 300, seed=0).readings
    maps = [GrowingNeuralGas(random_state=s).fit(readings) for s in range(5)]
    by_map = [skeletonize(g).n_landmarks for g in maps]
    by_exploration = [
        skeletonize(
            GrowingNeuralGas(random_state=0).fit(explore(10, 300, seed=s).readings)
        ).n_landmarks
        for s in range(5)
    ]
    assert {len(g.nodes_) for g in maps} == {62}
    assert all(4 <= n <= 18 for n in by_map + by_exploration), (by_map, by_exploration)
    literal = [skeletonize(g, method="curvature").n_landmarks for g in maps]
    assert max(by_map) - min(by_map) < max(literal) - min(literal), (by_map, literal)


def test_bad_arguments() -> None:
    pos, edges = _random_graph(1)
    with pytest.raises(InvalidArgumentError, match="method must be"):
        skeletonize((pos, edges), method="spline")
    with pytest.raises(InvalidArgumentError, match="k must be in"):
        skeletonize((pos, edges), k=10_000)
    with pytest.raises(InvalidArgumentError, match="graph must be"):
        skeletonize("a graph")
    with pytest.raises(InvalidArgumentError, match="edges must join nodes"):
        skeletonize((pos, [(0, 99)]))


def _separated(k: int, seed: int, spread: float) -> np.ndarray:
    """k clusters of 400 points in 8-d, their centres at least 12 apart, each a Gaussian of
    standard deviation ``spread`` (12 apart against a radius of about 3 spread)."""
    rng = np.random.default_rng([k, seed])
    centres = rng.uniform(0, 1, (k, 8))
    gaps = [np.linalg.norm(a - b) for i, a in enumerate(centres) for b in centres[i + 1 :]]
    centres *= 12 / min(gaps)
    return np.vstack([c + spread * rng.standard_normal((400, 8)) for c in centres])


@pytest.mark.parametrize("k", [2, 3, 5, 8])
@pytest.mark.parametrize("spread", [0.05, 0.2])
def test_the_rule_finds_well_separated_clusters_whatever_the_seed(k: int, spread: float) -> None:
    from copi.learning import bootstrap_landmarks

    found = [bootstrap_landmarks(_separated(k, s, spread), resamples=8, seed=s)[0]
             for s in range(6)]  # fmt: skip
    assert found == [k] * 6
    # the literal maximum-curvature rule does not (it is kept as a named option)
    literal = [
        len(g.nodes_) - skeletonize(g, method="curvature").k
        for g in (GrowingNeuralGas(random_state=s).fit(x).prune_unused(x)
                  for s, x in ((s, _separated(k, s, spread)) for s in range(6)))
    ]  # fmt: skip
    assert literal != [k] * 6 or k == 2


def test_unused_nodes_are_pruned_and_the_network_keeps_learning() -> None:
    x = _separated(3, 0, 0.05)
    gng = GrowingNeuralGas(random_state=0).fit(x)
    before = len(gng.nodes_)
    used = np.bincount(gng.predict(x), minlength=before) > 0
    gng.prune_unused(x)
    assert len(gng.nodes_) == used.sum() < before  # strays between the clusters went
    assert (np.bincount(gng.predict(x), minlength=len(gng.nodes_)) > 0).all()
    assert gng.edges_.max() < len(gng.nodes_)
    gng.partial_fit(x[:200])  # its state stayed consistent
    assert len(gng.nodes_) >= used.sum()


def test_the_bootstrap_does_not_depend_on_the_workers() -> None:
    from copi.learning import bootstrap_landmarks

    x = _separated(3, 1, 0.3)
    one = bootstrap_landmarks(x, resamples=4, seed=2)
    two = bootstrap_landmarks(x, resamples=4, seed=2, workers=2)
    assert one == two and len(one[1]) == 4


def test_the_rules_of_earlier_versions_stay_named_options() -> None:
    from copi.learning import LearnParams, learn

    quick = {"worlds": 6, "steps": 120, "directions": 4}
    old = learn(LearnParams(**quick, skeleton_bootstrap=0))  # copi 0.2: the map's knee
    assert old.landmarks.k == int(np.argmax(old.landmarks.criterion))
    new = learn(LearnParams(**quick))
    stage = next(s for s in new.stats["stages"] if s["stage"] == "skeleton")
    assert new.landmarks.n_landmarks == stage["bootstrap_median"]
    lo, hi = stage["bootstrap_range"]
    assert lo <= new.landmarks.n_landmarks <= hi
    with pytest.raises(InvalidArgumentError, match="skeleton_bootstrap must be an int >= 0"):
        LearnParams(skeleton_bootstrap=-1)


@pytest.mark.slow
@pytest.mark.timeout(1800)  # ten learnings at full scale: ~10 s each alone, minutes when loaded
def test_the_landmark_count_moves_little_with_the_seed() -> None:
    """At copi learn's defaults, over 5 whole-pipeline seeds and over 5 map seeds on the
    same readings, the landmark count's max / min is at most 1.4, and below what the
    rule it replaced (copi 0.2's knee of the map's own H(k)) gives on the same maps.

    How the goal was set, from measurements (studies/landmarks.py, docs/landmarks.md):
    over ten seeds the count spreads 1.31 (whole pipeline) and 1.35 (map seeds), and
    these five seeds are five of those ten (42-54 landmarks either way: 1.29 each). The
    goal of 1.25 over map seeds, met (1.23) while the kernels' arithmetic depended on the
    processor, is not met with the processor-independent arithmetic copi has since, and
    is not claimed here. 1.4 is the ten seeds' spread with about one landmark's room;
    the old rule spreads 1.71 (map seeds) and 4.13 (whole) over these same seeds, so a
    return to it, or anything as unstable, fails."""
    from copi.learning import LearnParams, learn, skeletonize

    whole = [learn(LearnParams(seed=s, workers=2)) for s in range(5)]
    maps = [learn(LearnParams(seed=0, map_seed=s, workers=2)) for s in range(5)]
    for study, caps in (("whole pipeline", whole), ("map seeds", maps)):
        counts = [c.landmarks.n_landmarks for c in caps]
        knees = [skeletonize((c.nodes, c.edges), method="knee").n_landmarks for c in caps]
        spread = max(counts) / min(counts)
        assert spread <= 1.4, (study, counts)
        assert spread < max(knees) / min(knees), (study, counts, knees)
