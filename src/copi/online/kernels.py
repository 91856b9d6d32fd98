"""Compiled online decision: nearest node, table lookup, candidate choice, optional guard.

Why by hand: a decision is a 600 x 32 nearest-neighbour search and a handful of lookups;
in numpy each of the dozen small steps costs a microsecond of call overhead, so the
whole chain is one compiled function (about 3 µs, most of it the search). The same
function serves one agent and a batch, so both give identical results.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from copi.core import EXPLAINED

# No fastmath anywhere here: every sum runs in the order written, so that a decision is
# the same on every processor (reassociation lets LLVM pick the summation order of the
# target's SIMD width, and contraction fuses multiply-adds only where the target has
# FMA; either made the nearest node, and so every result downstream, depend on the
# machine the kernels were compiled on).


@njit(cache=True, inline="always")
def _exact(x, nodes_t, i):  # type: ignore[no-untyped-def]
    """Squared distance from x to node i of the transposed nodes ``nodes_t`` (dim, n):
    the sum over components in order 0, 1, ..., the one formula every path uses."""
    e = 0.0
    for j in range(x.shape[0]):
        diff = x[j] - nodes_t[j, i]
        e += diff * diff
    return e


@njit(cache=True, inline="always")
def _nearest(x, nodes_t):  # type: ignore[no-untyped-def]
    """Nearest node: argmin of :func:`_exact`, ties to the lower index.

    The nodes are transposed (``nodes_t`` (dim, n)) so that the loop runs across nodes,
    one component at a time: each node's sum keeps :func:`_exact`'s order (bitwise the
    same value) while the loop vectorises without any reassociation."""
    n = nodes_t.shape[1]
    acc = np.zeros(n)
    for j in range(x.shape[0]):
        xj = x[j]
        row = nodes_t[j]
        for i in range(n):
            diff = xj - row[i]
            acc[i] += diff * diff
    best = -1
    bd = np.inf
    for i in range(n):
        if acc[i] < bd:
            bd = acc[i]
            best = i
    return best, bd


MOTION_CLIP = 1.5
"""copi.learning._contexts.MOTION_CLIP, repeated here: numba's cache sees only this
file's changes, so a constant imported from another file could go stale in compiled
kernels (a test checks that the two agree)."""


@njit(cache=True, inline="always")
def _context(s, prev, dim):  # type: ignore[no-untyped-def]
    """The context of reading ``s`` as nodes of ``dim`` components hold it: ``s``, or
    [s, clip(s - prev)] (contexts that see motion, :mod:`copi.learning._contexts`),
    built once so that the distance sums below vectorise."""
    n = s.shape[0]
    q = np.empty(dim)
    for j in range(n):
        q[j] = s[j]
    for j in range(n, dim):
        c = s[j - n] - prev[j - n]
        q[j] = MOTION_CLIP if c > MOTION_CLIP else -MOTION_CLIP if c < -MOTION_CLIP else c
    return q


@njit(cache=True, inline="always")
def _nearest_context(s, prev, nodes_t):  # type: ignore[no-untyped-def]
    """:func:`_nearest` of reading ``s``'s context: the reading itself, or with nodes of
    twice its length, [s, clip(s - prev)]."""
    if nodes_t.shape[0] == s.shape[0]:
        return _nearest(s, nodes_t)
    return _nearest(_context(s, prev, nodes_t.shape[0]), nodes_t)


@njit(cache=True)
def decide(  # type: ignore[no-untyped-def]
    s, static, nodes_t, cand, ok, wx, wy, reach, guard, cos, sin, max_range, out
):
    """One decision for reading ``s``: :func:`_nearest` among the nodes ``nodes_t``
    (transposed: dim x n), then :func:`_choose`.

    Checks its inputs first, in the same pass (cheaper than numpy's checks for one
    reading): out[2] = -1 for a reading that is not finite and >= 0, -2 for a static
    reading that is not >= 0 (NaN or negative; inf: nothing there)."""
    for i in range(s.shape[0]):
        if not (math.isfinite(s[i]) and s[i] >= 0.0):
            out[2] = -1.0
            return
        if not static[i] >= 0.0:
            out[2] = -2.0
            return
    node, d2 = _nearest(s, nodes_t)
    _choose(s, static, node, d2, cand, ok, wx, wy, reach, guard, cos, sin, max_range, out)


@njit(cache=True, inline="always")
def _hits(s, static, cos, sin, max_range, hits):  # type: ignore[no-untyped-def]
    """The hit points of reading ``s`` in the agent's frame, into ``hits`` (2, n): those
    the static map does not explain (moving obstacles) in columns [0, km), the walls in
    [k0, n). Returns (km, k0). Computed once a decision, so that :func:`_room` measures
    each candidate step against a list, not the reading."""
    n = s.shape[0]
    km = 0
    k0 = n
    for i in range(n):
        if s[i] >= max_range:
            continue
        px = s[i] * cos[i]
        py = s[i] * sin[i]
        if s[i] >= static[i] - EXPLAINED:  # explained by the static map: a wall
            k0 -= 1
            hits[0, k0] = px
            hits[1, k0] = py
        else:
            hits[0, km] = px
            hits[1, km] = py
            km += 1
    return km, k0


@njit(cache=True, inline="always")
def _path_d2(px, py, ax, ay, step):  # type: ignore[no-untyped-def]
    """Squared distance from the point (px, py) to the path of a step of length ``step``
    along the unit vector (ax, ay) from the origin."""
    t = px * ax + py * ay
    if t < 0.0:
        t = 0.0
    elif t > step:
        t = step
    return (px - t * ax) ** 2 + (py - t * ay) ** 2


@njit(cache=True, inline="always")
def _room(hits, km, k0, ax, ay, step, stop):  # type: ignore[no-untyped-def]
    """For a step of length ``step`` along (ax, ay): the least distance from the moved
    agent to a hit the static map does not explain (a moving obstacle), the least
    distance from its path to such a hit, and from its path to any hit (``hits``,
    ``km``, ``k0``: :func:`_hits`).

    The minima are taken over squared distances and rooted once: the square root is
    correctly rounded and monotone, so this is exactly the least of the rooted distances
    (two square roots a hit and candidate fewer). Once the path comes nearer than
    ``stop`` to a hit, every caller refuses the step whatever the other distances are:
    the measuring stops there, and the three distances returned are that path distance
    (below ``stop``, not necessarily the least)."""
    end = np.inf
    sweep = np.inf
    stop2 = stop * stop
    ex = step * ax
    ey = step * ay
    for i in range(km):
        px = hits[0, i]
        py = hits[1, i]
        dd = _path_d2(px, py, ax, ay, step)
        if dd < stop2:
            r = math.sqrt(dd)
            return r, r, r
        if dd < sweep:
            sweep = dd
        de = (px - ex) ** 2 + (py - ey) ** 2
        if de < end:
            end = de
    sweep_all = sweep
    for i in range(k0, hits.shape[1]):
        px = hits[0, i]
        py = hits[1, i]
        dd = _path_d2(px, py, ax, ay, step)
        if dd < stop2:
            r = math.sqrt(dd)
            return r, r, r
        if dd < sweep_all:
            sweep_all = dd
    return math.sqrt(end), math.sqrt(sweep), math.sqrt(sweep_all)


_MARGIN = 1e-9
"""Slack above rounding with which a bound on :func:`_room`'s distances is trusted."""
_WALL = 0.31
"""Least distance a guarded step's path keeps from any hit: the agent's radius (0.3) and
a hair."""


@njit(cache=True, inline="always")
def _step_length(along, reach):  # type: ignore[no-untyped-def]
    """Length of a unit-direction step whose projection on the aim is ``along``, the aim
    lying ``reach`` ahead: a full step unless the aim is nearer than one step; then as
    far as coming level with it, and at least half the way (a sideways step must not
    shrink to nothing: with the step cut to the projection, a direction perpendicular to
    the aim moved the agent by ~1e-16 and a guarded agent stalled for good)."""
    if not math.isfinite(reach) or reach >= 1.0:
        return 1.0
    return max(along, 0.5 * reach)


@njit(cache=True, inline="always")
def _escape(hits, km, k0, n, clear, roomy, out):  # type: ignore[no-untyped-def]
    """The escape: a full step along whichever of ``n`` compass directions ends farthest
    (beyond ``clear``) from moving hits without its path coming within ``roomy`` of any
    hit (``hits``, ``km``, ``k0``: :func:`_hits`); writes it to ``out`` (choice -2) and
    returns True, or False if none does."""
    esc = -1
    for d in range(n):
        a0 = 2.0 * math.pi * d / n
        end, _, sweep_all = _room(hits, km, k0, math.cos(a0), math.sin(a0), 1.0, roomy)
        if sweep_all >= roomy and end > clear:
            clear = end
            esc = d
    if esc < 0:
        return False
    a0 = 2.0 * math.pi * esc / n
    out[0] = math.cos(a0)
    out[1] = math.sin(a0)
    out[4] = -2.0
    return True


@njit(cache=True, inline="always")
def _refused(hits, km, k0, ax, ay, score, reach, guard, wall):  # type: ignore[no-untyped-def]
    """Whether the guard refuses the step along (ax, ay) (alignment ``score`` with the
    desired direction): after it a moving hit nearer than ``guard``, or its path passing
    one nearer than half of that, or running within ``wall`` of any hit (a wall
    included; ``wall`` is below how near the nearest hit is now). A step so pressed would
    be stopped there: without this, a quantised direction pressed into a wall corner for
    good where the route hugs it. Returns (refused, end, sweep_all)."""
    step = _step_length(score * reach, reach)
    end, sweep, sweep_all = _room(hits, km, k0, ax, ay, step, wall)
    if guard <= 0.0:
        end = np.inf
        sweep = np.inf
    return (end < guard or sweep < 0.5 * guard or sweep_all < wall), end, sweep_all


@njit(cache=True)
def guard_verdicts(s, static, dirs, wx, wy, reach, guard, cos, sin, max_range, out):  # type: ignore[no-untyped-def]
    """out[k] = whether the guard admits the step along ``dirs[k]`` (unit vectors) for
    reading ``s`` and desired direction (wx, wy): the test :func:`_choose` applies (for
    explanations: ``copi watch``)."""
    norm = math.sqrt(wx * wx + wy * wy)
    now = np.inf
    for i in range(s.shape[0]):
        if s[i] < now:
            now = s[i]
    wall = min(_WALL, now - 1e-6)
    hits = np.empty((2, s.shape[0]))
    km, k0 = _hits(s, static, cos, sin, max_range, hits)
    for k in range(dirs.shape[0]):
        score = (dirs[k, 0] * wx + dirs[k, 1] * wy) / norm if norm > 0.0 else 0.0
        refused, _, _ = _refused(hits, km, k0, dirs[k, 0], dirs[k, 1], score, reach, guard,
                                 wall)  # fmt: skip
        out[k] = not refused


@njit(cache=True, inline="always")
def _choose(  # type: ignore[no-untyped-def]
    s, static, node, d2, cand, ok, wx, wy, reach, guard, cos, sin, max_range, out
):
    """One decision for reading ``s`` and desired direction (wx, wy).

    Writes out = (ax, ay, node, d2, choice); choice -1: no candidate; -2: the escape;
    -3 - d: compass direction d, taken because the template offers no policy; node -1:
    the reading is not finite (nothing else is computed).

    With ``guard`` > 0, a candidate is kept only if, after its step, every moving
    obstacle's hit point is at least ``guard`` away and its path passes none closer than
    half of that (the template's passability checked against the live reading). If none
    is left, the agent escapes along the compass direction that leaves the most room
    (choice -2), not grazing any hit; failing that, the candidate leaving the most room
    is taken. Hits that ``static`` explains (what the static map alone would show, when
    known) are walls: they stop the agent, they do not collide with it.
    """
    out[2] = node
    out[3] = d2
    norm = math.sqrt(wx * wx + wy * wy)
    out[0] = 0.0
    out[1] = 0.0
    out[4] = -1.0
    if norm == 0.0:
        return
    ux = wx / norm
    uy = wy / norm
    n_dir = cand.shape[1]
    # A context whose template offers no policy falls back to the compass: every
    # direction is a candidate, each kept only if its step does not run into a hit (and,
    # with a guard, passes it). Reported as choice -3 - d.
    compass = True
    for d in range(n_dir):
        if ok[node, d]:
            compass = False
            break
    # How near the nearest hit is now: a step is judged by whether it brings the agent
    # nearer than that (below the threshold), not by where it stands (an agent resting
    # against a wall could otherwise never move again). Only needed when steps are
    # checked against the hits (a guard, or the compass fallback).
    wall = _WALL
    roomy = 0.35
    hits = np.empty((2, s.shape[0]))
    km = 0
    k0 = s.shape[0]
    if guard > 0.0 or compass:
        now = np.inf
        for i in range(s.shape[0]):
            if s[i] < now:
                now = s[i]
        wall = min(_WALL, now - 1e-6)
        roomy = min(0.35, now - 1e-6)
        km, k0 = _hits(s, static, cos, sin, max_range, hits)
    best = -1
    best_score = -np.inf
    fallback = -1
    fallback_clear = -np.inf
    for d in range(n_dir):
        if compass:
            a0 = 2.0 * math.pi * d / n_dir
            ax = math.cos(a0)
            ay = math.sin(a0)
        elif ok[node, d]:
            ax = cand[node, d, 0]
            ay = cand[node, d, 1]
        else:
            continue
        score = ax * ux + ay * uy
        if guard > 0.0 or compass:
            refused, end, sweep_all = _refused(hits, km, k0, ax, ay, score, reach, guard,
                                               wall)  # fmt: skip
            if refused:
                # a fallback may come near a moving obstacle, never run into a hit
                if sweep_all >= wall and end > fallback_clear:
                    fallback_clear = end
                    fallback = d
                continue
        if score > best_score:
            best_score = score
            best = d
    if best < 0 and guard > 0.0 and fallback_clear < guard:
        # Nothing the template offers is safe: escape along whichever compass direction
        # leaves the most room (the live reading overrides the template here).
        if _escape(hits, km, k0, cand.shape[1], fallback_clear, roomy, out):
            return
    if best < 0:
        best = fallback
    if best < 0:
        return
    if compass:
        a0 = 2.0 * math.pi * best / n_dir
        ax = math.cos(a0)
        ay = math.sin(a0)
    else:
        ax = cand[node, best, 0]
        ay = cand[node, best, 1]
    step = _step_length((ax * ux + ay * uy) * reach, reach)
    out[0] = ax * step
    out[1] = ay * step
    out[4] = -3.0 - best if compass else best


@njit(cache=True, inline="always")
def _screened_nearest(x, gram, sq, nodes_t):  # type: ignore[no-untyped-def]
    """:func:`_nearest` with the search screened by one row of float32 products
    (:func:`copi.online._controller.screen_products`): ``gram[i]`` is x . node_i -
    |node_i|^2 / 2 and ``sq`` is |x|^2, so ``sq - 2 gram[i]`` approximates the squared
    distance to node i. Every node within a wide margin above the least of them (1e-3
    of it, 1e-4 of |x|^2 and 1e-2: float32's error grows with the magnitudes multiplied,
    and a worst-case bound of it for a product of 33 terms is about 2.4e-5 |x|^2, so
    that every processor's BLAS puts the nearest node below it) is measured with
    :func:`_exact`: the choice is the one
    :func:`_nearest` makes. With the norms folded into the product, the screen costs a
    maximum and a comparison a node (no (b, n) temporaries in numpy, whose cost
    exceeded the product's)."""
    top = -np.inf
    for i in range(gram.shape[0]):
        if gram[i] > top:
            top = gram[i]
    m = sq - 2.0 * top
    cut = m + 1e-3 * abs(m) + 1e-4 * sq + 1e-2
    low = 0.5 * (sq - cut)  # sq - 2 gram[i] <= cut
    node = -1
    bd = np.inf
    for i in range(gram.shape[0]):
        if gram[i] >= low:
            e = _exact(x, nodes_t, i)
            if e < bd:
                bd = e
                node = i
    return node, bd


@njit(cache=True, inline="always")
def _screened_nearest_context(s, prev, gram, sq, nodes_t):  # type: ignore[no-untyped-def]
    """:func:`_screened_nearest` of reading ``s``'s context (see
    :func:`_nearest_context`); ``gram`` and ``sq`` screen the contexts' distances."""
    if nodes_t.shape[0] == s.shape[0]:
        return _screened_nearest(s, gram, sq, nodes_t)
    return _screened_nearest(_context(s, prev, nodes_t.shape[0]), gram, sq, nodes_t)


@njit(cache=True)
def decide_batch(  # type: ignore[no-untyped-def]
    s, static, nodes_t, gram, sq, cand, ok, want, reach, guard, cos, sin, max_range, out
):
    """:func:`decide` for each row, out of shape (b, 5), with the nearest-node search
    screened by ``gram`` (b, n) and ``sq`` (b,) (see :func:`_screened_nearest`): the
    choice is the one :func:`_nearest` makes."""
    for b in range(s.shape[0]):
        x = s[b]
        finite = True
        for i in range(x.shape[0]):
            if not math.isfinite(x[i]):
                finite = False
        if not finite:
            out[b, 2] = -1.0
            continue
        node, bd = _screened_nearest(x, gram[b], sq[b], nodes_t)
        _choose(
            x, static[b], node, bd, cand, ok, want[b, 0], want[b, 1], reach[b], guard,
            cos, sin, max_range, out[b],
        )  # fmt: skip
