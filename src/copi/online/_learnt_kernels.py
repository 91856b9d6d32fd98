"""Compiled decision of copi's learnt preset (:class:`copi.online.LearntAgent`): every
compass move scored by the route and by the learnt safety model, the hand-written guard
as a filter; one agent or a batch. Built on the chain's kernels (:mod:`copi.online.kernels`)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from copi.core import EXPLAINED
from copi.learning.kernels import ring_features, safety_of, safety_probabilities
from copi.online.kernels import (
    _MARGIN,
    _WALL,
    _escape,
    _hits,
    _nearest_context,
    _room,
    _screened_nearest_context,
    _step_length,
)


def compass_table(n_dir: int) -> np.ndarray:
    """(cos, sin) of 2 pi d / n_dir for d < n_dir, by the formula (and the libm) the
    kernels used to evaluate per decision: a table built once instead of 2 n_dir
    trigonometric calls a decision."""
    a = [2.0 * math.pi * d / n_dir for d in range(n_dir)]
    return np.array([[math.cos(x), math.sin(x)] for x in a])


@njit(cache=True)
def decide_learnt(  # type: ignore[no-untyped-def]
    s, prev, static, nodes_t, node_prior, net, wx, wy, reach, guard, alpha, beta, wait,
    cos, sin, max_range, compass, feat, p, out, node_landmark, prev_landmark, keep, persist,
    lazy, static_aware,
):
    """One decision of the ``learnt`` preset: every compass direction (and, with
    ``wait``, standing still) scored by the global direction and the learnt safety
    together, the guard (as :func:`_choose`'s) kept as a filter.

    score(d) = cos(d, aim) + alpha log P(safe | reading turned to d) + beta log
    P(safe | template, d through g), the networks ``net`` as
    :func:`copi.learning._safety.kernel_net` lays them out and ``nodes_t`` the nodes
    transposed (dim, n). Waiting scores alpha log P(safe | wait). When the
    guard leaves no direction, the agent waits if the model says waiting is safer than
    every move that does not run into a hit, else escapes where most room is.
    out = (ax, ay, node, d2, choice): choice d, -2 the escape, -4 waiting, -1 nothing.

    Since the log terms are <= 0, cos(d, aim) bounds a direction's score: with ``lazy``
    (and no waiting, which compares against every direction) directions are taken best
    bound first, the guard and the network only for as long as a bound left can beat
    the best score (all of them when the guard admits none: the fallback needs them),
    with the same choice, ties to the lower index, as taking all. p (n_dir + 1,)
    receives the safety probabilities evaluated (NaN for the rest).

    Persistence (an option in the paper's sense, §V): while the reading stays within
    the landmark of the previous decision (``node_landmark[node] == prev_landmark``),
    direction ``keep`` (the previous choice) scores ``persist`` more.

    ``static_aware``: the networks were learnt with the static reading (their closeness
    block sees only hits the static map does not explain); otherwise they are handed
    none, as they learnt (the guard uses ``static`` either way)."""
    for d in range(p.shape[0]):
        p[d] = np.nan
    if not _learnt_inputs(s, prev, static, out):
        return
    node, d2 = _nearest_context(s, prev, nodes_t)
    k = keep if node < node_landmark.shape[0] and node_landmark[node] == prev_landmark else -1
    _learnt_choose(
        s, prev, static, node, d2, node_prior, net, wx, wy, reach, guard, alpha, beta, wait,
        cos, sin, max_range, compass, feat, p, out, lazy, k, persist,
        _work(s.shape[0], node_prior.shape[1]), static_aware,
    )  # fmt: skip


@njit(cache=True, inline="always")
def _learnt_inputs(s, prev, static, out):  # type: ignore[no-untyped-def]
    """Whether the reading, the previous one and the static reading are usable; if not,
    out[2] = -1 (ranges) or -2 (static)."""
    for i in range(s.shape[0]):
        if not (math.isfinite(s[i]) and s[i] >= 0.0 and math.isfinite(prev[i])):
            out[2] = -1.0
            return False
        if not static[i] >= 0.0:
            out[2] = -2.0
            return False
    return True


@njit(cache=True)
def decide_learnt_batch(  # type: ignore[no-untyped-def]
    s, prev, static, nodes_t, gram, sq, node_prior, net, want, reach, guard, alpha, beta,
    wait, cos, sin, max_range, compass, feat, p, out, static_aware, recognise,
):
    """:func:`decide_learnt` for each row (lazy), out of shape (b, 5), with the
    nearest-node search screened as :func:`decide_batch` screens it; without
    ``recognise`` (only when ``beta`` is 0, so that the choice does not use the context)
    no search: node -3 (-1 and -2 are the input errors), distance NaN."""
    work = _work(s.shape[1], node_prior.shape[1])
    for b in range(s.shape[0]):
        x = s[b]
        if not _learnt_inputs(x, prev[b], static[b], out[b]):
            continue
        node, bd = -3, np.nan
        if recognise:
            node, bd = _screened_nearest_context(x, prev[b], gram[b], sq[b], nodes_t)
        _learnt_choose(
            x, prev[b], static[b], node, bd, node_prior, net, want[b, 0], want[b, 1],
            reach[b], guard, alpha, beta, wait, cos, sin, max_range, compass, feat, p, out[b],
            True, -1, 0.0, work, static_aware,
        )  # fmt: skip


@njit(cache=True)
def decide_learnt_rows(  # type: ignore[no-untyped-def]
    ranges, positions, goals, active, lo, hi, prev, prev_goal, first, node_prior, net, guard,
    alpha, beta, wait, cos, sin, max_range, compass, feat, p, actions, static_aware,
):
    """:func:`decide_learnt_batch` without recognition (``beta`` 0) for the agents
    ``lo .. hi - 1`` still ``active`` of arrays many agents share (a crowd's), in place:
    agent i reads ``ranges[i]``, aims at ``goals[i]`` from ``positions[i]`` (the straight
    line, as far as the goal), its previous reading is ``prev[i - first]``, taken for
    the goal ``prev_goal[i - first]`` (another goal is a new task: no previous reading);
    its velocity goes to ``actions[i]``, its reading and goal to ``prev`` and
    ``prev_goal``. One compiled call a batch instead of a dozen array operations.
    Returns the first agent whose reading is unusable (not finite, negative), else -1."""
    n = ranges.shape[1]
    work = _work(n, node_prior.shape[1])
    static = work[4, :n]  # no static reading (inf)
    out = np.empty(5)
    for i in range(lo, hi):
        if not active[i]:
            continue
        k = i - first
        x = ranges[i]
        pv = prev[k]
        if prev_goal[k, 0] != goals[i, 0] or prev_goal[k, 1] != goals[i, 1]:
            for j in range(n):
                pv[j] = x[j]
        if not _learnt_inputs(x, pv, static, out):
            return i
        wx = goals[i, 0] - positions[i, 0]
        wy = goals[i, 1] - positions[i, 1]
        _learnt_choose(
            x, pv, static, -3, np.nan, node_prior, net, wx, wy, np.hypot(wx, wy), guard,
            alpha, beta, wait, cos, sin, max_range, compass, feat, p, out, True, -1, 0.0,
            work, static_aware,
        )  # fmt: skip
        actions[i, 0] = out[0]
        actions[i, 1] = out[1]
        for j in range(n):
            pv[j] = x[j]
        prev_goal[k, 0] = goals[i, 0]
        prev_goal[k, 1] = goals[i, 1]
    return -1


@njit(cache=True, inline="always")
def _work(n, n_dir):  # type: ignore[no-untyped-def]
    """Scratch of :func:`_learnt_choose` for ``n`` rays and ``n_dir`` directions (one
    allocation, made once a batch); its last row, no static reading (inf)."""
    work = np.empty((5, max(n, n_dir)))
    work[4] = np.inf
    return work


@njit(cache=True)
def _learnt_choose(  # type: ignore[no-untyped-def]
    s, prev, static, node, d2, node_prior, net, wx, wy, reach, guard, alpha, beta, wait,
    cos, sin, max_range, compass, feat, p, out, lazy, keep, persist, work, static_aware,
):
    """The choice of :func:`decide_learnt` once the reading is recognised (node, d2),
    direction ``keep`` (-1: none) scoring ``persist`` more; ``compass`` (n_dir, 2) holds
    each direction's (cos, sin) of 2 pi d / n_dir (:func:`compass_table`); ``work`` is
    scratch (:func:`_work`)."""
    seen = static if static_aware else work[4, : s.shape[0]]  # the networks' static
    n_dir = node_prior.shape[1]
    out[0] = 0.0
    out[1] = 0.0
    out[2] = node
    out[3] = d2
    out[4] = -1.0
    norm = math.sqrt(wx * wx + wy * wy)
    if norm == 0.0:
        return
    ux = wx / norm
    uy = wy / norm
    n = s.shape[0]
    per = n // n_dir
    all_p = wait or not lazy
    if all_p:
        safety_probabilities(s, prev, seen, net, n_dir, feat, p)
    rung = all_p  # the ring's features, computed when the network first needs them
    now = np.inf  # the nearest range, and the nearest hit the static map does not explain
    moving = np.inf
    for i in range(s.shape[0]):
        r = s[i]
        if r < now:
            now = r
        if r < moving and r < max_range and r < static[i] - EXPLAINED:
            moving = r
    hit = now if now < max_range else np.inf  # the nearest hit
    wall = min(_WALL, now - 1e-6)
    roomy = min(0.35, now - 1e-6)
    hits = work[:2, :n]
    km, k0 = _hits(s, static, cos, sin, max_range, hits)
    best = -1
    best_score = -np.inf
    free_p = 0.0
    # As _choose with every compass direction a candidate (so that alpha = beta = 0
    # without waiting is compass-guard, step for step): a guard-rejected direction that
    # does not run into a hit is a fallback, the one ending farthest from moving hits.
    fallback = -1
    fallback_clear = -np.inf
    along = work[2]
    bound = work[3]  # -inf once seen (every bound is finite)
    for d in range(n_dir):
        along[d] = compass[d, 0] * ux + compass[d, 1] * uy
        bound[d] = along[d] + persist if d == keep else along[d]
    while True:
        # the direction with the highest bound not yet seen (lower index first)
        d = -1
        top = -np.inf
        for e in range(n_dir):
            if bound[e] > top:
                top = bound[e]
                d = e
        if d < 0:
            break
        if not all_p and best >= 0 and top < best_score:
            break  # no direction left can beat the best (nor is the fallback needed)
        bound[d] = -np.inf
        ax = compass[d, 0]
        ay = compass[d, 1]
        step = _step_length(along[d] * reach, reach)
        if hit - step >= wall + _MARGIN and (guard <= 0.0 or moving - step >= guard + _MARGIN):
            # every hit is farther than the step: _room's distances, each at least a hit's
            # range less the step, could refuse nothing (and a fallback is needed only
            # when nothing is admitted), so they are not measured
            end = sweep = sweep_all = np.inf
        else:
            end, sweep, sweep_all = _room(hits, km, k0, ax, ay, step, wall)
        if guard <= 0.0:
            end = np.inf
            sweep = np.inf
        if all_p and sweep_all >= wall and p[d] > free_p:
            free_p = p[d]
        if end < guard or sweep < 0.5 * guard or sweep_all < wall:
            if sweep_all >= wall and (
                end > fallback_clear or (end == fallback_clear and d < fallback)
            ):
                fallback_clear = end
                fallback = d
            continue
        if top < best_score:
            continue
        if not all_p:
            if not rung:
                ring_features(s, prev, seen, feat)
                rung = True
            p[d] = safety_of(net, 0, d * per, feat, n)
        score = top + alpha * math.log(max(p[d], 1e-9))
        if beta > 0.0:
            score += beta * math.log(max(node_prior[node, d], 1e-9))
        if score > best_score or (score == best_score and d < best):
            best_score = score
            best = d
    if wait:
        wait_score = alpha * math.log(max(p[n_dir], 1e-9))
        if (best >= 0 and wait_score > best_score) or (best < 0 and p[n_dir] > free_p):
            out[4] = -4.0
            return
    if best < 0 and guard > 0.0 and fallback_clear < guard:
        if _escape(hits, km, k0, n_dir, fallback_clear, roomy, out):
            return
    if best < 0:
        best = fallback
    if best < 0:
        return
    ax = compass[best, 0]
    ay = compass[best, 1]
    step = _step_length((ax * ux + ay * uy) * reach, reach)
    out[0] = ax * step
    out[1] = ay * step
    out[4] = best
