from __future__ import annotations

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.distance import directed_hausdorff

from copi.errors import InvalidArgumentError
from copi.learning import GrowingNeuralGas, skeletonize


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
        assert np.linalg.norm(nodes[u] - nodes[v]) == pytest.approx(min(lengths))
        nodes[w] = (nodes.pop(u) + nodes.pop(v)) / 2
        adj[w] = (adj.pop(u) | adj.pop(v)) - {u, v}
        for b in adj[w]:
            adj[b] = (adj[b] - {u, v}) | {w}
        sets.append(np.array(list(nodes.values())))
    assert not any(adj.values())  # contracted until no edge is left
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
    if want < nx.number_connected_components(g):
        with pytest.raises(InvalidArgumentError, match="n_landmarks must be in"):
            skeletonize((pos, edges), n_landmarks=want)
        return
    lm = skeletonize((pos, edges), n_landmarks=want)
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


def test_on_a_context_map_the_knee_is_stable_and_fast_enough() -> None:
    rng = np.random.default_rng(0)
    X = np.concatenate([rng.normal(c, 0.3, size=(800, 4)) for c in (0.0, 3.0, 6.0)])
    gng = GrowingNeuralGas(random_state=0).fit(X)
    lm = skeletonize(gng)
    assert 1 <= lm.n_landmarks < len(gng.nodes_)
    assert lm.criterion[lm.k] == lm.criterion.max()
    components = nx.number_connected_components(gng.to_networkx())
    assert len(lm.merges) == len(gng.nodes_) - components and len(lm.curve) == len(lm.merges) + 1
    lit = skeletonize(gng, method="curvature", window=3)
    assert lit.criterion[lit.k] == lit.criterion.max()


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
