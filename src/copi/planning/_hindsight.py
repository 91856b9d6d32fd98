"""The hindsight values of :class:`copi.planning.futures.FuturesPlanner`: a window of cells
valued against sampled futures of moving discs, each future solved as if known.

Why by hand: each decision solves a window of a few thousand cells over 10 to 20 steps in
each of 32 futures; no library solves many small time-expanded grids at once, and a general
shortest-path search (networkx, scipy.sparse.csgraph) would rebuild a graph per future.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["covers", "disc_cells", "hindsight_values"]


_LANES = 16
"""Samples :func:`hindsight_values` solves at once (16 ran faster than 4 and 8, as fast as
32, on 32 futures of crowd episodes)."""


@njit(cache=True, nogil=True, inline="always")
def disc_cells(cx, cy, reach, x0, y0, res, lo, hi):  # type: ignore[no-untyped-def]
    """The rows i0..i1 and columns j0..j1 (within lo..hi) of the window cells (origin x0,
    y0, side ``res``) whose centres may lie within ``reach`` of (cx, cy); a cell (i, j)
    among them does when :func:`covers` says so."""
    j0 = max(int(math.ceil((cx - reach - x0) / res)), lo)
    j1 = min(int(math.floor((cx + reach - x0) / res)), hi)
    i0 = max(int(math.ceil((cy - reach - y0) / res)), lo)
    i1 = min(int(math.floor((cy + reach - y0) / res)), hi)
    return i0, i1, j0, j1


@njit(cache=True, nogil=True, inline="always")
def covers(cx, cy, reach, x0, y0, res, i, j):  # type: ignore[no-untyped-def]
    """Whether the centre of window cell (i, j) is within ``reach`` of (cx, cy)."""
    py = y0 + i * res - cy
    px = x0 + j * res - cx
    return px * px + py * py <= reach * reach


@njit(cache=True, nogil=True)
def _block_layer(samples, t, radii, agent_r, margin, x0, y0, res, lo, hi, pad, m, V):  # type: ignore[no-untyped-def]
    """Sets lane s of cell (i, j) of the flat buffer ``V`` (index ``((pad + i) * m + pad +
    j) * _LANES + s``) to inf where, in sample s at step t, some disc is within the sum of
    radii plus ``margin`` of the cell's centre (origin x0, y0, side ``res``), for the
    cells with lo <= i, j <= hi (the test of :func:`copi.planning.futures.occupancy`)."""
    for s in range(samples.shape[0]):
        for k in range(samples.shape[2]):
            reach = agent_r + radii[k] + margin
            cx = samples[s, t, k, 0]
            cy = samples[s, t, k, 1]
            i0, i1, j0, j1 = disc_cells(cx, cy, reach, x0, y0, res, lo, hi)
            for i in range(i0, i1 + 1):
                for j in range(j0, j1 + 1):
                    if covers(cx, cy, reach, x0, y0, res, i, j):
                        V[((pad + i) * m + pad + j) * _LANES + s] = np.inf


@njit(cache=True, nogil=True)  # nogil: many agents plan at once in threads
def hindsight_values(  # type: ignore[no-untyped-def]
    samples, radii, agent_r, margin, x0, y0, res, ok, terminal, goal, offsets, mid_ok, cap,
    box=-1,
):
    """The window's value averaged over the sampled futures, each solved as if known
    (hindsight optimisation: Chong, Givan & Chang 2000; Yoon et al. 2008).

    In each sample s a cell (i, j) is blocked at step t when some disc is within the sum of
    radii plus ``margin`` of its centre; ``V_s[t, i, j]`` is the least number of steps from
    (i, j) at step t through unblocked cells to the horizon, plus ``terminal`` there (0
    once in a ``goal`` cell), infinite when every way is blocked. Returns V (horizon + 1,
    n, n) whose step-1 layer is the mean over samples of min(V_s[1], ``cap``), a sample
    with no way through counting ``cap``; other layers unused.

    Against :func:`copi.planning.futures.risk_values` (which averages the discs first and
    plans once against the mean occupancy, so that at a few steps' distance every cell a
    disc may reach looks risky), this plans once per future and averages the plans' costs:
    it assumes the agent will see each future as it comes, which is optimistic (it will see
    it a step at a time), where the mean-occupancy plan is pessimistic.

    ``box`` >= 0: only the cells step 1's values within ``box`` + 2 cells of the centre
    (the square an agent starting there can be in) depend on are solved: at step t,
    those within ``box`` + 2 + p (t - 1) cells of the centre in each axis and 2 (``box``
    + 2) + q (t - 1) in the sum of both, where a move of ``offsets`` goes at most p cells
    in either axis and q in their sum (2 and 2 for the planner's): an octagon, about
    two thirds of its square far ahead. The values there are those of the
    whole window; the rest of step 1 is left infinite. ``box`` < 0: the whole window.

    The samples are solved :data:`_LANES` at a time, stored sample-last (lane s of cell
    (i, j)) in a grid padded by the longest move's reach: each cell's moves are tested for
    walls once for all the lanes, with no test of the window's edge, and the lanes' minima
    are one unrolled loop of fixed length. About 5x faster than one sample at a time, and
    the same numbers bit for bit (the same minima over the same moves, the samples summed
    in the same order)."""
    n_s = samples.shape[0]
    horizon = samples.shape[1] - 1
    n = ok.shape[0]
    n_off = offsets.shape[0]
    c = n // 2
    lo1, hi1 = 0, n - 1  # the cells of step 1 solved
    if box >= 0:
        lo1 = max(c - box - 2, 0)
        hi1 = min(c + box + 2, n - 1)
    pad = 0  # the farthest a move goes in either axis, cells
    l1 = 0  # and in the sum of both
    for o in range(n_off):
        pad = max(pad, abs(offsets[o, 0]), abs(offsets[o, 1]))
        l1 = max(l1, abs(offsets[o, 0]) + abs(offsets[o, 1]))
    m = n + 2 * pad
    total = np.zeros((n, n))
    L = _LANES
    # flat buffers, indexed by hand: (row * m + column) * L + lane; the padding stays inf
    Vn = np.full(m * m * L, np.inf)
    Vc = np.full(m * m * L, np.inf)
    delta = np.empty(n_off, dtype=np.int64)  # each move, as a step in the flat buffer
    for o in range(n_off):
        delta[o] = (offsets[o, 0] * m + offsets[o, 1]) * L
    # with no disc every future is the same: one is solved, and counted n_s times
    n_solve = n_s if samples.shape[2] > 0 else min(n_s, 1)
    for s0 in range(0, n_solve, L):
        w = min(L, n_solve - s0)
        part = samples[s0 : s0 + w]
        for i in range(n):
            for j in range(n):
                tv = terminal[i, j]
                base = ((pad + i) * m + pad + j) * L
                for s in range(L):
                    Vn[base + s] = tv
        _block_layer(part, horizon, radii, agent_r, margin, x0, y0, res, 0, n - 1, pad, m, Vn)
        for t in range(horizon - 1, 0, -1):
            lo, hi = 0, n - 1
            if box >= 0:
                lo = max(c - box - 2 - pad * (t - 1), 0)
                hi = min(c + box + 2 + pad * (t - 1), n - 1)
            for i in range(lo, hi + 1):
                jlo, jhi = lo, hi
                if box >= 0:  # the octagon
                    span = min(box + 2 + pad * (t - 1),
                               2 * (box + 2) + l1 * (t - 1) - abs(i - c))
                    jlo = max(c - span, 0)
                    jhi = min(c + span, n - 1)
                for j in range(jlo, jhi + 1):
                    base = ((pad + i) * m + pad + j) * L
                    if not ok[i, j]:
                        for s in range(L):
                            Vc[base + s] = np.inf
                        continue
                    if goal[i, j]:
                        for s in range(L):
                            Vc[base + s] = 0.0
                        continue
                    for s in range(L):
                        Vc[base + s] = np.inf
                    for o in range(n_off):
                        if not mid_ok[o, i, j]:
                            continue
                        src = base + delta[o]
                        for s in range(L):
                            v = Vn[src + s]
                            u = Vc[base + s]
                            Vc[base + s] = v if v < u else u
                    for s in range(L):  # every move costs one step (inf stays inf)
                        Vc[base + s] += 1.0
            # blocked cells: inf, whatever else (a goal cell too)
            _block_layer(part, t, radii, agent_r, margin, x0, y0, res, lo, hi, pad, m, Vc)
            Vn, Vc = Vc, Vn
        for i in range(lo1, hi1 + 1):
            for j in range(lo1, hi1 + 1):
                base = ((pad + i) * m + pad + j) * L
                for s in range(w):  # in the samples' order
                    total[i, j] += min(Vn[base + s], cap)
    for _ in range(n_solve, n_s):  # the futures alike (no disc): the one solved, again
        for i in range(lo1, hi1 + 1):
            for j in range(lo1, hi1 + 1):
                total[i, j] += min(Vn[((pad + i) * m + pad + j) * L], cap)
    V = np.full((horizon + 1, n, n), np.inf)
    for i in range(lo1, hi1 + 1):
        for j in range(lo1, hi1 + 1):
            if ok[i, j]:
                V[1, i, j] = total[i, j] / n_s
    return V
