from __future__ import annotations

import networkx as nx
import numpy as np
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial.distance import cdist
from sklearn.utils.estimator_checks import parametrize_with_checks

from copi.learning import GrowingNeuralGas
from copi.learning._gng import signal_stream
from copi.learning.reference import reference_gng


# Every scikit-learn check applies and passes: none is listed as an expected failure.
@parametrize_with_checks([GrowingNeuralGas(max_nodes=20, random_state=0)])
def test_sklearn_estimator_contract(estimator, check) -> None:
    check(estimator)


def _centres(rng: np.random.Generator, dim: int) -> np.ndarray:
    return rng.uniform(0, 10, size=(5, dim))


def _stream(n: int = 3000, dim: int = 6, seed: int = 0) -> np.ndarray:
    """Five Gaussian clusters (sd 0.7) around :func:`_centres`."""
    rng = np.random.default_rng(seed)
    centres = _centres(rng, dim)
    return centres[rng.integers(0, 5, n)] + rng.normal(0, 0.7, size=(n, dim))


@pytest.mark.parametrize("max_nodes", [None, 12])
def test_matches_the_plain_reference_on_the_same_stream(max_nodes) -> None:
    X = _stream()
    gng = GrowingNeuralGas(max_nodes, epochs=2, random_state=5).fit(X)
    first, order = signal_stream(len(X), 2, 5)
    nodes, edges = reference_gng(X, first, order, max_nodes=max_nodes)
    qe_ref = np.sqrt(cdist(X, nodes, "sqeuclidean").min(1)).mean()
    assert len(gng.nodes_) == len(nodes)
    assert abs(gng.quantization_error(X) / qe_ref - 1) < 0.02
    np.testing.assert_allclose(gng.nodes_, nodes, atol=1e-9)
    assert [tuple(e) for e in gng.edges_.tolist()] == edges


def test_growth_follows_lambda_and_max_nodes() -> None:
    X = _stream(2000)
    gng = GrowingNeuralGas(lambda_=50, epochs=1, random_state=0).fit(X)
    # one insertion per 50 signals from 2 nodes; isolated-node removal may take a few
    assert 2000 // 50 - 3 <= len(gng.nodes_) <= 2 + 2000 // 50
    assert gng.n_samples_seen_ == 2000
    capped = GrowingNeuralGas(10, random_state=0).fit(X)
    assert len(capped.nodes_) == 10


def test_partial_fit_continues_the_network() -> None:
    X = _stream(1200)
    gng = GrowingNeuralGas(random_state=1).partial_fit(X[:600])
    n_before = len(gng.nodes_)
    gng.partial_fit(X[600:])
    assert gng.n_samples_seen_ == 1200
    assert len(gng.nodes_) >= n_before
    first, _ = signal_stream(600, 0, 1)
    nodes, _ = reference_gng(X, first, np.arange(1200))
    np.testing.assert_allclose(gng.nodes_, nodes, atol=1e-9)


def test_edges_and_networkx_view() -> None:
    X = _stream(2000)
    gng = GrowingNeuralGas(random_state=2).fit(X)
    g = gng.to_networkx()
    assert g.number_of_nodes() == len(gng.nodes_)
    assert g.number_of_edges() == len(gng.edges_)
    assert (gng.edges_[:, 0] < gng.edges_[:, 1]).all()
    assert all(deg > 0 for _, deg in g.degree())  # isolated nodes are removed
    i, j = gng.edges_[0]
    assert g.edges[int(i), int(j)]["length"] == pytest.approx(
        np.linalg.norm(gng.nodes_[i] - gng.nodes_[j])
    )
    # The view's components are those of edges_ (counted apart), and they follow the
    # data's clusters: each cluster's nodes (by nearest centre) lie in one component, and
    # a component joins clusters only when their centres are close (seed 0's clusters 0
    # and 3 are 4.9 apart, under three typical radii 0.7 sqrt(6) = 1.7; the others >= 8.6).
    n_parts, part = connected_components(
        csr_matrix(
            (np.ones(len(gng.edges_)), (gng.edges_[:, 0], gng.edges_[:, 1])),
            shape=(len(gng.nodes_),) * 2,
        ),
        directed=False,
    )
    assert nx.number_connected_components(g) == n_parts
    centres = _centres(np.random.default_rng(0), 6)
    cluster = cdist(gng.nodes_, centres).argmin(1)
    assert all(len(set(part[cluster == c])) == 1 for c in range(5))
    for p in range(n_parts):
        joined = np.unique(cluster[part == p])
        assert cdist(centres[joined], centres[joined]).max() < 6.0
    close = cdist(centres, centres)[np.triu_indices(5, 1)] < 6.0
    assert int(close.sum()) == 1 and n_parts in (4, 5)


def test_predict_transform_score_agree() -> None:
    X = _stream(1500)
    gng = GrowingNeuralGas(random_state=3).fit(X)
    d = gng.transform(X[:50])
    np.testing.assert_array_equal(gng.predict(X[:50]), d.argmin(1))
    assert gng.score(X) == pytest.approx(-gng.quantization_error(X))
    np.testing.assert_allclose(gng.quantization_error(X[:50]), d.min(1).mean(), rtol=1e-9)


def test_bad_input_says_what() -> None:
    with pytest.raises(ValueError, match="NaN"):
        GrowingNeuralGas().fit(np.array([[0.0, np.nan], [1.0, 2.0]]))
    with pytest.raises(ValueError, match="eps_b"):
        GrowingNeuralGas(eps_b=2.0).fit(_stream(10))
    with pytest.raises(ValueError, match="at most 20000"):
        GrowingNeuralGas(lambda_=1).fit(np.random.default_rng(0).normal(size=(30000, 2)))
