"""Compiled inner loops of the crowd (:mod:`copi.world.crowd`): a uniform grid of the
agents' discs, every agent's ring scan against the walls and the others' discs found
through the grid, the moves, the contacts, and the placement without overlap.

Why by hand: each step every one of N agents casts 32 rays against the walls and the
other agents' discs. Brute force is N discs per scan (10,000 agents: 3 billion ray tests
a step); the grid hands a scan only the discs near it, ring of cells by ring of cells
outward, and stops as soon as no disc farther out can shorten any ray. A disc is tested
with the same formula as :func:`copi.geometry.kernels._scan_into`, whose wall loop each
scan reuses, so a crowd's reading is bitwise the one :class:`copi.world.RangeSensor`
gives with every other agent as a disc (tested).

Conventions: positions are rows (x, y) in agent steps; the grid covers the world's
bounding box from (x0, y0) in square cells of side h, ``nx`` by ``ny``, cell (i, j) is
``j * nx + i``; ``start[c] .. start[c + 1]`` indexes the agents of cell c in ``items``,
in increasing agent order (so every loop over them runs in one order, whatever the
machine). No fastmath: sums run in the order written.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from copi.geometry.kernels import _scan_into, closest_approach, move_one, ray_disc


@njit(cache=True, inline="always")
def _cell(v, v0, h, n):  # type: ignore[no-untyped-def]
    """The cell index of coordinate v along an axis (clamped to the grid)."""
    c = int(math.floor((v - v0) / h))
    return min(max(c, 0), n - 1)


@njit(cache=True)
def build_grid(positions, active, x0, y0, h, nx, ny, cell_of, start, items, fill):  # type: ignore[no-untyped-def]
    """Sort the active agents into the grid (a counting sort: two passes over the agents).

    ``cell_of`` (N,) receives each agent's cell (-1 when inactive); ``start`` (nx ny + 1,)
    and ``items`` (N,) the cells' contents; ``fill`` (nx ny,) is scratch."""
    n_cells = nx * ny
    for c in range(n_cells + 1):
        start[c] = 0
    for i in range(positions.shape[0]):
        if active[i]:
            c = _cell(positions[i, 1], y0, h, ny) * nx + _cell(positions[i, 0], x0, h, nx)
            cell_of[i] = c
            start[c + 1] += 1
        else:
            cell_of[i] = -1
    for c in range(n_cells):
        start[c + 1] += start[c]
        fill[c] = start[c]
    for i in range(positions.shape[0]):
        c = cell_of[i]
        if c >= 0:
            items[fill[c]] = i
            fill[c] += 1


@njit(cache=True, inline="always")
def _farthest(row):  # type: ignore[no-untyped-def]
    far = 0.0
    for i in range(row.shape[0]):
        if row[i] > far:
            far = row[i]
    return far


@njit(cache=True, inline="always")
def _bearing(x, y):  # type: ignore[no-untyped-def]
    """atan2(y, x) within 0.004 rad, without a library call (the window it places has a
    ray to spare each side, 0.2 rad for 32 rays)."""
    ax = abs(x)
    ay = abs(y)
    a = min(ax, ay) / max(ax, ay)
    t = 0.25 * math.pi * a + 0.273 * a * (1.0 - a)
    if ay > ax:
        t = 0.5 * math.pi - t
    if x < 0.0:
        t = math.pi - t
    return -t if y < 0.0 else t


@njit(cache=True, inline="always")
def _discs_of_cell(b, ox, oy, c, positions, radius, cos, sin, start, items, row, far):  # type: ignore[no-untyped-def]
    """Lower ``row`` by the discs of cell c (agent b's own aside), as ``_scan_into``
    does, each on the rays of its angular window only (one to spare each side); returns
    -1 when b's centre is inside one (then ``row`` is all 0), else 1 if a reading was
    lowered, 0 if none."""
    lowered = 0
    n = cos.shape[0]
    per = n / (2.0 * math.pi)
    r = radius
    for p in range(start[c], start[c + 1]):
        k = items[p]
        if k == b:
            continue
        vx = ox - positions[k, 0]
        vy = oy - positions[k, 1]
        cc = vx * vx + vy * vy - r * r
        if cc <= 0.0:
            for i in range(n):
                row[i] = 0.0
            return -1
        # a disc whose nearest point is beyond every reading it could shorten: none
        reach = far + r
        if vx * vx + vy * vy >= reach * reach:
            continue
        # the bearing of the centre, and r / sqrt(cc) >= asin(r / d), the half-width
        mid = _bearing(-vx, -vy) * per
        half = r / math.sqrt(cc) * per
        first = int(math.floor(mid - half)) - 1
        last = int(math.ceil(mid + half)) + 2
        if last - first >= n:
            first = 0
            last = n
        elif first < 0:
            first += n
            last += n
        for q in range(first, last):
            i = q - n if q >= n else q
            t = ray_disc(cos[i], sin[i], vx, vy, cc)
            if t < row[i]:
                row[i] = t
                lowered = 1
    return lowered


@njit(cache=True, inline="always")
def _scan_one(b, positions, cos, sin, segs, radius, max_range, x0, y0, h, nx, ny, start,  # type: ignore[no-untyped-def]
              items, sectors, row, no_centers, no_radii):  # fmt: skip
    ox = positions[b, 0]
    oy = positions[b, 1]
    _scan_into(ox, oy, cos, sin, segs, no_centers, no_radii, max_range, row)
    n = cos.shape[0]
    ci = _cell(ox, x0, h, nx)
    cj = _cell(oy, y0, h, ny)
    far = _farthest(row)
    # cells nearest first: once a cell's discs are all beyond every reading, so are the
    # rest's
    for e in range(sectors.shape[0]):
        if sectors[e, 4] >= far:
            break
        i = ci + int(sectors[e, 0])
        j = cj + int(sectors[e, 1])
        if i < 0 or i >= nx or j < 0 or j >= ny:
            continue
        c = j * nx + i
        if start[c] == start[c + 1]:
            continue
        lo = int(sectors[e, 2])
        m = int(sectors[e, 3])
        fc = 0.0  # the farthest reading among the rays that can meet the cell's discs
        for q in range(lo, lo + m):
            v = row[q - n if q >= n else q]
            if v > fc:
                fc = v
        if sectors[e, 4] >= fc:
            continue
        done = _discs_of_cell(b, ox, oy, c, positions, radius, cos, sin, start, items, row, fc)
        if done < 0:
            return
        if done > 0 and fc == far:  # the farthest reading may have been lowered
            far = _farthest(row)


@njit(cache=True)
def scan_agents(positions, active, lo, hi, cos, sin, segs, radius, max_range, x0, y0, h, nx,  # type: ignore[no-untyped-def]
                ny, start, items, sectors, out):  # fmt: skip
    """``out[b]``: the ring reading of each active agent b in ``lo .. hi - 1`` against
    the walls ``segs`` and every other active agent's disc (radius ``radius``) in the
    grid; rows of inactive agents are left as they are. ``sectors`` (M, 5) lists the
    cells around an agent's, nearest first, as rows (di, dj, first ray, rays, least
    distance): the rays that can meet a disc centred there and that disc's least
    distance (:func:`copi.world.crowd.cell_sectors`)."""
    no_centers = np.empty((0, 2))
    no_radii = np.empty(0)
    for b in range(lo, hi):
        if active[b]:
            _scan_one(b, positions, cos, sin, segs, radius, max_range, x0, y0, h, nx, ny,
                      start, items, sectors, out[b], no_centers, no_radii)  # fmt: skip


@njit(cache=True)
def move_agents(positions, actions, active, segs, radius, old, blocked):  # type: ignore[no-untyped-def]
    """Move each active agent by its action (already clipped to norm 1), stopped by the
    walls (:func:`copi.geometry.kernels.move_one`); ``old`` receives the positions before."""
    for i in range(positions.shape[0]):
        old[i, 0] = positions[i, 0]
        old[i, 1] = positions[i, 1]
        if not active[i]:
            blocked[i] = False
            continue
        x, y, bl = move_one(positions[i, 0], positions[i, 1], actions[i, 0], actions[i, 1],
                            segs, radius)  # fmt: skip
        positions[i, 0] = x
        positions[i, 1] = y
        blocked[i] = bl


@njit(cache=True)
def agent_gaps(old, positions, active, radius, reach, x0, y0, h, nx, ny, start, items, gap):  # type: ignore[no-untyped-def]
    """``gap[b]``: the least surface distance between active agent b and any other over
    the step (both moving linearly from ``old`` to ``positions``; negative: a contact),
    inf when none is within ``reach`` (two radii plus two steps: none nearer can be met).
    The grid is the one of ``old``."""
    two_r = 2.0 * radius
    w = int(math.ceil(reach / h))
    for b in range(old.shape[0]):
        gap[b] = np.inf
        if not active[b]:
            continue
        ax = old[b, 0]
        ay = old[b, 1]
        adx = positions[b, 0] - ax
        ady = positions[b, 1] - ay
        ci = _cell(ax, x0, h, nx)
        cj = _cell(ay, y0, h, ny)
        best = np.inf
        for j in range(max(cj - w, 0), min(cj + w + 1, ny)):
            for i in range(max(ci - w, 0), min(ci + w + 1, nx)):
                c = j * nx + i
                for p in range(start[c], start[c + 1]):
                    k = items[p]
                    if k == b:
                        continue
                    d = closest_approach(ax, ay, adx, ady, old[k, 0], old[k, 1],
                                         positions[k, 0] - old[k, 0],
                                         positions[k, 1] - old[k, 1])  # fmt: skip
                    if d - two_r < best:
                        best = d - two_r
        gap[b] = best


@njit(cache=True)
def within(positions, active, b, reach, x0, y0, h, nx, ny, start, items, out):  # type: ignore[no-untyped-def]
    """The active agents other than b whose centres lie within ``reach`` of b's, into
    ``out``, in increasing order of cell then agent; returns how many."""
    ox = positions[b, 0]
    oy = positions[b, 1]
    k = int(math.ceil(reach / h))
    ci = _cell(ox, x0, h, nx)
    cj = _cell(oy, y0, h, ny)
    n = 0
    r2 = reach * reach
    for j in range(max(cj - k, 0), min(cj + k + 1, ny)):
        for i in range(max(ci - k, 0), min(ci + k + 1, nx)):
            c = j * nx + i
            for p in range(start[c], start[c + 1]):
                a = items[p]
                if a == b:
                    continue
                dx = positions[a, 0] - ox
                dy = positions[a, 1] - oy
                if dx * dx + dy * dy <= r2:
                    out[n] = a
                    n += 1
    return n


@njit(cache=True)
def place_discs(candidates, placed, n_placed, wanted, min_dist, x0, y0, h, nx, ny, head, nxt):  # type: ignore[no-untyped-def]
    """Random sequential placement: take ``candidates`` (m, 2) in order, keeping each one
    at least ``min_dist`` from every disc kept so far, until ``wanted`` are kept.

    ``placed`` (wanted, 2) holds the ``n_placed`` kept so far; ``head`` (nx ny,) and
    ``nxt`` (wanted,) are a linked-list grid of them (cells at least ``min_dist`` wide,
    -1 for none), carried from call to call. Returns (kept in all, candidates used)."""
    d2 = min_dist * min_dist
    used = 0
    for m in range(candidates.shape[0]):
        if n_placed >= wanted:
            break
        used = m + 1
        x = candidates[m, 0]
        y = candidates[m, 1]
        ci = _cell(x, x0, h, nx)
        cj = _cell(y, y0, h, ny)
        ok = True
        for j in range(max(cj - 1, 0), min(cj + 2, ny)):
            for i in range(max(ci - 1, 0), min(ci + 2, nx)):
                p = head[j * nx + i]
                while p >= 0:
                    dx = placed[p, 0] - x
                    dy = placed[p, 1] - y
                    if dx * dx + dy * dy < d2:
                        ok = False
                        break
                    p = nxt[p]
                if not ok:
                    break
            if not ok:
                break
        if ok:
            placed[n_placed, 0] = x
            placed[n_placed, 1] = y
            c = cj * nx + ci
            nxt[n_placed] = head[c]
            head[c] = n_placed
            n_placed += 1
    return n_placed, used
