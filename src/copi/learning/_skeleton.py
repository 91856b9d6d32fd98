"""Skeletonisation of the context map into landmarks (paper §II-B)."""

from __future__ import annotations

import heapq
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import shortest_path
from scipy.spatial.distance import cdist

from copi.errors import InvalidArgumentError

__all__ = ["METHODS", "Landmarks", "bootstrap_landmarks", "choose_k", "skeletonize"]


@dataclass(frozen=True, eq=False)
class Landmarks:
    """The skeleton G^K of a context map: landmark contexts and who they stand for."""

    points: NDArray[np.float64]
    """Landmark contexts X^ (the nodes of G^K), shape (n_landmarks, n_features)."""
    members: NDArray[np.int64]
    """For every node of the map, the landmark it was contracted into, shape (n_nodes,)."""
    node_landmark: NDArray[np.int64]
    """For every node of the map, its landmark by graph distance d_G (paper §III): the
    landmark whose anchor is the fewest links away, ties to the nearer in the state
    space; shape (n_nodes,)."""
    anchors: NDArray[np.int64]
    """For every landmark, the map node it stands on: its member nearest to it."""
    curve: NDArray[np.float64]
    """H(k), the Hausdorff distance between the map's nodes and those of G^k, for
    k = 0 .. K_max (the number of contractions until no edge is left)."""
    criterion: NDArray[np.float64]
    """The quantity maximised to choose k, for every k (see :func:`skeletonize`)."""
    k: int
    """The chosen refinement G^k."""
    merges: NDArray[np.int64]
    """The contraction sequence: row k = (u, v, w), edge (u, v) contracted into new node w
    (nodes numbered as the map's, new nodes from n_nodes on)."""

    @property
    def n_landmarks(self) -> int:
        return int(self.points.shape[0])


def _graph_arrays(graph: Any) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """(positions, edges) of a fitted GrowingNeuralGas, a networkx graph with node
    attribute ``pos`` (nodes 0..n-1), or a (positions, edges) pair."""
    if hasattr(graph, "nodes_") and hasattr(graph, "edges_"):
        return np.asarray(graph.nodes_, dtype=np.float64), np.asarray(graph.edges_, dtype=np.int64)
    if isinstance(graph, tuple) and len(graph) == 2:
        pos, edges = graph
        return np.asarray(pos, dtype=np.float64), np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    if hasattr(graph, "nodes") and hasattr(graph, "edges"):
        n = graph.number_of_nodes()
        if sorted(graph.nodes) != list(range(n)):
            raise InvalidArgumentError("graph nodes must be numbered 0..n-1")
        try:
            pos = np.array([graph.nodes[i]["pos"] for i in range(n)], dtype=np.float64)
        except KeyError:
            raise InvalidArgumentError("every graph node needs a 'pos' attribute") from None
        return pos, np.array(list(graph.edges), dtype=np.int64).reshape(-1, 2)
    raise InvalidArgumentError(
        "graph must be a fitted GrowingNeuralGas, a networkx graph with 'pos', or "
        f"(positions, edges); got {type(graph).__name__}"
    )


def _length(v: NDArray[np.float64]) -> float:
    """Euclidean length of ``v``, summed by numpy's fixed pairwise order: not by
    ``np.linalg.norm``, whose dot product is BLAS's, summed in the order of the kernel
    BLAS picks for the processor (so edge lengths, and which of two near-equal edges is
    contracted first, moved with the machine)."""
    return float(np.sqrt((v * v).sum()))


def _contract(pos: NDArray[np.float64], edges: NDArray[np.int64]):  # type: ignore[no-untyped-def]
    """Contract shortest edges until none is left, tracking the Hausdorff distance.

    Distances from the original nodes are kept for every node ever made (n x 2n floats);
    each step adds one column (O(n d)) instead of recomputing all pairs."""
    n, dim = pos.shape
    cap = 2 * n
    p = np.zeros((cap, dim))
    p[:n] = pos
    alive = np.zeros(cap, dtype=bool)
    alive[:n] = True
    adj: list[set[int]] = [set() for _ in range(cap)]
    heap: list[tuple[float, int, int]] = []
    for u, v in edges:
        u, v = int(u), int(v)
        if u == v or v in adj[u]:
            continue
        adj[u].add(v)
        adj[v].add(u)
        heap.append((_length(pos[u] - pos[v]), min(u, v), max(u, v)))
    heapq.heapify(heap)
    dist = np.full((n, cap), np.inf)
    dist[:, :n] = cdist(pos, pos)  # differences first: no BLAS (see _length)
    np.fill_diagonal(dist[:, :n], 0.0)
    near = np.zeros(n)  # distance from each original to the nearest live node
    near_of = np.arange(n)  # ... and which node that is
    far = np.zeros(cap)  # distance from each node to the nearest original
    curve = [0.0]
    merges = []
    m = n
    def pop() -> tuple[int, int] | None:
        """The next pair to contract: the shortest live edge; when no edge is left but
        the map is in pieces, the closest pair of live nodes of different pieces (so that
        the refinements end in one node, as a connected map's do)."""
        while heap:
            _, u, v = heapq.heappop(heap)
            if alive[u] and alive[v] and v in adj[u]:
                return u, v
        live = np.flatnonzero(alive[:m])
        if len(live) < 2:
            return None
        q = p[live]
        d = ((q[:, None, :] - q[None, :, :]) ** 2).sum(-1)
        np.fill_diagonal(d, np.inf)
        i, j = np.unravel_index(int(np.argmin(d)), d.shape)
        return int(min(live[i], live[j])), int(max(live[i], live[j]))

    while (pair := pop()) is not None:
        u, v = pair
        w = m
        m += 1
        p[w] = 0.5 * (p[u] + p[v])
        alive[u] = alive[v] = False
        alive[w] = True
        for a in (u, v):
            for b in adj[a]:
                if b not in (u, v):
                    adj[b].discard(a)
                    if b not in adj[w]:
                        adj[b].add(w)
                        adj[w].add(b)
                        heapq.heappush(
                            heap, (_length(p[w] - p[b]), min(w, b), max(w, b))
                        )
            adj[a] = set()
        merges.append((u, v, w))
        col = np.sqrt(((pos - p[w]) ** 2).sum(1))
        dist[:, w] = col
        far[w] = col.min()
        lost = (near_of == u) | (near_of == v)
        better = ~lost & (col < near)
        near[better] = col[better]
        near_of[better] = w
        if lost.any():
            live = np.flatnonzero(alive[:m])
            sub = dist[np.ix_(np.flatnonzero(lost), live)]
            arg = sub.argmin(1)
            near[lost] = sub[np.arange(len(arg)), arg]
            near_of[lost] = live[arg]
        curve.append(max(float(near.max()), float(far[:m][alive[:m]].max())))
    return np.array(curve), np.array(merges, dtype=np.int64).reshape(-1, 3), p[:m]


def _curvature(curve: NDArray[np.float64], window: int) -> NDArray[np.float64]:
    """Signed Menger curvature of the normalised curve (k / K, H / max H) through the
    points k - window, k, k + window (zero where the window does not fit)."""
    kmax = len(curve) - 1
    out = np.zeros(len(curve))
    if kmax < 2 * window or curve.max() <= 0:
        return out
    x = np.arange(len(curve)) / kmax
    y = curve / curve.max()
    k = np.arange(window, kmax - window + 1)
    ax, ay = x[k - window], y[k - window]
    bx, by = x[k], y[k]
    cx, cy = x[k + window], y[k + window]
    cross = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    ab = np.hypot(bx - ax, by - ay)
    bc = np.hypot(cx - bx, cy - by)
    ca = np.hypot(cx - ax, cy - ay)
    out[k] = 2 * cross / (ab * bc * ca)
    return out


METHODS = ("knee", "curvature", "lmethod", "log-knee", "log-lmethod")
"""The rules that choose the refinement k from H(k) (see :func:`skeletonize`)."""


def _envelope(curve: NDArray[np.float64]) -> NDArray[np.float64]:
    """H's running maximum, normalised to [0, 1] (H may dip a little when a contraction
    lands a node closer to the originals)."""
    env = np.maximum.accumulate(np.asarray(curve, dtype=np.float64))
    return env / env.max() if env.max() > 0 else env


def _two_lines(x: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray[np.float64]:
    """For every breakpoint c, the total squared error of the best line through the points
    0..c and of the best line through c..end (the L-method of Salvador and Chan,
    "Determining the number of clusters/segments in hierarchical clustering/segmentation
    algorithms", ICTAI 2004), from prefix sums in O(n); +inf where a side has fewer than
    two points."""
    n = len(x)

    def sse(cx, cy, cxx, cyy, cxy, m):  # type: ignore[no-untyped-def]
        # residual sum of squares of the least-squares line over m points
        vx = cxx - cx * cx / m
        vy = cyy - cy * cy / m
        vxy = cxy - cx * cy / m
        with np.errstate(invalid="ignore", divide="ignore"):
            out = vy - np.where(vx > 0, vxy * vxy / vx, 0.0)
        return np.maximum(out, 0.0)

    px, py = np.cumsum(x), np.cumsum(y)
    pxx, pyy, pxy = np.cumsum(x * x), np.cumsum(y * y), np.cumsum(x * y)
    c = np.arange(n)
    m_left = c + 1.0
    left = sse(px, py, pxx, pyy, pxy, m_left)
    tx, ty, txx, tyy, txy = px[-1], py[-1], pxx[-1], pyy[-1], pxy[-1]
    # the right side starts at c (the breakpoint belongs to both lines)
    rx = tx - np.r_[0.0, px[:-1]]
    ry = ty - np.r_[0.0, py[:-1]]
    rxx = txx - np.r_[0.0, pxx[:-1]]
    ryy = tyy - np.r_[0.0, pyy[:-1]]
    rxy = txy - np.r_[0.0, pxy[:-1]]
    m_right = n - c + 0.0
    right = sse(rx, ry, rxx, ryy, rxy, m_right)
    total = left + right
    total[(m_left < 2) | (m_right < 2)] = np.inf
    return total


def criterion(curve: NDArray[np.float64], method: str, window: int | None = None,
              n_nodes: int | None = None) -> NDArray[np.float64]:  # fmt: skip
    """The quantity a rule maximises over k = 0 .. K_max (see :func:`skeletonize`)."""
    if method not in METHODS:
        raise InvalidArgumentError(f"method must be one of {', '.join(METHODS)}; got {method!r}")
    kmax = len(curve) - 1
    y = _envelope(curve)
    if kmax < 1 or y.max() <= 0:
        return np.zeros(len(curve))
    if method in ("log-knee", "log-lmethod"):
        n = n_nodes if n_nodes is not None else kmax + 1
        # the landmarks left after k contractions, on a log scale: 1 at the map, 0 at the end
        left = np.log(np.maximum(n - np.arange(kmax + 1), 1))
        x = (left[0] - left) / max(left[0] - left[-1], 1e-12)
    else:
        x = np.arange(kmax + 1) / kmax
    if method in ("knee", "log-knee"):
        return x - y
    if method == "curvature":
        w = window if window is not None else max(1, round(0.02 * kmax))
        return _curvature(y, w)
    return -_two_lines(x, y)


def choose_k(curve: NDArray[np.float64], method: str = "knee", *, window: int | None = None,
             n_nodes: int | None = None) -> int:  # fmt: skip
    """The refinement k a rule chooses on H(k) (K_max when the curve is flat)."""
    c = criterion(curve, method, window, n_nodes)
    if method in ("lmethod", "log-lmethod"):
        finite = np.isfinite(c)
        return int(np.argmax(np.where(finite, c, -np.inf))) if finite.any() else len(curve) - 1
    return int(np.argmax(c)) if c.max() > 0 else len(curve) - 1


def bootstrap_landmarks(
    contexts: NDArray[np.float64],
    *,
    resamples: int = 32,
    method: str = "knee",
    seed: int = 0,
    max_nodes: int | None = None,
    epochs: int = 2,
    workers: int = 1,
    progress: Any = None,
) -> tuple[int, list[int]]:
    """(landmark count, the count of every resample): the median, over ``resamples``
    context maps grown on bootstrap resamples of ``contexts``, of the landmarks the rule
    ``method`` chooses on each map's H(k) (paper §II-B, read robustly).

    A context map's H(k) is a staircase, and the k a rule reads from one map moves with
    the seed: on the default ``learn`` data the knee of single maps gave 23 to 95
    landmarks over five seeds. The rule's choice on one map is a noisy estimate of the
    choice on the data; its median over maps of resampled data is not (over five seeds,
    ten with ``studies/landmarks.py``: max / min 1.16 over whole pipelines, 1.06 over
    map seeds on the same readings). Resample b draws its readings and its map from
    ``default_rng([seed, 1000 + b])``, so the result does not depend on ``workers``.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> centres = 10 * np.eye(4)  # four well-separated clusters in 4-d
    >>> x = np.vstack([c + 0.2 * rng.standard_normal((150, 4)) for c in centres])
    >>> bootstrap_landmarks(x, resamples=8, seed=1, max_nodes=40)[0]
    4
    """
    if method not in METHODS:
        raise InvalidArgumentError(f"method must be one of {', '.join(METHODS)}; got {method!r}")
    if int(resamples) != resamples or resamples < 1:
        raise InvalidArgumentError(f"resamples must be a positive int; got {resamples!r}")
    x = np.asarray(contexts, dtype=np.float64)
    jobs = [(x, b, method, seed, max_nodes, epochs) for b in range(int(resamples))]
    counts: list[int] = []
    if workers > 1:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        ctx = multiprocessing.get_context("fork" if "fork" in
                                          multiprocessing.get_all_start_methods() else "spawn")
        with ProcessPoolExecutor(workers, mp_context=ctx) as pool:
            for c in pool.map(_resample_count, jobs):
                counts.append(c)
                if progress is not None:
                    progress(len(counts), len(jobs))
    else:
        for job in jobs:
            counts.append(_resample_count(job))
            if progress is not None:
                progress(len(counts), len(jobs))
    return int(np.round(np.median(counts))), counts


def _resample_count(job: tuple[Any, ...]) -> int:
    """The landmarks ``method`` chooses on the map of bootstrap resample b."""
    from copi.learning._gng import GrowingNeuralGas

    x, b, method, seed, max_nodes, epochs = job
    rng = np.random.default_rng([seed, 1000 + b])
    sample = x[rng.integers(0, len(x), len(x))]
    gng = GrowingNeuralGas(max_nodes, epochs=epochs, random_state=int(rng.integers(2**31)))
    gng.fit(sample).prune_unused(sample)
    pos, edges = np.asarray(gng.nodes_), np.asarray(gng.edges_)
    curve, _, _ = _contract(pos, edges)
    return len(pos) - choose_k(curve, method, n_nodes=len(pos))


def skeletonize(
    graph: Any,
    *,
    method: str = "knee",
    window: int | None = None,
    k: int | None = None,
    n_landmarks: int | None = None,
) -> Landmarks:
    """Landmarks of a context map by repeated edge contraction (paper §II-B).

    G^0 is the map. G^{k+1} contracts the shortest edge (Euclidean length in the state
    space) of G^k into a node at its midpoint, relabelling the edges of both ends to it.
    H(k) is the Hausdorff distance between the nodes of G^0 and of G^k (eq. 1), for k up
    to K_max, when no edge is left; a map in several pieces then goes on contracting the
    closest pair of nodes of different pieces, until one node is left (copi's addition:
    so that well-separated groups of contexts, which a GNG leaves unconnected, show on H
    as the jump they are). The skeleton is the G^k where the curve H bends most.

    Both axes are normalised to [0, 1]: x = k / K_max, y = h(k) / h(K_max), where h is
    the running maximum of H (H itself may dip by a little when a contraction lands a
    node closer to the originals; the running max removes those dips).

    The paper takes "the refined network maximising the curvature of H". ``method="knee"``
    (default) reads that as the knee of the normalised curve: the k maximising x - y, the
    point farthest below the chord from (0, 0) to (1, 1), as Kneedle defines a knee
    (Satopää et al., "Finding a 'Kneedle' in a Haystack", 2011). That is not in general
    where the curvature peaks: on y = x^4 over [0, 1] the knee is at x = 4^(-1/3) ~ 0.63,
    the curvature maximum at x = 56^(-1/6) ~ 0.51. It is chosen because on the real H, a
    staircase of jumps, it is stable where a discrete curvature is not, whose maximum
    lands on whichever jump is sharpest at the stencil's scale (see ``copi figures``): at
    the default ``learn`` scale the knee gave 38-65 landmarks over five map seeds on the
    same readings and 32-78 over five exploration seeds, the curvature rule 48-562 and
    96-562.

    ``method="curvature"`` takes the literal maximum of the discrete curvature: the signed
    Menger curvature (1 / radius of the circle through the points at k - w, k, k + w, w =
    ``window``, default 2 % of K_max, at least 1), positive where the curve turns upwards.

    Parameters
    ----------
    graph : fitted GrowingNeuralGas, networkx.Graph with node attribute ``pos``, or a
        (positions, edges) pair.
    method : {"knee", "curvature"}
    window : int, optional
        Half-width w of the curvature stencil (method "curvature").
    k : int, optional
        Use this refinement instead.
    n_landmarks : int, optional
        Use the refinement with this many nodes instead (at least the number of
        connected components).

    Examples
    --------
    >>> pos = np.array([[0.0], [0.1], [0.2], [5.0], [5.1], [5.2]])
    >>> edges = [(0, 1), (1, 2), (3, 4), (4, 5), (2, 3)]
    >>> lm = skeletonize((pos, edges), n_landmarks=2)
    >>> lm.n_landmarks, lm.members.tolist()
    (2, [0, 0, 0, 1, 1, 1])
    """
    if method not in METHODS:
        raise InvalidArgumentError(f"method must be one of {', '.join(METHODS)}; got {method!r}")
    pos, edges = _graph_arrays(graph)
    n = pos.shape[0]
    if n == 0:
        raise InvalidArgumentError("the graph has no nodes")
    if edges.size and (edges.min() < 0 or edges.max() >= n):
        raise InvalidArgumentError(f"edges must join nodes 0..{n - 1}")
    curve, merges, allpos = _contract(pos, edges)
    kmax = len(curve) - 1
    crit = criterion(curve, method, window, n)
    if n_landmarks is not None:
        if not n - kmax <= n_landmarks <= n:
            raise InvalidArgumentError(
                f"n_landmarks must be in {n - kmax}..{n} (the map has {n} nodes); got "
                f"{n_landmarks}"
            )
        k = n - int(n_landmarks)
    if k is None:
        chosen = choose_k(curve, method, window=window, n_nodes=n)
    else:
        if not 0 <= k <= kmax:
            raise InvalidArgumentError(f"k must be in 0..{kmax}; got {k}")
        chosen = int(k)
    # Follow the first `chosen` merges to find every node's surviving representative.
    parent = np.arange(len(allpos))
    for u, v, wnode in merges[:chosen]:
        parent[u] = wnode
        parent[v] = wnode
    root = np.arange(len(allpos))
    for i in range(len(allpos) - 1, -1, -1):  # merged nodes point to later ones
        root[i] = root[parent[i]] if parent[i] != i else i
    alive = np.ones(len(allpos), dtype=bool)
    alive[n + chosen :] = False
    alive[merges[:chosen, :2].ravel()] = False
    survivors = np.flatnonzero(alive)
    index = np.full(len(allpos), -1)
    index[survivors] = np.arange(len(survivors))
    members = index[root[:n]]
    points = allpos[survivors]
    anchors = np.empty(len(survivors), dtype=np.int64)
    for j in range(len(survivors)):
        own = np.flatnonzero(members == j)
        anchors[j] = own[np.argmin(((pos[own] - points[j]) ** 2).sum(1))]
    node_landmark = _by_graph_distance(pos, edges, points, anchors)
    return Landmarks(
        points=points,
        members=members.astype(np.int64),
        node_landmark=node_landmark,
        anchors=anchors,
        curve=curve,
        criterion=crit,
        k=chosen,
        merges=merges,
    )


def _by_graph_distance(
    pos: NDArray[np.float64],
    edges: NDArray[np.int64],
    points: NDArray[np.float64],
    anchors: NDArray[np.int64],
) -> NDArray[np.int64]:
    """Each node's landmark by hop distance from the landmarks' anchors (d_G, §III),
    ties broken by Euclidean distance to the landmark."""
    n = pos.shape[0]
    if len(edges):
        a = csr_matrix(
            (
                np.ones(2 * len(edges)),
                (np.r_[edges[:, 0], edges[:, 1]], np.r_[edges[:, 1], edges[:, 0]]),
            ),
            shape=(n, n),
        )
    else:
        a = csr_matrix((n, n))
    hops = shortest_path(a, unweighted=True, indices=anchors)  # (L, n), inf if unreachable
    eu = np.sqrt(((pos[None, :, :] - points[:, None, :]) ** 2).sum(-1))
    key = np.where(np.isfinite(hops), hops, np.inf)
    best = key.min(0)
    tied = key == best[None, :]
    return np.where(tied, eu, np.inf).argmin(0).astype(np.int64)
