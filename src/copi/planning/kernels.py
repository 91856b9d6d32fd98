"""Compiled inner loops of the planners.

Why by hand: the reference path of every Experiment-1 episode needs a visibility graph of
a fresh snapshot (walls plus frozen discs) and an A* search on it, thousands of times; the
Moving AI checks run A* on 512 x 512 grids tens of thousands of times. networkx would take
seconds for one 512 x 512 grid search, and no library builds a visibility graph of a
closed polygonal free space with tangent pruning. These loops do, in milliseconds.

Geometry conventions: the free space is closed (paths may run along its edges and through
its vertices). Its boundary is a set of rings, each a run of vertices in ``xy`` between
``starts[k]`` and ``starts[k + 1]``, oriented with the free space on the left (outer rings
counter-clockwise, holes clockwise). Point-in-free-space is the even-odd rule over all
rings, with points on an edge counted as free.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

SQRT2 = math.sqrt(2.0)

# -- binary heap over (key, item) in two arrays -----------------------------------------


@njit(cache=True, inline="always")
def heap_push(keys, items, size, key, item):  # type: ignore[no-untyped-def]
    i = size
    keys[i] = key
    items[i] = item
    while i > 0:
        parent = (i - 1) >> 1
        if keys[parent] <= keys[i]:
            break
        keys[parent], keys[i] = keys[i], keys[parent]
        items[parent], items[i] = items[i], items[parent]
        i = parent
    return size + 1


@njit(cache=True, inline="always")
def heap_room(keys, items, size):  # type: ignore[no-untyped-def]
    """(keys, items) with room for one more entry: the same arrays, or twice as large."""
    if size < keys.shape[0]:
        return keys, items
    k2 = np.empty(2 * keys.shape[0])
    i2 = np.empty(2 * keys.shape[0], dtype=np.int64)
    k2[:size] = keys[:size]
    i2[:size] = items[:size]
    return k2, i2


@njit(cache=True, inline="always")
def heap_pop(keys, items, size):  # type: ignore[no-untyped-def]
    key = keys[0]
    item = items[0]
    size -= 1
    keys[0] = keys[size]
    items[0] = items[size]
    i = 0
    while True:
        left = 2 * i + 1
        if left >= size:
            break
        child = left
        if left + 1 < size and keys[left + 1] < keys[left]:
            child = left + 1
        if keys[i] <= keys[child]:
            break
        keys[child], keys[i] = keys[i], keys[child]
        items[child], items[i] = items[i], items[child]
        i = child
    return key, item, size


# -- grid A* (Moving AI conventions) ----------------------------------------------------


@njit(cache=True)
def grid_astar(free, sx, sy, gx, gy, g, parent, stamp, query):  # type: ignore[no-untyped-def]
    """Octile A* on a boolean grid ``free[y, x]``: 8-connected, straight 1, diagonal
    sqrt 2, no corner cutting (a diagonal needs both orthogonal neighbours free).

    ``g``, ``parent`` and ``stamp`` are flat work arrays of the grid's size, reused across
    queries: an entry is valid for this query only when ``stamp`` equals ``query`` (a
    different number each call), which saves clearing megabytes per query. Returns the
    length (inf when unreachable); ``parent`` then holds the predecessor of each reached
    cell (flat index, -1 at the start).
    """
    h, w = free.shape
    cap = 1024
    keys = np.empty(cap)
    items = np.empty(cap, dtype=np.int64)
    start = sy * w + sx
    goal = gy * w + gx
    # stamp: == query -> g valid and open; == -query -> closed.
    g[start] = 0.0
    parent[start] = -1
    stamp[start] = query
    size = heap_push(keys, items, 0, _octile(sx, sy, gx, gy), start)
    while size > 0:
        key, u, size = heap_pop(keys, items, size)
        if stamp[u] == -query:
            continue
        if u == goal:
            return g[u]
        stamp[u] = -query
        ux = u % w
        uy = u // w
        for dy in range(-1, 2):
            for dx in range(-1, 2):
                if dx == 0 and dy == 0:
                    continue
                vx = ux + dx
                vy = uy + dy
                if vx < 0 or vy < 0 or vx >= w or vy >= h or not free[vy, vx]:
                    continue
                if dx != 0 and dy != 0:
                    if not (free[uy, vx] and free[vy, ux]):
                        continue
                    step = SQRT2
                else:
                    step = 1.0
                v = vy * w + vx
                if stamp[v] == -query:
                    continue
                cand = g[u] + step
                if stamp[v] != query or cand < g[v] - 1e-12:
                    g[v] = cand
                    parent[v] = u
                    stamp[v] = query
                    keys, items = heap_room(keys, items, size)
                    size = heap_push(keys, items, size, cand + _octile(vx, vy, gx, gy), v)
    return np.inf


@njit(cache=True, inline="always")
def _octile(x0, y0, x1, y1):  # type: ignore[no-untyped-def]
    dx = abs(x1 - x0)
    dy = abs(y1 - y0)
    return max(dx, dy) + (SQRT2 - 1.0) * min(dx, dy)


# -- closed polygonal free space: points and segments ---------------------------------


@njit(cache=True, inline="always")
def _on_segment(px, py, ax, ay, bx, by, eps):  # type: ignore[no-untyped-def]
    """Whether p lies on segment ab (within eps, absolute)."""
    ex = bx - ax
    ey = by - ay
    ll = ex * ex + ey * ey
    if ll == 0.0:
        return (px - ax) ** 2 + (py - ay) ** 2 <= eps * eps
    t = ((px - ax) * ex + (py - ay) * ey) / ll
    if t < 0.0:
        t = 0.0
    elif t > 1.0:
        t = 1.0
    dx = ax + t * ex - px
    dy = ay + t * ey - py
    return dx * dx + dy * dy <= eps * eps


@njit(cache=True)
def point_free(px, py, xy, starts, eps):  # type: ignore[no-untyped-def]
    """Whether p lies in the closed free space (on an edge counts as free)."""
    inside = False
    for k in range(starts.shape[0] - 1):
        a = starts[k]
        b = starts[k + 1]
        for i in range(a, b):
            j = i + 1 if i + 1 < b else a
            ax = xy[i, 0]
            ay = xy[i, 1]
            bx = xy[j, 0]
            by = xy[j, 1]
            if _on_segment(px, py, ax, ay, bx, by, eps):
                return True
            if (ay > py) != (by > py):
                x = ax + (py - ay) * (bx - ax) / (by - ay)
                if x > px:
                    inside = not inside
    return inside


@njit(cache=True)
def segment_free(ax, ay, bx, by, xy, starts, eps, pins):  # type: ignore[no-untyped-def]
    """Whether the segment ab lies in the closed free space, touching none of the
    points ``pins`` (shape (p, 2); see VisibilityGraph's ``through_pinch_points``).

    Rejected at once if it properly crosses a boundary edge. Otherwise it is cut at every
    boundary vertex it touches, and each piece's midpoint must be free: a piece between
    consecutive touch points crosses no edge, so it is free or blocked as a whole.
    """
    for k in range(pins.shape[0]):
        if _on_segment(pins[k, 0], pins[k, 1], ax, ay, bx, by, eps):
            return False
    dx = bx - ax
    dy = by - ay
    length = math.sqrt(dx * dx + dy * dy)
    if length == 0.0:
        return point_free(ax, ay, xy, starts, eps)
    n = xy.shape[0]
    cuts = np.empty(n + 2)
    m = 0
    cuts[m] = 0.0
    m += 1
    cuts[m] = 1.0
    m += 1
    for k in range(starts.shape[0] - 1):
        s0 = starts[k]
        s1 = starts[k + 1]
        for i in range(s0, s1):
            j = i + 1 if i + 1 < s1 else s0
            cx = xy[i, 0]
            cy = xy[i, 1]
            ex = xy[j, 0]
            ey = xy[j, 1]
            # Signed distances of c and e from the line ab, and of a and b from ce.
            d1 = ((cx - ax) * dy - (cy - ay) * dx) / length
            d2 = ((ex - ax) * dy - (ey - ay) * dx) / length
            fx = ex - cx
            fy = ey - cy
            flen = math.sqrt(fx * fx + fy * fy)
            if flen == 0.0:
                continue
            d3 = ((ax - cx) * fy - (ay - cy) * fx) / flen
            d4 = ((bx - cx) * fy - (by - cy) * fx) / flen
            if ((d1 > eps and d2 < -eps) or (d1 < -eps and d2 > eps)) and (
                (d3 > eps and d4 < -eps) or (d3 < -eps and d4 > eps)
            ):
                return False
            # Vertex c touching the open segment: a cut.
            if abs(d1) <= eps:
                t = ((cx - ax) * dx + (cy - ay) * dy) / (length * length)
                if 0.0 < t < 1.0:
                    cuts[m] = t
                    m += 1
    c = np.sort(cuts[:m])
    for i in range(m - 1):
        if c[i + 1] - c[i] <= 1e-12:
            continue
        t = 0.5 * (c[i] + c[i + 1])
        if not point_free(ax + t * dx, ay + t * dy, xy, starts, eps):
            return False
    return True


@njit(cache=True)
def ring_neighbours(starts, n):  # type: ignore[no-untyped-def]
    """Previous and next vertex index of every vertex along its ring."""
    prev = np.empty(n, dtype=np.int64)
    nxt = np.empty(n, dtype=np.int64)
    for k in range(starts.shape[0] - 1):
        a = starts[k]
        b = starts[k + 1]
        for i in range(a, b):
            prev[i] = i - 1 if i > a else b - 1
            nxt[i] = i + 1 if i + 1 < b else a
    return prev, nxt


@njit(cache=True)
def reflex_vertices(xy, starts):  # type: ignore[no-untyped-def]
    """Indices of the vertices where the free space turns right (interior angle > 180
    degrees): the only vertices a shortest path can bend at."""
    n = xy.shape[0]
    prev, nxt = ring_neighbours(starts, n)
    out = np.empty(n, dtype=np.int64)
    m = 0
    for i in range(n):
        p = prev[i]
        q = nxt[i]
        cross = (xy[i, 0] - xy[p, 0]) * (xy[q, 1] - xy[i, 1]) - (xy[i, 1] - xy[p, 1]) * (
            xy[q, 0] - xy[i, 0]
        )
        if cross < 0.0:
            out[m] = i
            m += 1
    return out[:m]


@njit(cache=True, inline="always")
def _tangent(xy, prev, nxt, v, wx, wy):  # type: ignore[no-untyped-def]
    """Whether the line from w through vertex v leaves v's ring neighbours on one side
    (a shortest path through a vertex bends around it, never into it)."""
    vx = xy[v, 0]
    vy = xy[v, 1]
    dx = vx - wx
    dy = vy - wy
    s1 = dx * (xy[prev[v], 1] - wy) - dy * (xy[prev[v], 0] - wx)
    s2 = dx * (xy[nxt[v], 1] - wy) - dy * (xy[nxt[v], 0] - wx)
    return s1 * s2 >= 0.0


@njit(cache=True)
def visibility_edges(xy, starts, reflex, eps, pins):  # type: ignore[no-untyped-def]
    """Edges (i, j, length) of the reduced visibility graph among ``reflex`` vertices:
    tangent at both ends and inside the closed free space."""
    n = xy.shape[0]
    prev, nxt = ring_neighbours(starts, n)
    r = reflex.shape[0]
    cap = 64
    ei = np.empty(cap, dtype=np.int64)
    ej = np.empty(cap, dtype=np.int64)
    m = 0
    for a in range(r):
        i = reflex[a]
        for b in range(a + 1, r):
            j = reflex[b]
            if not _tangent(xy, prev, nxt, i, xy[j, 0], xy[j, 1]):
                continue
            if not _tangent(xy, prev, nxt, j, xy[i, 0], xy[i, 1]):
                continue
            if not segment_free(xy[i, 0], xy[i, 1], xy[j, 0], xy[j, 1], xy, starts, eps, pins):
                continue
            if m == cap:
                cap *= 2
                ei2 = np.empty(cap, dtype=np.int64)
                ej2 = np.empty(cap, dtype=np.int64)
                ei2[:m] = ei[:m]
                ej2[:m] = ej[:m]
                ei = ei2
                ej = ej2
            ei[m] = a
            ej[m] = b
            m += 1
    return ei[:m], ej[:m]


@njit(cache=True)
def visible_from(px, py, xy, starts, reflex, eps, pins):  # type: ignore[no-untyped-def]
    """Which reflex vertices a free point sees along a segment tangent at the vertex."""
    n = xy.shape[0]
    prev, nxt = ring_neighbours(starts, n)
    out = np.zeros(reflex.shape[0], dtype=np.bool_)
    for a in range(reflex.shape[0]):
        i = reflex[a]
        if not _tangent(xy, prev, nxt, i, px, py):
            continue
        out[a] = segment_free(px, py, xy[i, 0], xy[i, 1], xy, starts, eps, pins)
    return out


@njit(cache=True)
def graph_astar(pts, indptr, indices, weights, s_vis, g_vis, sx, sy, gx, gy, direct):  # type: ignore[no-untyped-def]
    """A* from a start point to a goal point over the graph of ``pts`` (CSR adjacency),
    the start linked to the vertices flagged in ``s_vis``, the goal to those in ``g_vis``,
    and to each other when ``direct``. Euclidean heuristic (admissible and consistent).

    Returns (length, parent) with parent[v] = predecessor (-1: the start); the goal's
    predecessor is parent[n] (-1: straight from the start; -2: unreachable).
    """
    n = pts.shape[0]
    g = np.full(n + 1, np.inf)
    parent = np.full(n + 1, -2, dtype=np.int64)
    closed = np.zeros(n + 1, dtype=np.bool_)
    cap = indices.shape[0] + 2 * n + 4
    keys = np.empty(cap)
    items = np.empty(cap, dtype=np.int64)
    size = 0
    if direct:
        d = math.hypot(gx - sx, gy - sy)
        g[n] = d
        parent[n] = -1
        size = heap_push(keys, items, size, d, n)
    for v in range(n):
        if s_vis[v]:
            d = math.hypot(pts[v, 0] - sx, pts[v, 1] - sy)
            g[v] = d
            parent[v] = -1
            size = heap_push(keys, items, size, d + math.hypot(gx - pts[v, 0], gy - pts[v, 1]), v)
    while size > 0:
        _, u, size = heap_pop(keys, items, size)
        if closed[u]:
            continue
        if u == n:
            return g[n], parent
        closed[u] = True
        ux = pts[u, 0]
        uy = pts[u, 1]
        if g_vis[u]:
            cand = g[u] + math.hypot(gx - ux, gy - uy)
            if cand < g[n]:
                g[n] = cand
                parent[n] = u
                size = heap_push(keys, items, size, cand, n)
        for e in range(indptr[u], indptr[u + 1]):
            v = indices[e]
            cand = g[u] + weights[e]
            if cand < g[v]:
                g[v] = cand
                parent[v] = u
                size = heap_push(
                    keys, items, size, cand + math.hypot(gx - pts[v, 0], gy - pts[v, 1]), v
                )
    return np.inf, parent
