"""Compiled inner loops of the crowd (:mod:`copi.world.crowd`): a uniform grid of the
agents' discs, every agent's ring scan against the walls and the others' discs found
through the grid, the moves, the contacts, and the placement without overlap.

Why by hand: each step every one of N agents casts 32 rays against the walls and the
other agents' discs. Brute force is N discs per scan (10,000 agents: 3 billion ray tests
a step); the grid hands a scan only the discs near it, ring of cells by ring of cells
outward, and stops as soon as no disc farther out can shorten any ray; each disc is
tested on the one or two rays of its angular window only. A disc is tested
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

RUNNING, SUCCESS, COLLISION = 0, 1, 2
"""A trip's outcome, as :attr:`copi.world.crowd.Crowd.outcome` holds it."""


@njit(cache=True, inline="always")
def _cell(v, v0, h, n):  # type: ignore[no-untyped-def]
    """The cell index of coordinate v along an axis (clamped to the grid)."""
    c = int(math.floor((v - v0) / h))
    return min(max(c, 0), n - 1)


@njit(cache=True)
def build_grid(positions, active, x0, y0, h, nx, ny, cell_of, start, items, fill, ordered):  # type: ignore[no-untyped-def]
    """Sort the active agents into the grid (a counting sort: two passes over the agents).

    ``cell_of`` (N,) receives each agent's cell (-1 when inactive); ``start`` (nx ny + 1,)
    and ``items`` (N,) the cells' contents, ``ordered`` (N, 2) their positions in that
    order (so that a scan reads the discs of a cell from consecutive memory); ``fill``
    (nx ny,) is scratch."""
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
            ordered[fill[c], 0] = positions[i, 0]
            ordered[fill[c], 1] = positions[i, 1]
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
    """atan2(y, x) within 0.004 rad, without a library call (the window it places is
    widened by :data:`_SPARE` of a ray each side, 0.02 rad for 32 rays)."""
    ax = abs(x)
    ay = abs(y)
    a = min(ax, ay) / max(ax, ay)
    t = 0.25 * math.pi * a + 0.273 * a * (1.0 - a)
    if ay > ax:
        t = 0.5 * math.pi - t
    if x < 0.0:
        t = math.pi - t
    return -t if y < 0.0 else t


_SPARE = 0.1
"""How much of a ray's spacing a disc's angular window is widened each side: five times
:func:`_bearing`'s error for 32 rays (0.004 rad is 0.02 of their spacing)."""


@njit(cache=True, inline="always")
def _discs_of_cell(b, ox, oy, c, ordered, items, start, radius, cos, sin, per, reach2, row):  # type: ignore[no-untyped-def]
    """Lower ``row`` by the discs of cell c (agent b's own aside) whose centres lie
    nearer than sqrt(``reach2``), as ``_scan_into`` does, each on the rays of its angular
    window only; returns True when b's centre is inside one (then ``row`` is all 0)."""
    n = cos.shape[0]
    r = radius
    for p in range(start[c], start[c + 1]):
        vx = ox - ordered[p, 0]
        vy = oy - ordered[p, 1]
        d2 = vx * vx + vy * vy
        if d2 >= reach2 or items[p] == b:
            continue
        cc = d2 - r * r
        if cc <= 0.0:
            for i in range(n):
                row[i] = 0.0
            return True
        # a ray meets the disc only within asin(r / d) <= r / sqrt(cc) of its centre's
        # bearing: the rays of that window (in ray spacings), widened by _SPARE
        mid = _bearing(-vx, -vy) * per
        half = r / math.sqrt(cc) * per + _SPARE
        first = int(math.ceil(mid - half))
        last = int(math.floor(mid + half)) + 1
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
    return False


@njit(cache=True, inline="always")
def _cell_distance2(ox, oy, x0, y0, h, i, j):  # type: ignore[no-untyped-def]
    """The squared distance from (ox, oy) to cell (i, j)'s square (0 inside)."""
    xl = x0 + i * h
    yl = y0 + j * h
    dx = max(xl - ox, ox - (xl + h), 0.0)
    dy = max(yl - oy, oy - (yl + h), 0.0)
    return dx * dx + dy * dy


@njit(cache=True, inline="always")
def _scan_one(b, ox, oy, cos, sin, segs, radius, max_range, x0, y0, h, nx, ny, start,  # type: ignore[no-untyped-def]
              items, ordered, row, no_centers, no_radii):  # fmt: skip
    _scan_into(ox, oy, cos, sin, segs, no_centers, no_radii, max_range, row)
    per = cos.shape[0] / (2.0 * math.pi)
    ci = _cell(ox, x0, h, nx)
    cj = _cell(oy, y0, h, ny)
    # rings of cells outward (ring k: the cells k away along x or y); once a ring's
    # nearest possible disc, farther than (k - 1) h, is beyond every reading, so are
    # the rest's
    for k in range(max(ci, nx - 1 - ci, cj, ny - 1 - cj) + 1):
        reach = _farthest(row) + radius
        if (k - 1) * h >= reach:
            return
        reach2 = reach * reach
        for j in range(max(cj - k, 0), min(cj + k, ny - 1) + 1):
            # the ring's top and bottom rows whole, its other rows at both ends
            jump = 1 if (j == cj - k or j == cj + k) else max(2 * k, 1)
            for i in range(ci - k, ci + k + 1, jump):
                if i < 0 or i >= nx or _cell_distance2(ox, oy, x0, y0, h, i, j) >= reach2:
                    continue
                if _discs_of_cell(b, ox, oy, j * nx + i, ordered, items, start, radius, cos,
                                  sin, per, reach2, row):  # fmt: skip
                    return


@njit(cache=True)
def scan_agents(positions, active, lo, hi, cos, sin, segs, radius, max_range, x0, y0, h, nx,  # type: ignore[no-untyped-def]
                ny, start, items, ordered, out):  # fmt: skip
    """``out[b]``: the ring reading of each active agent b in ``lo .. hi - 1`` against
    the walls ``segs`` and every other active agent's disc (radius ``radius``) in the
    grid; rows of inactive agents are left as they are. ``ordered`` holds the grid's
    agents' positions in the grid's order (:func:`build_grid`)."""
    no_centers = np.empty((0, 2))
    no_radii = np.empty(0)
    for b in range(lo, hi):
        if active[b]:
            _scan_one(b, positions[b, 0], positions[b, 1], cos, sin, segs, radius,
                      max_range, x0, y0, h, nx, ny, start, items, ordered, out[b],
                      no_centers, no_radii)  # fmt: skip


@njit(cache=True)
def clip_actions(actions, active, out):  # type: ignore[no-untyped-def]
    """``out[i]``: agent i's action (N, 2) if it is in the world (``active``), else 0,
    scaled to norm 1 if longer (divided by its norm, ``np.hypot``'s). Returns the first
    agent in the world whose action is not finite (``out`` then unfinished), else -1."""
    for i in range(actions.shape[0]):
        if not active[i]:
            out[i, 0] = 0.0
            out[i, 1] = 0.0
            continue
        ax = actions[i, 0]
        ay = actions[i, 1]
        if not (math.isfinite(ax) and math.isfinite(ay)):
            return i
        norm = np.hypot(ax, ay)
        if norm > 1.0:
            ax = ax / norm
            ay = ay / norm
        out[i, 0] = ax
        out[i, 1] = ay
    return -1


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
def agent_gaps(old, positions, active, radius, exact, x0, y0, h, nx, ny, start, items, ordered,  # type: ignore[no-untyped-def]
               gap):  # fmt: skip
    """``gap[b]`` for each agent b: the least surface distance between active agent b
    and any other over the step (both moving linearly from ``old`` to ``positions``,
    each by at most one agent step; negative: a contact), exact whenever it is below
    ``exact``, else at least ``exact``; inf when no agent started within ``exact`` + 2
    radii + 2 of b (none of those can come within ``exact``). The grid is the one of
    ``old`` (``ordered``: their positions in its order, :func:`build_grid`).

    Only the pairs that started that near are measured (a squared distance first: most
    agents of the cells around are farther), each pair once: the closest approach of b
    to k is the one of k to b, bit for bit (the differences only change sign)."""
    two_r = 2.0 * radius
    near = exact + two_r + 2.0
    near2 = near * near
    w = int(math.ceil(near / h))
    for b in range(old.shape[0]):
        gap[b] = np.inf
    for b in range(old.shape[0]):
        if not active[b]:
            continue
        ax = old[b, 0]
        ay = old[b, 1]
        adx = positions[b, 0] - ax
        ady = positions[b, 1] - ay
        ci = _cell(ax, x0, h, nx)
        cj = _cell(ay, y0, h, ny)
        for j in range(max(cj - w, 0), min(cj + w + 1, ny)):
            for i in range(max(ci - w, 0), min(ci + w + 1, nx)):
                c = j * nx + i
                for p in range(start[c], start[c + 1]):
                    ox = ordered[p, 0] - ax
                    oy = ordered[p, 1] - ay
                    if ox * ox + oy * oy > near2:
                        continue
                    k = items[p]
                    if k <= b:  # b itself, or a pair measured from k
                        continue
                    d = closest_approach(ax, ay, adx, ady, old[k, 0], old[k, 1],
                                         positions[k, 0] - old[k, 0],
                                         positions[k, 1] - old[k, 1]) - two_r  # fmt: skip
                    if d < gap[b]:
                        gap[b] = d
                    if d < gap[k]:
                        gap[k] = d


@njit(cache=True)
def arrived(positions, goals, was, tolerance, reached):  # type: ignore[no-untyped-def]
    """``reached[i]``: agent i, in the world for the step just taken (``was``), ended it
    with its centre within ``tolerance`` of its goal."""
    for i in range(positions.shape[0]):
        dx = positions[i, 0] - goals[i, 0]
        dy = positions[i, 1] - goals[i, 1]
        reached[i] = was[i] and np.hypot(dx, dy) <= tolerance


@njit(cache=True)
def account(positions, old, was, gap, reached, t, leave, velocities, path_length, contacts,  # type: ignore[no-untyped-def]
            min_gap, arrivals, outcome, ended, trip_length, active, contact, left):  # fmt: skip
    """The books of step ``t`` (the step just taken, from ``old`` to ``positions``, by
    the agents ``was`` in the world; ``reached``: :func:`arrived`) in one pass: each
    agent's velocity, path length, contacts (``gap`` below 0), least gap, arrivals, its
    first trip's outcome (:data:`SUCCESS`, :data:`COLLISION`), end and length; with
    ``leave``, an agent whose trip ended leaves (``active``). ``contact`` and ``left``
    receive the step's flags. The same sums, in the same order, as the arrays'."""
    for i in range(positions.shape[0]):
        vx = positions[i, 0] - old[i, 0]
        vy = positions[i, 1] - old[i, 1]
        velocities[i, 0] = vx
        velocities[i, 1] = vy
        path_length[i] += np.hypot(vx, vy)
        c = gap[i] < 0.0
        r = reached[i]
        contact[i] = c
        contacts[i] += c
        if gap[i] < min_gap[i]:
            min_gap[i] = gap[i]
        arrivals[i] += r
        if was[i] and outcome[i] == RUNNING and (c or r):
            outcome[i] = COLLISION if c else SUCCESS
            ended[i] = t
            trip_length[i] = path_length[i]
        left[i] = leave and was[i] and (c or r)
        if left[i]:
            active[i] = False


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
