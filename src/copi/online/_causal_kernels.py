"""Compiled inference over the causal map (which options the static map allows, value
iteration over places with the observed outcome probabilities) and the ray cast of the
walls an agent has learnt on its occupancy grid.

Why by hand: the first two are loops over a few hundred places, eight options each and a
handful of outcomes, run every few decisions; scipy's graph routines take no outcome
distributions, and in numpy each of the small steps would cost more in call overhead
than the loop itself. The cast runs every step: 32 short marches, a few microseconds
compiled.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# The eight options of a place, "make for the neighbouring place" E, NE, N, NW, W, SW, S, SE.
OFFSETS = np.array(
    [[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1]], dtype=np.int64
)


@njit(cache=True)
def plausible_options(free, k, m, i0, i1, j0, j1, offsets, out, seen, queue):  # type: ignore[no-untyped-def]
    """out[p, a] = whether the fine grid ``free[y, x]`` (k x k fine cells per place, m x m
    places) has a free 8-connected path from place p into its neighbour in direction a,
    inside the square the two span, for places p = (i, j) with i0 <= i < i1, j0 <= j < j1.

    ``seen`` (fine grid's size, int64) and ``queue`` (int64, 4 k^2 long) are work arrays;
    ``seen`` must hold values below 1 on entry and is left stamped."""
    nf = free.shape[0]
    stamp = 0
    for j in range(j0, j1):
        for i in range(i0, i1):
            p = j * m + i
            for a in range(8):
                out[p, a] = False
                qi = i + offsets[a, 0]
                qj = j + offsets[a, 1]
                if qi < 0 or qj < 0 or qi >= m or qj >= m:
                    continue
                stamp += 1
                x0 = min(i, qi) * k
                y0 = min(j, qj) * k
                x1 = x0 + 2 * k if qi != i else x0 + k
                y1 = y0 + 2 * k if qj != j else y0 + k
                x1 = min(x1, nf)
                y1 = min(y1, nf)
                head = 0
                tail = 0
                for y in range(j * k, min((j + 1) * k, nf)):
                    for x in range(i * k, min((i + 1) * k, nf)):
                        if free[y, x]:
                            seen[y * nf + x] = stamp
                            queue[tail] = y * nf + x
                            tail += 1
                found = False
                while head < tail and not found:
                    c = queue[head]
                    head += 1
                    cy = c // nf
                    cx = c - cy * nf
                    for dy in range(-1, 2):
                        for dx in range(-1, 2):
                            if dx == 0 and dy == 0:
                                continue
                            x = cx + dx
                            y = cy + dy
                            if x < x0 or y < y0 or x >= x1 or y >= y1:
                                continue
                            if not free[y, x] or seen[y * nf + x] == stamp:
                                continue
                            # no corner cutting, as the grid planner
                            if dx != 0 and dy != 0 and not (free[cy, x] and free[y, cx]):
                                continue
                            seen[y * nf + x] = stamp
                            if x // k == qi and y // k == qj:
                                found = True
                                break
                            queue[tail] = y * nf + x
                            tail += 1
                        if found:
                            break
                out[p, a] = found
    # leave seen below 1 for the next call
    for c in range(seen.shape[0]):
        seen[c] = 0


@njit(cache=True)
def option_values(  # type: ignore[no-untyped-def]
    places, m, goal, plaus, n, steps, contacts, offs, nxt, cnt, prior, length, patience,
    contact_cost, value, best, tol, max_sweeps,
):
    """Value iteration over the places listed in ``places`` (ids j * m + i).

    The option (p, a) has been tried n[p, a] times, took steps[p, a] steps in all and
    ended in a contact contacts[p, a] times; its other outcomes are the places
    nxt[offs[p*8+a] : offs[p*8+a+1]] with counts cnt[...]. To them ``prior``
    pseudo-observations are added: the intended neighbour in length[a] steps when the
    static map allows it (plaus[p, a]), else staying put for ``patience`` steps. So

        Q(p, a) = E[steps] + P(contact) contact_cost + sum_p' P(p') V(p'),
        V(p) = min_a Q(p, a),   V(goal) = 0,

    solved by Gauss-Seidel sweeps in alternating order until no value moves by more than
    ``tol``. ``value`` (m*m) receives V (1e9: no way known, and outside ``places``),
    ``best`` the option taken (-1 at the goal, with no way, or outside ``places``).
    Returns the sweeps made."""
    far = 1e9
    for t in range(value.shape[0]):
        value[t] = far
        best[t] = -1
    value[goal] = 0.0
    sweeps = 0
    while sweeps < max_sweeps:
        sweeps += 1
        change = 0.0
        for s in range(places.shape[0]):
            t = s if sweeps % 2 == 1 else places.shape[0] - 1 - s
            p = places[t]
            if p == goal:
                continue
            i = p % m
            j = p // m
            bq = far
            ba = -1
            for a in range(8):
                qi = i + OFFSETS[a, 0]
                qj = j + OFFSETS[a, 1]
                total = prior + n[p, a]
                if plaus[p, a] and 0 <= qi < m and 0 <= qj < m:
                    q = qj * m + qi
                    exp_steps = prior * length[a] + steps[p, a]
                    future = prior * value[q]
                else:
                    exp_steps = prior * patience + steps[p, a]
                    future = prior * value[p]
                e = p * 8 + a
                for r in range(offs[e], offs[e + 1]):
                    future += cnt[r] * value[nxt[r]]
                qv = (exp_steps + contacts[p, a] * contact_cost + future) / total
                if qv < bq:
                    bq = qv
                    ba = a
            if bq > far:
                bq = far
            d = abs(bq - value[p])
            if d > change:
                change = d
            value[p] = bq
            best[p] = ba if bq < far else -1
        if change < tol:
            break
    return sweeps



@njit(cache=True)
def cast_grid(occupancy, hits, level, min_hits, x, y, cell, extent, cos, sin, max_range, step,  # type: ignore[no-untyped-def]
              out):  # fmt: skip
    """out[i] = distance along ray i from (x, y) to the first wall cell of the grid
    (side ``cell``, corner at (-extent, -extent)): a cell whose ``occupancy`` is at least
    ``level`` and that was hit ``min_hits`` times. Marching in steps of ``step``, less one
    step, so that it never exceeds the distance to the wall's face; ``max_range`` where
    the ray meets none (or leaves the grid)."""
    n = occupancy.shape[0]
    for i in range(cos.shape[0]):
        out[i] = max_range
        t = step
        while t <= max_range:
            cx = int(math.floor((x + t * cos[i] + extent) / cell))
            cy = int(math.floor((y + t * sin[i] + extent) / cell))
            if cx < 0 or cy < 0 or cx >= n or cy >= n:
                break
            if occupancy[cy, cx] >= level and hits[cy, cx] >= min_hits:
                out[i] = max(0.0, t - step)
                break
            t += step
