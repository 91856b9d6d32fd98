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

from copi.bounds._field import field_at
from copi.geometry.kernels import (
    closest_approach,
    escapes,
    free_moves,
    local_segments,
    sweep_one,
)
from copi.planning.kernels import heap_pop, heap_push

# A move must clear every wall and disc by this much more than the simulator demands, so
# that rounding (the simulator normalises a command of norm 1 + 1e-16) never turns a
# planned move into a contact or a stop.
MARGIN = 1e-6

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


@njit(cache=True)
def _mark_contacts(samples, s, radii, agent_r, margin, x0, y0, res, blocked):  # type: ignore[no-untyped-def]
    """Sets ``blocked[t, i, j]`` where, in sample ``s`` at step t >= 1, some disc is within
    the sum of radii plus ``margin`` of the centre of window cell (i, j) (origin x0, y0,
    side ``res``); cells already set stay set."""
    horizon = samples.shape[1] - 1
    n = blocked.shape[1]
    for t in range(1, horizon + 1):
        for k in range(samples.shape[2]):
            reach = agent_r + radii[k] + margin
            cx = samples[s, t, k, 0]
            cy = samples[s, t, k, 1]
            j0 = max(int(math.ceil((cx - reach - x0) / res)), 0)
            j1 = min(int(math.floor((cx + reach - x0) / res)), n - 1)
            i0 = max(int(math.ceil((cy - reach - y0) / res)), 0)
            i1 = min(int(math.floor((cy + reach - y0) / res)), n - 1)
            r2 = reach * reach
            for i in range(i0, i1 + 1):
                py = y0 + i * res - cy
                for j in range(j0, j1 + 1):
                    px = x0 + j * res - cx
                    if px * px + py * py <= r2:
                        blocked[t, i, j] = True


@njit(cache=True)
def occupancy(samples, radii, agent_r, margin, x0, y0, res, n):  # type: ignore[no-untyped-def]
    """``P[t, i, j]``: the share of samples in which some disc, at step t, is within the
    sum of radii plus ``margin`` of the centre of window cell (i, j) (origin x0, y0, side
    ``res``, n x n cells)."""
    n_s = samples.shape[0]
    horizon = samples.shape[1] - 1
    count = np.zeros((horizon + 1, n, n), dtype=np.int32)
    blocked = np.zeros((horizon + 1, n, n), dtype=np.bool_)
    for s in range(n_s):
        blocked[:] = False
        _mark_contacts(samples, s, radii, agent_r, margin, x0, y0, res, blocked)
        for t in range(1, horizon + 1):
            for i in range(n):
                for j in range(n):
                    count[t, i, j] += blocked[t, i, j]
    out = np.empty((horizon + 1, n, n))
    for t in range(horizon + 1):
        for i in range(n):
            for j in range(n):
                out[t, i, j] = count[t, i, j] / n_s
    return out


@njit(cache=True, inline="always")
def _risk(p):  # type: ignore[no-untyped-def]
    """The cost of a probability of contact: minus the log of surviving it."""
    return -math.log(1.0 - min(p, 0.999))


@njit(cache=True, inline="always")
def _best_move(Vn, cost, i, j, offsets, mid_ok):  # type: ignore[no-untyped-def]
    """The least value of a move from cell (i, j) into the next step's layer: over the
    ``offsets`` that stay in the window and clear of walls (``mid_ok``), ``Vn`` plus
    ``cost`` at the cell reached (inf if none; an infinite ``Vn`` stays infinite)."""
    n = Vn.shape[0]
    best = np.inf
    for o in range(offsets.shape[0]):
        a = i + offsets[o, 0]
        b = j + offsets[o, 1]
        if a < 0 or b < 0 or a >= n or b >= n or not mid_ok[o, i, j]:
            continue
        v = Vn[a, b] + cost[a, b]
        if v < best:
            best = v
    return best


@njit(cache=True)
def risk_values(P, ok, terminal, goal, offsets, mid_ok, weight, discount):  # type: ignore[no-untyped-def]
    """Backward induction over the window. ``cost[t, i, j]`` = one step plus ``weight``
    times ``discount ** (t - 1)`` times the risk of being in cell (i, j) at step t (a
    risk far ahead weighs less: the agent replans before it gets there); ``V[t, i, j]`` =
    the least sum of costs from cell (i, j) at step t to the horizon, plus ``terminal``
    there (0 once in a ``goal`` cell: the episode ends). ``ok[i, j]``: the cell is free of walls;
    ``mid_ok[o, i, j]``: offset o from (i, j) keeps clear of them. Returns (V, cost),
    each (horizon + 1, n, n) (V[0] unused)."""
    horizon = P.shape[0] - 1
    n = P.shape[1]
    cost = np.empty_like(P)
    for t in range(horizon + 1):
        w = weight * discount ** max(t - 1, 0)
        for i in range(n):
            for j in range(n):
                cost[t, i, j] = 1.0 + w * _risk(P[t, i, j])
    V = np.full((horizon + 1, n, n), np.inf)
    V[horizon] = terminal
    for t in range(horizon - 1, 0, -1):
        for i in range(n):
            for j in range(n):
                if goal[i, j]:
                    V[t, i, j] = 0.0
                    continue
                if not ok[i, j]:
                    continue
                V[t, i, j] = _best_move(V[t + 1], cost[t + 1], i, j, offsets, mid_ok)
    return V, cost


@njit(cache=True, inline="always")
def _interp(V, x0, y0, res, x, y):  # type: ignore[no-untyped-def]
    """V at (x, y), bilinear over the finite corners of its window cell (inf if none)."""
    n = V.shape[0]
    fx = (x - x0) / res
    fy = (y - y0) / res
    j = int(math.floor(fx))
    i = int(math.floor(fy))
    u = fx - j
    w = fy - i
    total = 0.0
    mass = 0.0
    for di in range(2):
        for dj in range(2):
            a = i + di
            b = j + dj
            if a < 0 or b < 0 or a >= n or b >= n:
                continue
            v = V[a, b]
            if not math.isfinite(v):
                continue
            c = (w if di else 1.0 - w) * (u if dj else 1.0 - u)
            total += c * v
            mass += c
    if mass <= 1e-9:
        return np.inf
    return total / mass


@njit(cache=True)
def field_grid(dist, fx0, fy0, fh, x0, y0, res, ny, nx, gx, gy):  # type: ignore[no-untyped-def]
    """The field's distance to go at the centres of an ny x nx grid (origin x0, y0)."""
    out = np.empty((ny, nx))
    for i in range(ny):
        for j in range(nx):
            out[i, j] = field_at(dist, fx0, fy0, fh, x0 + j * res, y0 + i * res, gx, gy)
    return out


@njit(cache=True)
def window(ok, mid_ok, terminal, goal, i0, j0, n):  # type: ignore[no-untyped-def]
    """The n x n window of the episode's grids whose corner cell is (i0, j0); cells off
    the grids are walls."""
    ny, nx = ok.shape
    n_off = mid_ok.shape[0]
    w_ok = np.zeros((n, n), dtype=np.bool_)
    w_mid = np.zeros((n_off, n, n), dtype=np.bool_)
    w_term = np.full((n, n), np.inf)
    w_goal = np.zeros((n, n), dtype=np.bool_)
    for a in range(n):
        i = i0 + a
        if i < 0 or i >= ny:
            continue
        for b in range(n):
            j = j0 + b
            if j < 0 or j >= nx:
                continue
            w_ok[a, b] = ok[i, j]
            w_term[a, b] = terminal[i, j]
            w_goal[a, b] = goal[i, j]
            for o in range(n_off):
                w_mid[o, a, b] = mid_ok[o, i, j]
    return w_ok, w_mid, w_term, w_goal




@njit(cache=True)
def escape_move(  # type: ignore[no-untyped-def]
    px, py, gx, gy, tol, r, segs, samples, radii, moves, margin, escape_margin, V, x0, y0,
    res, loss, dist, fx0, fy0, fh,
):
    """The first move of least expected cost, counting as lost each sample in which the
    move is in contact, or leaves no second move clear of that sample's next step by
    ``escape_margin`` more (the agent, replanning, sees where the discs went but not yet
    where they go next: the margin stands for that). Cost: ``loss`` times the share
    lost, plus one step, plus the window's value ``V`` (step 1) after the move. Returns
    (move, cost, share of samples the move is in contact with)."""
    n_s = samples.shape[0]
    d = samples.shape[2]
    n_m = moves.shape[0]
    near = np.empty(d, dtype=np.int64)
    n_near = 0
    for k in range(d):
        ex = samples[0, 0, k, 0] - px
        ey = samples[0, 0, k, 1] - py
        far = 2.0 + 2.0 * 1.0 + r + radii[k] + margin + escape_margin
        if ex * ex + ey * ey <= far * far:
            near[n_near] = k
            n_near += 1
    local = local_segments(px, py, segs, 2.0 + r + 1e-3)
    free2 = np.zeros(n_m, dtype=np.bool_)
    best = -1
    best_cost = np.inf
    best_hit = 1.0
    for m in range(n_m):
        dx = moves[m, 0]
        dy = moves[m, 1]
        length = math.sqrt(dx * dx + dy * dy)
        swept = sweep_one(px, py, dx / length, dy / length, local, r) if length > 0.0 else 0.0
        if length > 0.0 and swept < length + MARGIN:
            continue
        qx = px + dx
        qy = py + dy
        done = math.sqrt((qx - gx) ** 2 + (qy - gy) ** 2) <= tol - MARGIN
        free_moves(qx, qy, r, local, moves, free2, MARGIN)  # second moves walls let through
        lost = 0
        hits = 0
        for s in range(n_s):
            hit = False
            for a in range(n_near):
                k = near[a]
                cx = samples[s, 0, k, 0]
                cy = samples[s, 0, k, 1]
                gap = closest_approach(px, py, dx, dy, cx, cy, samples[s, 1, k, 0] - cx,
                                        samples[s, 1, k, 1] - cy)  # fmt: skip
                if gap - r - radii[k] < margin:
                    hit = True
                    break
            if hit:
                hits += 1
                lost += 1
                continue
            if done:
                continue
            if not escapes(qx, qy, r, moves, free2, samples[s, 1], samples[s, 2], radii, near,
                           n_near, margin + escape_margin):  # fmt: skip
                lost += 1
        cost = loss * lost / n_s + 1.0
        if not done:
            v = _interp(V[1], x0, y0, res, qx, qy)
            if not math.isfinite(v):
                v = samples.shape[1] - 2 + field_at(dist, fx0, fy0, fh, qx, qy, gx, gy)
            cost += v
        if cost < best_cost:
            best = m
            best_cost = cost
            best_hit = hits / n_s
    return best, best_cost, best_hit


@njit(cache=True)
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

    Against :func:`risk_values` (which averages the discs first and plans once against
    the mean occupancy, so that at a few steps' distance every cell a disc may reach looks
    risky), this plans once per future and averages the plans' costs: it assumes the agent
    will see each future as it comes, which is optimistic (it will see it a step at a
    time), where the mean-occupancy plan is pessimistic.

    ``box`` >= 0: only the cells an agent starting at the window's centre can be in are
    solved, those within ``box`` + 2 t cells of the centre at step t (a move goes at most
    2 cells: ``offsets``); the values there are those of the whole window, the rest of
    step 1 is left infinite. ``box`` < 0: the whole window."""
    n_s = samples.shape[0]
    horizon = samples.shape[1] - 1
    n = ok.shape[0]
    c = n // 2
    lo1, hi1 = 0, n - 1  # the cells of step 1 solved
    if box >= 0:
        lo1 = max(c - box - 2, 0)
        hi1 = min(c + box + 2, n - 1)
    blocked = np.zeros((horizon + 1, n, n), dtype=np.bool_)
    Vn = np.empty((n, n))
    Vc = np.full((n, n), np.inf)
    step = np.ones((n, n))  # every move costs one step
    total = np.zeros((n, n))
    for s in range(n_s):
        blocked[:] = False
        _mark_contacts(samples, s, radii, agent_r, margin, x0, y0, res, blocked)
        for i in range(n):
            for j in range(n):
                Vn[i, j] = terminal[i, j] if not blocked[horizon, i, j] else np.inf
        for t in range(horizon - 1, 0, -1):
            lo, hi = 0, n - 1
            if box >= 0:
                lo = max(c - box - 2 * t, 0)
                hi = min(c + box + 2 * t, n - 1)
            for i in range(lo, hi + 1):
                for j in range(lo, hi + 1):
                    if blocked[t, i, j] or not ok[i, j]:
                        Vc[i, j] = np.inf
                        continue
                    if goal[i, j]:
                        Vc[i, j] = 0.0
                        continue
                    Vc[i, j] = _best_move(Vn, step, i, j, offsets, mid_ok)
            Vn, Vc = Vc, Vn
        for i in range(lo1, hi1 + 1):
            for j in range(lo1, hi1 + 1):
                total[i, j] += min(Vn[i, j], cap)
    V = np.full((horizon + 1, n, n), np.inf)
    for i in range(lo1, hi1 + 1):
        for j in range(lo1, hi1 + 1):
            if ok[i, j]:
                V[1, i, j] = total[i, j] / n_s
    return V
