"""Growing Neural Gas as a scikit-learn estimator (paper §II-A)."""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np
from numpy.typing import NDArray
from sklearn.base import BaseEstimator, ClusterMixin, TransformerMixin
from sklearn.utils import check_random_state
from sklearn.utils._param_validation import Interval
from sklearn.utils.validation import check_is_fitted, validate_data

from copi.learning import _gng_kernels

__all__ = ["GrowingNeuralGas"]

# Beyond this the (nodes x nodes) edge-age matrix would not fit comfortably in memory.
_MAX_CAPACITY = 20_000


class GrowingNeuralGas(ClusterMixin, TransformerMixin, BaseEstimator):  # type: ignore[misc]
    """Fritzke's Growing Neural Gas: a graph of nodes that grows to model the topology
    and the distribution of its input (Fritzke 1995; the paper's context map, §II-A).

    Every signal moves its nearest node by ``eps_b`` and that node's neighbours by
    ``eps_n``, connects the two nearest nodes, ages and prunes edges; every ``lambda_``
    signals a node is inserted where the accumulated error is largest. See
    ``copi.learning._gng_kernels.gng_run`` for the exact rules.

    Reaching the paper's scale: one node is inserted per ``lambda_`` = 100 signals, so the
    paper's 593 nodes take about 59,000 signals. copi's exploration collects 100 worlds x
    300 steps = 30,000 readings, and ``epochs=2`` (the default) feeds them twice, each pass
    in a fresh random order: 60,000 signals and about 600 nodes.

    Parameters
    ----------
    max_nodes : int or None
        Stop inserting nodes once the network has this many (adaptation goes on).
    eps_b, eps_n : float
        Learning rates of the winner and of its neighbours.
    lambda_ : int
        Signals between insertions.
    max_age : int
        Edges older than this are removed.
    alpha : float
        Error scaling of the two nodes an insertion splits.
    d : float
        Error decay per signal (Fritzke's 1 - beta).
    epochs : int
        Passes over the data in :meth:`fit`, each in a new random order.
    random_state : int, Generator, RandomState or None
        Drives the initial two nodes and the orders of the passes.

    Attributes
    ----------
    nodes_ : ndarray of shape (n_nodes, n_features)
    edges_ : ndarray of shape (n_edges, 2)
        Pairs (i, j), i < j, of connected nodes.
    errors_ : ndarray of shape (n_nodes,)
    n_samples_seen_ : int
        Signals fed so far (over all calls).
    labels_ : ndarray of shape (n_samples,)
        Nearest node of each training sample after :meth:`fit`.
    n_features_in_ : int

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> ring = np.column_stack([np.cos(t := rng.uniform(0, 2 * np.pi, 4000)), np.sin(t)])
    >>> gng = GrowingNeuralGas(max_nodes=20, random_state=0).fit(ring)
    >>> len(gng.nodes_), bool(gng.quantization_error(ring) < 0.2)
    (20, True)
    """

    _parameter_constraints: dict[str, list[Any]] = {
        "max_nodes": [Interval(numbers.Integral, 2, None, closed="left"), None],
        "eps_b": [Interval(numbers.Real, 0, 1, closed="both")],
        "eps_n": [Interval(numbers.Real, 0, 1, closed="both")],
        "lambda_": [Interval(numbers.Integral, 1, None, closed="left")],
        "max_age": [Interval(numbers.Integral, 1, None, closed="left")],
        "alpha": [Interval(numbers.Real, 0, 1, closed="both")],
        "d": [Interval(numbers.Real, 0, 1, closed="both")],
        "epochs": [Interval(numbers.Integral, 1, None, closed="left")],
        "random_state": ["random_state"],
    }

    def __init__(
        self,
        max_nodes: int | None = None,
        *,
        eps_b: float = 0.2,
        eps_n: float = 0.006,
        lambda_: int = 100,
        max_age: int = 50,
        alpha: float = 0.5,
        d: float = 0.995,
        epochs: int = 2,
        random_state: Any = None,
    ) -> None:
        self.max_nodes = max_nodes
        self.eps_b = eps_b
        self.eps_n = eps_n
        self.lambda_ = lambda_
        self.max_age = max_age
        self.alpha = alpha
        self.d = d
        self.epochs = epochs
        self.random_state = random_state

    # -- fitting --------------------------------------------------------------------

    def fit(self, X: Any, y: Any = None) -> GrowingNeuralGas:
        """Grow a new network on X for ``epochs`` passes, each in a random order."""
        self._validate_params()
        X = validate_data(self, X, dtype=np.float64, ensure_min_samples=2, reset=True)
        first, order = signal_stream(X.shape[0], self.epochs, self.random_state)
        self._init_state(X, first)
        self._feed(X, order)
        self.labels_ = self.predict(X)
        return self

    def partial_fit(self, X: Any, y: Any = None) -> GrowingNeuralGas:
        """Feed X once, in the given order, to the network (started on first call with
        two random rows of X). Used for continual learning online (paper §III)."""
        first = not hasattr(self, "nodes_")
        if first:
            self._validate_params()
        X = validate_data(
            self, X, dtype=np.float64, ensure_min_samples=2 if first else 1, reset=first
        )
        if first:
            self._init_state(X, signal_stream(X.shape[0], 0, self.random_state)[0])
        self._feed(X, np.arange(X.shape[0]))
        return self

    def _init_state(self, X: NDArray[np.float64], first: NDArray[np.int64]) -> None:
        self._w = np.zeros((2, X.shape[1]))
        self._w[0], self._w[1] = X[first[0]], X[first[1]]
        self._err = np.zeros(2)
        self._age = np.full((2, 2), -1, dtype=np.int32)
        self._nbr = np.zeros((2, 2), dtype=np.int32)
        self._deg = np.zeros(2, dtype=np.int32)
        self._n = 2
        self.n_samples_seen_ = 0
        self._publish()

    def _feed(self, X: NDArray[np.float64], order: NDArray[np.int64]) -> None:
        limit = self.max_nodes if self.max_nodes is not None else np.iinfo(np.int64).max
        grow = (self.n_samples_seen_ % self.lambda_ + len(order)) // self.lambda_
        cap = int(min(limit, self._n + grow))
        if cap > _MAX_CAPACITY:
            raise ValueError(
                f"GrowingNeuralGas would grow to {cap} nodes; at most {_MAX_CAPACITY} are "
                "supported: set max_nodes or feed fewer signals"
            )
        self._reserve(max(cap, self._n))
        n, seen = _gng_kernels.gng_run(
            np.ascontiguousarray(X),
            np.ascontiguousarray(order, dtype=np.int64),
            self._w,
            self._err,
            self._age,
            self._nbr,
            self._deg,
            self._n,
            self.n_samples_seen_,
            int(min(limit, _MAX_CAPACITY)),
            float(self.eps_b),
            float(self.eps_n),
            int(self.lambda_),
            int(self.max_age),
            float(self.alpha),
            float(self.d),
        )
        self._n = int(n)
        self.n_samples_seen_ = int(seen)
        self._publish()

    def _reserve(self, cap: int) -> None:
        old = self._w.shape[0]
        if cap <= old:
            return
        w = np.zeros((cap, self._w.shape[1]))
        w[:old] = self._w
        err = np.zeros(cap)
        err[:old] = self._err
        age = np.full((cap, cap), -1, dtype=np.int32)
        age[:old, :old] = self._age
        nbr = np.zeros((cap, cap), dtype=np.int32)
        nbr[:old, :old] = self._nbr
        deg = np.zeros(cap, dtype=np.int32)
        deg[:old] = self._deg
        self._w, self._err, self._age, self._nbr, self._deg = w, err, age, nbr, deg

    def _publish(self) -> None:
        n = self._n
        self.nodes_ = self._w[:n].copy()
        self.errors_ = self._err[:n].copy()
        i, j = np.nonzero(np.triu(self._age[:n, :n] >= 0, k=1))
        self.edges_ = np.column_stack([i, j]).astype(np.int64)

    def prune_unused(self, X: Any) -> GrowingNeuralGas:
        """Remove the nodes no row of X is nearest to (and their edges); returns self.

        Growing inserts a node halfway between the node of largest error and its worst
        neighbour; between well-separated groups of signals such a node may never be any
        signal's nearest, and a node that stands for no context is not a context (GNG-U,
        Fritzke 1997, removes such units by their utility). On copi's maps of readings no
        node is unused; on data in separate clusters the strays between them are.

        Examples
        --------
        >>> import numpy as np
        >>> rng = np.random.default_rng(0)
        >>> X = np.vstack([rng.normal(c, 0.05, (300, 2)) for c in (0.0, 10.0)])
        >>> gng = GrowingNeuralGas(random_state=0).fit(X)
        >>> bool(np.bincount(gng.prune_unused(X).predict(X), minlength=len(gng.nodes_)).min() > 0)
        True
        """
        labels = self.predict(X)
        n = self._n
        counts = np.bincount(labels, minlength=n)
        keep = counts > 0
        if keep.all():
            return self
        if keep.sum() < 2:  # a network keeps two nodes at least
            keep[np.argsort(-counts, kind="stable")[:2]] = True
        idx = np.flatnonzero(keep)
        remap = np.full(n, -1, dtype=np.int64)
        remap[idx] = np.arange(len(idx))
        cap = self._w.shape[0]
        w = np.zeros_like(self._w)
        w[: len(idx)] = self._w[idx]
        err = np.zeros_like(self._err)
        err[: len(idx)] = self._err[idx]
        age = np.full((cap, cap), -1, dtype=np.int32)
        age[: len(idx), : len(idx)] = self._age[np.ix_(idx, idx)]
        nbr = np.zeros((cap, cap), dtype=np.int32)
        deg = np.zeros(cap, dtype=np.int32)
        for new, old in enumerate(idx):
            kept = [int(remap[j]) for j in self._nbr[old, : self._deg[old]] if keep[j]]
            nbr[new, : len(kept)] = kept
            deg[new] = len(kept)
        self._w, self._err, self._age, self._nbr, self._deg = w, err, age, nbr, deg
        self._n = len(idx)
        self._publish()
        self.labels_ = self.predict(X)
        return self

    # -- using the network ---------------------------------------------------------

    def predict(self, X: Any) -> NDArray[np.int64]:
        """Index of the nearest node of each row of X."""
        idx, _ = self._nearest(X)
        return idx

    def transform(self, X: Any) -> NDArray[np.float64]:
        """Euclidean distances from each row of X to every node, shape (n, n_nodes)."""
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        d2 = (X**2).sum(1)[:, None] - 2 * X @ self.nodes_.T + (self.nodes_**2).sum(1)[None, :]
        return np.sqrt(np.maximum(d2, 0.0))

    def quantization_error(self, X: Any) -> float:
        """Mean Euclidean distance from the rows of X to their nearest nodes."""
        _, d2 = self._nearest(X)
        return float(np.sqrt(d2).mean())

    def score(self, X: Any, y: Any = None) -> float:
        """Negative quantization error (greater is better, as scikit-learn expects)."""
        return -self.quantization_error(X)

    def _nearest(self, X: Any) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        idx = np.empty(X.shape[0], dtype=np.int64)
        d2 = np.empty(X.shape[0])
        _gng_kernels.nearest(np.ascontiguousarray(X), self.nodes_, len(self.nodes_), idx, d2)
        return idx, d2

    def to_networkx(self) -> Any:
        """The network as a ``networkx.Graph``: node i has attribute ``pos`` (its vector)
        and ``error``; edges have ``length`` (Euclidean)."""
        import networkx as nx

        check_is_fitted(self)
        g = nx.Graph()
        for i, (p, e) in enumerate(zip(self.nodes_, self.errors_, strict=True)):
            g.add_node(i, pos=p, error=float(e))
        for i, j in self.edges_:
            g.add_edge(
                int(i), int(j), length=float(np.linalg.norm(self.nodes_[i] - self.nodes_[j]))
            )
        return g

    def __sklearn_is_fitted__(self) -> bool:
        # The parameter lambda_ ends with "_", which scikit-learn's default test would
        # mistake for a fitted attribute.
        return hasattr(self, "nodes_")

    def __sklearn_tags__(self) -> Any:
        tags = super().__sklearn_tags__()
        tags.non_deterministic = False
        return tags


def signal_stream(
    n_samples: int, epochs: int, random_state: Any
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """The rows that seed the first two nodes, and the order in which :meth:`fit` feeds
    the samples (``epochs`` random permutations, one after the other)."""
    rng = check_random_state(_legacy_seed(random_state))
    first = rng.choice(n_samples, size=2, replace=False).astype(np.int64)
    order = [rng.permutation(n_samples) for _ in range(epochs)]
    return first, (np.concatenate(order) if order else np.zeros(0, dtype=np.int64))


def _legacy_seed(seed: Any) -> Any:
    """scikit-learn's check_random_state takes ints and RandomState; turn a numpy
    Generator into a RandomState seeded from it (so copi's one seeding idiom works)."""
    if isinstance(seed, np.random.Generator):
        return np.random.RandomState(seed.integers(2**32 - 1))
    return seed
