"""Plain reference implementations of the learning algorithms, for tests and benchmarks.

Written the obvious way (numpy arithmetic, Python dicts and sets, no compilation), rule by
rule from the source papers, so that the compiled versions can be checked against them.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["reference_gng"]


def reference_gng(
    X: Any,
    first: Any,
    order: Any,
    *,
    max_nodes: int | None = None,
    eps_b: float = 0.2,
    eps_n: float = 0.006,
    lambda_: int = 100,
    max_age: int = 50,
    alpha: float = 0.5,
    d: float = 0.995,
) -> tuple[NDArray[np.float64], list[tuple[int, int]]]:
    """Fritzke's Growing Neural Gas fed the rows ``X[order]``, starting from the two
    nodes ``X[first]``; returns the nodes and the edges (i < j)."""
    X = np.asarray(X, dtype=np.float64)
    nodes: list[NDArray[np.float64]] = [X[first[0]].copy(), X[first[1]].copy()]
    errors: list[float] = [0.0, 0.0]
    adj: list[dict[int, int]] = [{}, {}]  # adj[i][j] = age of edge i-j
    seen = 0
    limit = max_nodes if max_nodes is not None else float("inf")

    def connect(i: int, j: int, age: int) -> None:
        adj[i][j] = age
        adj[j][i] = age

    def remove_node(i: int) -> None:
        # the last node takes the free slot, as in the compiled version
        last = len(nodes) - 1
        for j in list(adj[i]):
            del adj[j][i]
        if i != last:
            nodes[i], errors[i], adj[i] = nodes[last], errors[last], adj[last]
            for j in adj[i]:
                adj[j][i] = adj[j].pop(last)
        nodes.pop()
        errors.pop()
        adj.pop()

    for t in order:
        xi = X[t]
        dist = np.array([np.sum((xi - w) ** 2) for w in nodes])
        s1, s2 = (int(k) for k in np.argsort(dist, kind="stable")[:2])
        seen += 1
        errors[s1] += float(dist[s1])
        nodes[s1] = nodes[s1] + eps_b * (xi - nodes[s1])
        for k in adj[s1]:
            connect(s1, k, adj[s1][k] + 1)
            nodes[k] = nodes[k] + eps_n * (xi - nodes[k])
        connect(s1, s2, 0)
        k = 0
        while k < len(nodes):
            if adj[s1].get(k, -1) > max_age:
                del adj[s1][k]
                del adj[k][s1]
                if not adj[k]:
                    moved = s1 == len(nodes) - 1
                    remove_node(k)
                    s1 = k if moved else s1
                    continue
            k += 1
        if seen % lambda_ == 0 and len(nodes) < limit:
            q = int(np.argmax(errors))
            if adj[q]:
                f = max(sorted(adj[q]), key=lambda j: errors[j])
                r = len(nodes)
                nodes.append(0.5 * (nodes[q] + nodes[f]))
                errors.append(0.0)
                adj.append({})
                del adj[q][f]
                del adj[f][q]
                connect(q, r, 0)
                connect(r, f, 0)
                errors[q] *= alpha
                errors[f] *= alpha
                errors[r] = errors[q]
        errors = [e * d for e in errors]
    edges = sorted((i, j) for i in range(len(nodes)) for j in adj[i] if i < j)
    return np.array(nodes), edges
