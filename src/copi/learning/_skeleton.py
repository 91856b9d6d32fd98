"""Skeletonisation of the context map into landmarks (paper §II-B)."""

from __future__ import annotations

import heapq
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import shortest_path

from copi.errors import InvalidArgumentError

__all__ = ["Landmarks", "skeletonize"]


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
        heap.append((float(np.linalg.norm(pos[u] - pos[v])), min(u, v), max(u, v)))
    heapq.heapify(heap)
    sq = (pos**2).sum(1)
    dist = np.full((n, cap), np.inf)
    dist[:, :n] = np.sqrt(np.maximum(sq[:, None] - 2 * pos @ pos.T + sq[None, :], 0.0))
    np.fill_diagonal(dist[:, :n], 0.0)
    near = np.zeros(n)  # distance from each original to the nearest live node
    near_of = np.arange(n)  # ... and which node that is
    far = np.zeros(cap)  # distance from each node to the nearest original
    curve = [0.0]
    merges = []
    m = n
    while heap:
        _, u, v = heapq.heappop(heap)
        if not (alive[u] and alive[v] and v in adj[u]):
            continue
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
                            heap, (float(np.linalg.norm(p[w] - p[b])), min(w, b), max(w, b))
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
    to K_max, when no edge is left. The skeleton is the G^k where the curve H bends most.

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
    if method not in ("knee", "curvature"):
        raise InvalidArgumentError(f"method must be 'knee' or 'curvature'; got {method!r}")
    pos, edges = _graph_arrays(graph)
    n = pos.shape[0]
    if n == 0:
        raise InvalidArgumentError("the graph has no nodes")
    if edges.size and (edges.min() < 0 or edges.max() >= n):
        raise InvalidArgumentError(f"edges must join nodes 0..{n - 1}")
    curve, merges, allpos = _contract(pos, edges)
    kmax = len(curve) - 1
    envelope = np.maximum.accumulate(curve)
    if method == "knee":
        x = np.arange(kmax + 1) / max(kmax, 1)
        criterion = x - envelope / envelope.max() if envelope.max() > 0 else np.zeros_like(x)
    else:
        w = window if window is not None else max(1, round(0.02 * kmax))
        criterion = _curvature(envelope, w)
    if n_landmarks is not None:
        if not n - kmax <= n_landmarks <= n:
            raise InvalidArgumentError(
                f"n_landmarks must be in {n - kmax}..{n} (the map has {n} nodes in "
                f"{n - kmax} connected components); got {n_landmarks}"
            )
        k = n - int(n_landmarks)
    if k is None:
        chosen = int(np.argmax(criterion)) if criterion.max() > 0 else kmax
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
        criterion=criterion,
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
