"""Compiled inner loops of copi's geometry.

Why by hand: a sensor scan is 32 rays against every wall segment and every moving disc, and
it runs on every step of every agent. Shapely answers one ray in tens of microseconds and
vectorised numpy builds (rays x primitives) temporaries for a few dozen numbers; a compiled
loop with early culling does the whole scan in about the time numpy takes to allocate one
temporary (see ``benchmarks/bench_world.py``). The public, validated entry points are in
``_rays.py`` and ``_motion.py``; these functions trust their arguments.

Conventions: a segment is a row ``(px, py, qx, qy)``; a direction is a unit vector; every
time or range is a length along the ray, in agent steps.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# A hit exactly at the far end of the sensor's range is kept as "no hit" (max range).


@njit(cache=True, inline="always")
def ray_disc(dx, dy, vx, vy, cc):  # type: ignore[no-untyped-def]
    """How far along the unit ray (dx, dy) a disc is first hit, from a point at (vx, vy)
    from the disc's centre, ``cc`` = vx² + vy² − r² > 0 (the point outside it); inf when
    the ray misses it or it lies behind."""
    b = dx * vx + dy * vy
    if b >= 0.0:
        return np.inf
    disc = b * b - cc
    if disc < 0.0:
        return np.inf
    return -b - math.sqrt(disc)


@njit(cache=True, inline="always")
def _scan_into(ox, oy, cos, sin, segs, centers, radii, max_range, out):  # type: ignore[no-untyped-def]
    n = cos.shape[0]
    for i in range(n):
        out[i] = max_range
    r2max = max_range * max_range
    for k in range(segs.shape[0]):
        px = segs[k, 0]
        py = segs[k, 1]
        ex = segs[k, 2] - px
        ey = segs[k, 3] - py
        wx = px - ox
        wy = py - oy
        ll = ex * ex + ey * ey
        # Cull segments entirely out of range: distance from the origin to the segment.
        u = -(wx * ex + wy * ey) / ll if ll > 0.0 else 0.0
        u = min(max(u, 0.0), 1.0)
        cx = wx + u * ex
        cy = wy + u * ey
        if cx * cx + cy * cy >= r2max:
            continue
        wxe = wx * ey - wy * ex
        for i in range(n):
            dx = cos[i]
            dy = sin[i]
            den = dx * ey - dy * ex
            if den == 0.0:
                continue
            t = wxe / den
            if t < 0.0 or t >= out[i]:
                continue
            s = (wx * dy - wy * dx) / den
            if 0.0 <= s <= 1.0:
                out[i] = t
    for k in range(radii.shape[0]):
        r = radii[k]
        vx = ox - centers[k, 0]
        vy = oy - centers[k, 1]
        cc = vx * vx + vy * vy - r * r
        if cc <= 0.0:
            # The origin is inside the disc: everything is blocked at once.
            for i in range(n):
                out[i] = 0.0
            return
        reach = max_range + r
        if vx * vx + vy * vy >= reach * reach:
            continue
        for i in range(n):
            t = ray_disc(cos[i], sin[i], vx, vy, cc)
            if t < out[i]:
                out[i] = t


@njit(cache=True)
def scan(origins, cos, sin, segs, centers, radii, max_range, out):  # type: ignore[no-untyped-def]
    """Fill ``out[b, i]`` with the range of ray i from origin b (see module docstring)."""
    for b in range(origins.shape[0]):
        _scan_into(origins[b, 0], origins[b, 1], cos, sin, segs, centers, radii, max_range, out[b])


@njit(cache=True, inline="always")
def _finite(a):  # type: ignore[no-untyped-def]
    for v in a.flat:
        if not math.isfinite(v):
            return False
    return True


@njit(cache=True)
def scan_checked(origins, cos, sin, segs, centers, radii, max_range, out):  # type: ignore[no-untyped-def]
    """:func:`scan` after checking, in the same compiled call, that every input is finite
    and every radius >= 0; returns False (and computes nothing) otherwise. Checking here
    costs nanoseconds where numpy's isfinite costs a microsecond per array."""
    if not (
        _finite(origins)
        and _finite(cos)
        and _finite(sin)
        and _finite(segs)
        and _finite(centers)
        and _finite(radii)
        and math.isfinite(max_range)
    ):
        return False
    for v in radii:
        if v < 0.0:
            return False
    if not max_range > 0.0:
        return False
    scan(origins, cos, sin, segs, centers, radii, max_range, out)
    return True


# A disc touching a wall (to rounding) may move along it: only a move whose component
# into the wall exceeds this (per unit of travel) counts as entering it. Sliding along
# the tangent of a corner circle then stays within ~1e-9 of the contact distance.
TANGENT = 1e-7


@njit(cache=True, inline="always")
def sweep_one(ox, oy, dx, dy, segs, r):  # type: ignore[no-untyped-def]
    """Distance a disc of radius r at o can travel along the unit vector d before it
    touches a segment, or inf. Only entering contacts count, so a disc resting against a
    wall may slide along it or leave it."""
    best = np.inf
    for k in range(segs.shape[0]):
        px = segs[k, 0]
        py = segs[k, 1]
        qx = segs[k, 2]
        qy = segs[k, 3]
        ex = qx - px
        ey = qy - py
        ll = ex * ex + ey * ey
        if ll > 0.0:
            el = math.sqrt(ll)
            nx = -ey / el
            ny = ex / el
            h = (ox - px) * nx + (oy - py) * ny
            if h < 0.0:
                nx = -nx
                ny = -ny
                h = -h
            dn = dx * nx + dy * ny
            if dn < 0.0:
                t = (h - r) / -dn
                if t < 0.0:
                    # Already touching (to rounding): only a move clearly into the wall
                    # is stopped; a tangential one slides on.
                    if dn > -TANGENT:
                        continue
                    t = 0.0
                if t < best:
                    s = ((ox + t * dx - px) * ex + (oy + t * dy - py) * ey) / ll
                    if 0.0 <= s <= 1.0:
                        best = t
        for j in range(2):
            cx = px if j == 0 else qx
            cy = py if j == 0 else qy
            vx = ox - cx
            vy = oy - cy
            b = dx * vx + dy * vy
            if b >= 0.0:
                continue
            cc = vx * vx + vy * vy - r * r
            if cc <= 0.0:
                if b > -TANGENT:
                    continue  # touching the corner and moving along it
                t = 0.0
            else:
                disc = b * b - cc
                if disc < 0.0:
                    continue
                t = -b - math.sqrt(disc)
            if t < best:
                best = t
    return best


# Gap kept between a stopped disc and the wall it ran into, so that rounding never puts
# it on the far side of the contact.
STOP_GAP = 1e-9


@njit(cache=True, inline="always")
def move_one(ox, oy, vx, vy, segs, r):  # type: ignore[no-untyped-def]
    """Move a disc by (vx, vy), stopping it at the first wall; returns (x, y, blocked)."""
    length = math.sqrt(vx * vx + vy * vy)
    if length == 0.0:
        return ox, oy, False
    dx = vx / length
    dy = vy / length
    free = sweep_one(ox, oy, dx, dy, segs, r)
    if free >= length:
        return ox + vx, oy + vy, False
    step = max(free - STOP_GAP, 0.0)
    return ox + step * dx, oy + step * dy, True


@njit(cache=True)
def move(positions, velocities, segs, r, out):  # type: ignore[no-untyped-def]
    """Move each disc (row) by its velocity; ``out[b] = (x, y, blocked)``."""
    for b in range(positions.shape[0]):
        x, y, blocked = move_one(
            positions[b, 0], positions[b, 1], velocities[b, 0], velocities[b, 1], segs, r
        )
        out[b, 0] = x
        out[b, 1] = y
        out[b, 2] = 1.0 if blocked else 0.0


@njit(cache=True, inline="always")
def point_segment_d2(x, y, segs, k):  # type: ignore[no-untyped-def]
    """Squared distance from (x, y) to segment k of ``segs`` (rows x0, y0, x1, y1)."""
    px = segs[k, 0]
    py = segs[k, 1]
    ex = segs[k, 2] - px
    ey = segs[k, 3] - py
    ll = ex * ex + ey * ey
    u = ((x - px) * ex + (y - py) * ey) / ll if ll > 0.0 else 0.0
    u = min(max(u, 0.0), 1.0)
    cx = px + u * ex - x
    cy = py + u * ey - y
    return cx * cx + cy * cy


@njit(cache=True, inline="always")
def _clearance_one(x, y, segs):  # type: ignore[no-untyped-def]
    best = np.inf
    for k in range(segs.shape[0]):
        d = point_segment_d2(x, y, segs, k)
        if d < best:
            best = d
    return math.sqrt(best)


@njit(cache=True)
def clearance(points, segs, out):  # type: ignore[no-untyped-def]
    """``out[b]`` = distance from point b to the nearest segment."""
    for b in range(points.shape[0]):
        out[b] = _clearance_one(points[b, 0], points[b, 1], segs)


@njit(cache=True, inline="always")
def closest_approach(ax, ay, adx, ady, bx, by, bdx, bdy):  # type: ignore[no-untyped-def]
    """Least distance between two points moving linearly over t in [0, 1]."""
    px = ax - bx
    py = ay - by
    vx = adx - bdx
    vy = ady - bdy
    vv = vx * vx + vy * vy
    t = 0.0
    if vv > 0.0:
        t = min(max(-(px * vx + py * vy) / vv, 0.0), 1.0)
    qx = px + t * vx
    qy = py + t * vy
    return math.sqrt(qx * qx + qy * qy)


@njit(cache=True)
def step_world(  # type: ignore[no-untyped-def]
    agent,
    action,
    agent_radius,
    segs,
    centers,
    headings,
    radii,
    speed,
    turn,
    retry,
    cos,
    sin,
    max_range,
    ranges,
):
    """One time step of the navigation domain, in place (see ``copi.world.Simulator``).

    Obstacles random-walk: heading += turn[k]; if that move would touch a wall the
    headings ``2 pi retry[k, j]`` are tried in turn; if all are blocked the obstacle stays.
    The agent moves by ``action`` (already clipped), stopped by walls. Contact is the
    closest approach of agent and obstacle over the step, both moving linearly, against
    the sum of radii. Then the sensor scans from the new position into ``ranges``.

    Returns (blocked, contact, min_gap) where min_gap is the least surface distance to an
    obstacle over the step (negative on contact).
    """
    n_obs = radii.shape[0]
    old = centers.copy()
    for k in range(n_obs if speed > 0.0 else 0):
        h = headings[k] + turn[k]
        moved = False
        for j in range(retry.shape[1] + 1):
            if j > 0:
                h = 2.0 * math.pi * retry[k, j - 1]
            dx = math.cos(h)
            dy = math.sin(h)
            if sweep_one(centers[k, 0], centers[k, 1], dx, dy, segs, radii[k]) >= speed:
                centers[k, 0] += speed * dx
                centers[k, 1] += speed * dy
                moved = True
                break
        headings[k] = h if moved else headings[k]
    return step_agent(agent, action, agent_radius, segs, old, centers, radii, cos, sin,
                      max_range, ranges)  # fmt: skip


@njit(cache=True)
def step_agent(  # type: ignore[no-untyped-def]
    agent, action, agent_radius, segs, old, centers, radii, cos, sin, max_range, ranges
):
    """The agent's half of a time step, in place: it moves by ``action`` (already clipped),
    stopped by walls, while each obstacle moves linearly from ``old`` to ``centers``;
    contact is the closest approach of the two motions against the sum of radii; then the
    sensor scans from the new position into ``ranges``. Returns (blocked, contact, min_gap),
    min_gap the least surface distance to an obstacle over the step (negative on contact).
    """
    n_obs = radii.shape[0]
    ax0 = agent[0]
    ay0 = agent[1]
    x, y, blocked = move_one(ax0, ay0, action[0], action[1], segs, agent_radius)
    agent[0] = x
    agent[1] = y
    min_gap = np.inf
    for k in range(n_obs):
        d = closest_approach(
            ax0,
            ay0,
            x - ax0,
            y - ay0,
            old[k, 0],
            old[k, 1],
            centers[k, 0] - old[k, 0],
            centers[k, 1] - old[k, 1],
        )
        gap = d - agent_radius - radii[k]
        if gap < min_gap:
            min_gap = gap
    _scan_into(x, y, cos, sin, segs, centers, radii, max_range, ranges)
    return blocked, min_gap < 0.0, min_gap


# -- the moves of a disc agent: which walls let through, which escape the discs --------


@njit(cache=True)
def local_segments(x, y, segs, reach):  # type: ignore[no-untyped-def]
    """The segments within ``reach`` of (x, y): the only ones a move shorter than
    ``reach`` minus the disc's radius can touch."""
    n = 0
    keep = np.empty(segs.shape[0], dtype=np.int64)
    r2 = reach * reach
    for k in range(segs.shape[0]):
        if point_segment_d2(x, y, segs, k) <= r2:
            keep[n] = k
            n += 1
    out = np.empty((n, 4))
    for i in range(n):
        out[i] = segs[keep[i]]
    return out


@njit(cache=True, inline="always")
def free_moves(qx, qy, r, segs, moves, free, room):  # type: ignore[no-untyped-def]
    """``free[c]``: whether the walls ``segs`` let an agent of radius ``r`` at (qx, qy)
    make move ``moves[c]`` whole with ``room`` to spare (waiting always)."""
    for c in range(moves.shape[0]):
        ex = moves[c, 0]
        ey = moves[c, 1]
        le = math.sqrt(ex * ex + ey * ey)
        free[c] = le == 0.0 or sweep_one(qx, qy, ex / le, ey / le, segs, r) >= le + room


@njit(cache=True, inline="always")
def escapes(qx, qy, r, moves, free, c1, c2, radii, near, n_near, clear):  # type: ignore[no-untyped-def]
    """Whether some move ``moves[c]`` with ``free[c]`` (:func:`free_moves`) passes every
    disc ``near[:n_near]``, moving linearly from ``c1`` to ``c2`` (radii ``radii``), with
    ``clear`` to spare: the escape the model-oracle asks (``copi.bounds``) of a first move's end."""
    for c in range(moves.shape[0]):
        if not free[c]:
            continue
        ok = True
        for a in range(n_near):
            k = near[a]
            cx = c1[k, 0]
            cy = c1[k, 1]
            gap = closest_approach(qx, qy, moves[c, 0], moves[c, 1], cx, cy, c2[k, 0] - cx,
                                    c2[k, 1] - cy)  # fmt: skip
            if gap - r - radii[k] < clear:
                ok = False
                break
        if ok:
            return True
    return False
