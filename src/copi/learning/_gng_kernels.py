"""Compiled Growing Neural Gas (Fritzke 1995), one signal at a time.

Why by hand: GNG is sequential (each signal moves the nodes the next one is compared with),
so it cannot be vectorised over signals, and no maintained library implements it with
Fritzke's exact rules at speed (mdp takes about 21 s and neupy 6 s for 60,000 signals of
32-d data growing to 600 nodes). A compiled loop does it in about a tenth of a second.

State, all preallocated for ``cap`` nodes: ``w`` (cap, d) positions, ``err`` (cap,)
accumulated errors, ``age`` (cap, cap) int32 edge ages with -1 for "no edge" (symmetric),
``deg`` (cap,) degrees and ``nbr`` (cap, cap) neighbour lists (row i: the deg[i]
neighbours of i, in no order), so that a signal visits the winner's few neighbours
instead of scanning a row of the age matrix; ``n`` nodes are live, the first n rows.
"""

from __future__ import annotations

import numpy as np
from numba import njit

# No fastmath: every sum runs in the order written, so that the map is the same on every
# processor (reassociation let LLVM sum in the order of the target's SIMD width and
# contraction fuse multiply-adds where the target has FMA: the same seed grew a
# different map, and so different landmarks, on different machines). The searches run
# over a transposed copy of the positions instead, which vectorises across nodes with
# each node's sum in its own fixed order.


@njit(cache=True, inline="always")
def _nearest_two(x, wt, n, acc):  # type: ignore[no-untyped-def]
    """Indices and squared distances of the nearest and second-nearest live nodes;
    ``wt`` (d, cap) holds the positions transposed, ``acc`` (cap,) is scratch.

    Each node's squared distance is summed over components 0, 1, ... in turn (the value
    a plain loop over that node gives), the loop running across nodes so that it
    vectorises without reordering any sum."""
    d = x.shape[0]
    for i in range(n):
        acc[i] = 0.0
    for j in range(d):
        xj = x[j]
        row = wt[j]
        for i in range(n):
            diff = xj - row[i]
            acc[i] += diff * diff
    b1 = -1
    b2 = -1
    d1 = np.inf
    d2 = np.inf
    for i in range(n):
        a = acc[i]
        if a < d1:
            b2 = b1
            d2 = d1
            b1 = i
            d1 = a
        elif a < d2:
            b2 = i
            d2 = a
    return b1, d1, b2, d2


@njit(cache=True, inline="always")
def _sync(wt, w, i):  # type: ignore[no-untyped-def]
    """Copy node i's position into the transposed copy."""
    for j in range(w.shape[1]):
        wt[j, i] = w[i, j]


@njit(cache=True, inline="always")
def _link(a, b, nbr, deg):  # type: ignore[no-untyped-def]
    nbr[a, deg[a]] = b
    deg[a] += 1
    nbr[b, deg[b]] = a
    deg[b] += 1


@njit(cache=True, inline="always")
def _drop(a, b, nbr, deg):  # type: ignore[no-untyped-def]
    """Remove b from a's neighbour list (swap with the last entry)."""
    for idx in range(deg[a]):
        if nbr[a, idx] == b:
            deg[a] -= 1
            nbr[a, idx] = nbr[a, deg[a]]
            return


@njit(cache=True, inline="always")
def _unlink(a, b, age, nbr, deg):  # type: ignore[no-untyped-def]
    age[a, b] = -1
    age[b, a] = -1
    _drop(a, b, nbr, deg)
    _drop(b, a, nbr, deg)


@njit(cache=True)
def _remove_node(r, w, err, age, nbr, deg, n):  # type: ignore[no-untyped-def]
    """Remove node r (it has no edges left) by moving the last live node into its slot;
    returns the new n."""
    last = n - 1
    if r != last:
        w[r] = w[last]
        err[r] = err[last]
        deg[r] = deg[last]
        for idx in range(deg[last]):
            k = nbr[last, idx]
            nbr[r, idx] = k
            age[r, k] = age[last, k]
            age[k, r] = age[k, last]
            age[last, k] = -1
            age[k, last] = -1
            for jdx in range(deg[k]):
                if nbr[k, jdx] == last:
                    nbr[k, jdx] = r
                    break
    deg[last] = 0
    return last


@njit(cache=True)
def gng_run(  # type: ignore[no-untyped-def]
    x, order, w, err, age, nbr, deg, n, seen, max_nodes, eps_b, eps_n, lam, max_age, alpha, decay
):
    """Feed the signals ``x[order]`` to the network; returns (n, seen).

    Fritzke (1995), step by step for each signal xi:
      1. nearest unit s1 and second-nearest s2;
      2. age every edge of s1 by one;
      3. error of s1 += squared distance |w_s1 - xi|^2;
      4. move s1 by eps_b (xi - w_s1) and its topological neighbours by eps_n;
      5. connect s1 and s2 with age 0 (refresh the edge if it exists);
      6. remove edges older than max_age, then units left without edges;
      7. every lam signals (counted over the network's life), unless max_nodes units
         exist, insert r halfway between the unit q of largest error and its neighbour f
         of largest error, replace the edge q-f by q-r and r-f, scale the errors of q and
         f by alpha, and give r the new error of q;
      8. scale every error by decay (Fritzke's 1 - beta).

    Step 8 is done lazily: errors are stored divided by a running product of the decays
    (``scale``), so that a signal costs no pass over all nodes; the true errors are
    written back before returning. Comparisons between stored errors are unchanged.
    """
    dim = x.shape[1]
    scale = 1.0
    expired = np.empty(w.shape[0], dtype=np.int64)
    wt = np.ascontiguousarray(w.T)  # positions transposed, kept in step with w
    acc = np.empty(w.shape[0])
    for t in range(order.shape[0]):
        xi = x[order[t]]
        s1, d1, s2, _ = _nearest_two(xi, wt, n, acc)
        seen += 1
        err[s1] += d1 / scale
        for j in range(dim):
            w[s1, j] += eps_b * (xi[j] - w[s1, j])
        _sync(wt, w, s1)
        for idx in range(deg[s1]):
            k = nbr[s1, idx]
            age[s1, k] += 1
            age[k, s1] += 1
            for j in range(dim):
                w[k, j] += eps_n * (xi[j] - w[k, j])
            _sync(wt, w, k)
        if age[s1, s2] < 0:
            _link(s1, s2, nbr, deg)
        age[s1, s2] = 0
        age[s2, s1] = 0
        # Step 6: only s1's edges aged, so only they can expire. Expired neighbours are
        # collected first (node removal renumbers slots), then unlinked.
        m = 0
        for idx in range(deg[s1]):
            k = nbr[s1, idx]
            if age[s1, k] > max_age:
                expired[m] = k
                m += 1
        for e in range(m):
            _unlink(s1, expired[e], age, nbr, deg)
        # Isolated ones go in the order a scan up the slots would meet them: always the
        # lowest pending slot next, since a removal moves the last node into the freed
        # slot (and, if that node was pending too, it is met there next).
        while m > 0:
            low = 0
            for e in range(1, m):
                if expired[e] < expired[low]:
                    low = e
            k = expired[low]
            m -= 1
            expired[low] = expired[m]
            if deg[k] == 0:
                last = n - 1
                n = _remove_node(k, w, err, age, nbr, deg, n)
                if k < n:
                    _sync(wt, w, k)  # the last node moved into slot k
                if s1 == last:
                    s1 = k
                for e in range(m):
                    if expired[e] == last:
                        expired[e] = k
        if seen % lam == 0 and n < max_nodes:
            q = 0
            for i in range(1, n):
                if err[i] > err[q]:
                    q = i
            f = -1
            for idx in range(deg[q]):
                i = nbr[q, idx]
                if f < 0 or err[i] > err[f] or (err[i] == err[f] and i < f):
                    f = i
            if f >= 0:
                r = n
                n += 1
                for j in range(dim):
                    w[r, j] = 0.5 * (w[q, j] + w[f, j])
                _sync(wt, w, r)
                _unlink(q, f, age, nbr, deg)
                age[q, r] = 0
                age[r, q] = 0
                age[r, f] = 0
                age[f, r] = 0
                deg[r] = 0
                _link(q, r, nbr, deg)
                _link(r, f, nbr, deg)
                err[q] *= alpha
                err[f] *= alpha
                err[r] = err[q]
        scale *= decay
        if scale < 1e-150:
            for i in range(n):
                err[i] *= scale
            scale = 1.0
    for i in range(n):
        err[i] *= scale
    return n, seen


@njit(cache=True)
def nearest(x, w, n, out_idx, out_d2):  # type: ignore[no-untyped-def]
    """Nearest live node of each row of x, and the squared distance."""
    wt = np.ascontiguousarray(w[:n].T)
    acc = np.empty(n)
    for t in range(x.shape[0]):
        b, d, _, _ = _nearest_two(x[t], wt, n, acc)
        out_idx[t] = b
        out_d2[t] = d
