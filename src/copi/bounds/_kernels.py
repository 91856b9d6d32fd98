"""Compiled searches of the ceilings.

Why by hand: both ceilings search over space *and time* (a move is safe or not depending
on when it is made), with the simulator's own tests of walls and contacts, over hundreds
of thousands of moves an episode. No planning library searches a continuous position
against moving discs with the simulator's swept tests; networkx or Python heaps would be
a hundred times slower than these loops.

The tests are the simulator's (:mod:`copi.geometry.kernels`): a move is made only when
a wall does not stop it (``sweep_one``), and it is in contact when the closest approach
of the two linear motions over the step is below the sum of radii (``closest_approach``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, types
from numba.typed import Dict

from copi.geometry.kernels import closest_approach, local_segments, sweep_one
from copi.planning.futures import MARGIN, field_at
from copi.planning.kernels import heap_pop, heap_push

_OFFSET = 4096
_SIDE = 8192


@njit(cache=True, inline="always")
def _key(x, y, t, q):  # type: ignore[no-untyped-def]
    ix = int(math.floor(x / q)) + _OFFSET
    iy = int(math.floor(y / q)) + _OFFSET
    return (np.int64(t) * _SIDE + iy) * _SIDE + ix



@njit(cache=True)
def spacetime_astar(  # type: ignore[no-untyped-def]
    x0, y0, gx, gy, tol, r, segs, future, dist, fx0, fy0, fh, moves, dirs, q, weight, max_nodes
):
    """A* over (position, time) against the recorded future of every disc.

    ``future[t, k] = (x, y, radius)`` of disc k at step t (t = 0 .. T); ``moves[m]`` the
    agent's displacements (``dirs[m]`` the index of its direction among the unit vectors
    of ``moves``, -1 for waiting); ``q`` the side of the cells that merge states at one
    step; the cost is the number of steps, the heuristic ``weight`` times the field's
    distance to go (``dist`` with origin ``fx0, fy0`` and side ``fh``).

    Returns ``(goal, n, xs, ys, parent, move)``: the index of the node that reaches the
    goal (-1: no plan within T steps; -2: the budget of ``max_nodes`` ran out), the number
    of nodes, and the search tree (the plan is the moves from the goal back to node 0).
    """
    T = future.shape[0] - 1
    d = future.shape[1]
    xs = np.empty(max_nodes)
    ys = np.empty(max_nodes)
    ts = np.empty(max_nodes, dtype=np.int32)
    parent = np.empty(max_nodes, dtype=np.int32)
    move = np.empty(max_nodes, dtype=np.int16)
    keys = np.empty(max_nodes)
    items = np.empty(max_nodes, dtype=np.int64)
    n_dirs = 0
    for m in range(dirs.shape[0]):
        n_dirs = max(n_dirs, dirs[m] + 1)
    free = np.empty(n_dirs)
    unit = np.zeros((n_dirs, 2))
    for m in range(moves.shape[0]):
        if dirs[m] >= 0:
            length = math.sqrt(moves[m, 0] ** 2 + moves[m, 1] ** 2)
            unit[dirs[m], 0] = moves[m, 0] / length
            unit[dirs[m], 1] = moves[m, 1] / length
    seen = Dict.empty(key_type=types.int64, value_type=types.boolean)
    h0 = field_at(dist, fx0, fy0, fh, x0, y0, gx, gy)
    xs[0] = x0
    ys[0] = y0
    ts[0] = 0
    parent[0] = -1
    move[0] = -1
    n = 1
    if not math.isfinite(h0):
        return -1, n, xs, ys, parent, move
    seen[_key(x0, y0, 0, q)] = True
    size = heap_push(keys, items, 0, weight * max(h0 - tol, 0.0), 0)
    while size > 0:
        _, u, size = heap_pop(keys, items, size)
        x = xs[u]
        y = ys[u]
        t = ts[u]
        if t >= T:
            continue
        local = local_segments(x, y, segs, 1.0 + r + 1e-3)
        for j in range(n_dirs):
            free[j] = sweep_one(x, y, unit[j, 0], unit[j, 1], local, r)
        for m in range(moves.shape[0]):
            dx = moves[m, 0]
            dy = moves[m, 1]
            if dirs[m] >= 0 and free[dirs[m]] < math.sqrt(dx * dx + dy * dy) + MARGIN:
                continue
            nx = x + dx
            ny = y + dy
            safe = True
            for k in range(d):
                cx = future[t, k, 0]
                cy = future[t, k, 1]
                gap = closest_approach(
                    x, y, dx, dy, cx, cy, future[t + 1, k, 0] - cx, future[t + 1, k, 1] - cy
                )
                if gap - r - future[t, k, 2] < MARGIN:
                    safe = False
                    break
            if not safe:
                continue
            if n >= max_nodes:
                return -2, n, xs, ys, parent, move
            key = _key(nx, ny, t + 1, q)
            reached = math.sqrt((nx - gx) ** 2 + (ny - gy) ** 2) <= tol - MARGIN
            if key in seen and not reached:
                continue
            hv = field_at(dist, fx0, fy0, fh, nx, ny, gx, gy)
            if not math.isfinite(hv) and not reached:
                continue
            seen[key] = True
            xs[n] = nx
            ys[n] = ny
            ts[n] = t + 1
            parent[n] = u
            move[n] = m
            n += 1
            if reached:
                return n - 1, n, xs, ys, parent, move
            size = heap_push(keys, items, size, t + 1 + weight * max(hv - tol, 0.0), n - 1)
    return -1, n, xs, ys, parent, move


# -- the model-predictive oracle --------------------------------------------------------


@njit(cache=True)
def sample_futures(  # type: ignore[no-untyped-def]
    obstacles, segs, n_samples, horizon, turn_sd, retries, seed, clear, cx0, cy0, ch, fallback
):
    """``n_samples`` futures of the discs' random walk over ``horizon`` steps, drawn with
    the simulator's own rule (:func:`copi.geometry.kernels.step_world`): each step the
    heading turns by N(0, ``turn_sd``); a move that would touch a wall tries ``retries``
    uniform headings, else the disc waits. A disc's heading and speed are those of its
    observed velocity (a disc seen waiting: a uniform heading at ``fallback``, or at the
    others' greatest speed when ``fallback`` <= 0).

    ``obstacles`` rows (x, y, vx, vy, radius); ``clear``: the distance to the walls on a
    grid (origin cx0, cy0, side ch), which spares the swept test of a move that cannot
    reach a wall. Returns (n_samples, horizon + 1, d, 2).
    """
    cny, cnx = clear.shape
    slack = ch * 0.7072  # a point is at most this far from its cell's centre
    np.random.seed(seed)
    d = obstacles.shape[0]
    out = np.empty((n_samples, horizon + 1, d, 2))
    if fallback <= 0.0:
        fallback = 0.0
        for k in range(d):
            fallback = max(fallback, math.sqrt(obstacles[k, 2] ** 2 + obstacles[k, 3] ** 2))
    for k in range(d):
        x = obstacles[k, 0]
        y = obstacles[k, 1]
        vx = obstacles[k, 2]
        vy = obstacles[k, 3]
        rk = obstacles[k, 4]
        speed = math.sqrt(vx * vx + vy * vy)
        seen = speed > 1e-9
        if not seen:
            speed = fallback
        local = local_segments(x, y, segs, horizon * speed + rk + 1e-3)
        h0 = math.atan2(vy, vx)
        for s in range(n_samples):
            cx = x
            cy = y
            h = h0 if seen else 2.0 * math.pi * np.random.random()
            out[s, 0, k, 0] = cx
            out[s, 0, k, 1] = cy
            for t in range(horizon):
                g = h + np.random.normal(0.0, turn_sd)
                ci = int(math.floor((cy - cy0) / ch + 0.5))
                cj = int(math.floor((cx - cx0) / ch + 0.5))
                far = (0 <= ci < cny and 0 <= cj < cnx
                       and clear[ci, cj] - slack > speed + rk + 1e-6)  # fmt: skip
                for j in range(retries + 1):
                    if j > 0:
                        g = 2.0 * math.pi * np.random.random()
                    dx = math.cos(g)
                    dy = math.sin(g)
                    if speed > 0.0 and (far or sweep_one(cx, cy, dx, dy, local, rk) >= speed):
                        cx += speed * dx
                        cy += speed * dy
                        h = g
                        break
                out[s, t + 1, k, 0] = cx
                out[s, t + 1, k, 1] = cy
    return out
