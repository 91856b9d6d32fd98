"""The chauffeur's motion in compiled code: one sub-step's pieces, and a whole time step.

Written by hand because a time step is ten sub-steps of a few scalar operations each
(Isaacs' control, an exact arc, a swept disc against the walls, a capture test): numpy's
per-call cost dominates such work (350 µs a time step in Python, most of a chauffeur
training run), and no library does it. :mod:`copi.games._chauffeur` and
:mod:`copi.games._play` call these same functions, so there is one copy of each formula.
"""

from __future__ import annotations

import math

from numba import njit

from copi.geometry.kernels import move_one


@njit(cache=True)
def relative(px, py, heading, ex, ey):  # type: ignore[no-untyped-def]
    """The evader at (ex, ey) in the frame of the car at (px, py, heading): (x to the
    right, y forward)."""
    dx, dy = ex - px, ey - py
    c, s = math.cos(heading), math.sin(heading)
    return dx * s - dy * c, dx * c + dy * s


@njit(cache=True)
def isaacs_u(px, py, heading, ex, ey, turn_radius, dt_turn):  # type: ignore[no-untyped-def]
    """Isaacs' control u for the car at (px, py, heading) and the evader at (ex, ey);
    see :func:`copi.games.isaacs_control`."""
    x, y = relative(px, py, heading, ex, ey)
    if (x - turn_radius) ** 2 + y * y < turn_radius**2:
        return 1.0  # inside the right turning circle: swerve left, away
    if (x + turn_radius) ** 2 + y * y < turn_radius**2:
        return -1.0
    u = -math.atan2(x, y) / dt_turn
    return min(max(u, -1.0), 1.0)


@njit(cache=True)
def arc(heading, u, speed, turn_radius, dt):  # type: ignore[no-untyped-def]
    """The car's displacement over ``dt`` with control ``u`` (an exact circular arc) and
    its heading after: (dx, dy, heading). See :meth:`copi.games.Pursuer.arc`."""
    u = min(max(u, -1.0), 1.0)
    dist = speed * dt
    # the chord 2 rho sin(dh / 2) as dist sin(x) / x, x = dh / 2: no loss when nearly straight
    dh = u * dist / turn_radius
    half = 0.5 * dh
    chord = dist * (math.sin(half) / half if half != 0.0 else 1.0)
    mid = heading + half
    return chord * math.cos(mid), chord * math.sin(mid), heading + dh


@njit(cache=True)
def first_contact(px, py, dpx, dpy, ex, ey, dex, dey, ell):  # type: ignore[no-untyped-def]
    """(tau, closest) for two points moving linearly over tau in [0, 1]; see
    :func:`copi.games.first_contact`."""
    rx, ry = ex - px, ey - py
    vx, vy = dex - dpx, dey - dpy
    a = vx * vx + vy * vy
    b = rx * vx + ry * vy
    c = rx * rx + ry * ry - ell * ell
    tmin = min(max(-b / a, 0.0), 1.0) if a > 0 else 0.0
    cx, cy = rx + tmin * vx, ry + tmin * vy
    closest = math.sqrt(cx * cx + cy * cy)
    if c <= 0:
        return 0.0, closest
    if a == 0:
        return math.inf, closest
    disc = b * b - a * c
    if disc < 0:
        return math.inf, closest
    tau = (-b - math.sqrt(disc)) / a
    return (tau if 0 <= tau <= 1 else math.inf), closest


@njit(cache=True)
def pursuer_step(  # type: ignore[no-untyped-def]
    px, py, heading, e0x, e0y, dex, dey, segs, radius,
    speed, turn_radius, capture_radius, substeps, control, steer,
):  # fmt: skip
    """One time step of the car (see :func:`copi.games.pursuer_step`): Isaacs' control
    at each sub-step when ``steer``, else ``control`` held. Returns
    (x, y, heading, tau or inf, closest)."""
    h = 1.0 / substeps
    dturn = speed * h / turn_radius
    closest = math.inf
    for i in range(substeps):
        ex, ey = e0x + (i * h) * dex, e0y + (i * h) * dey
        u = isaacs_u(px, py, heading, ex, ey, turn_radius, dturn) if steer else control
        dpx, dpy, heading = arc(heading, u, speed, turn_radius, h)
        if segs.shape[0] > 0:
            nx, ny, _ = move_one(px, py, dpx, dpy, segs, radius)
            dpx, dpy = nx - px, ny - py
        tau, near = first_contact(px, py, dpx, dpy, ex, ey, h * dex, h * dey, capture_radius)
        closest = min(closest, near)
        px, py = px + dpx, py + dpy
        if tau <= 1.0:
            return px, py, heading, (i + tau) * h, closest
    return px, py, heading, math.inf, closest
