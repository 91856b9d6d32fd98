"""The learnt safety model's features and evaluation, compiled (paper §II-D; the model is
learnt in :mod:`copi.learning`, from counterfactual probes).

Online, copi's learnt agent (:mod:`copi.online`) evaluates the model at every decision:
a budget of a few µs leaves no room for numpy's per-call overhead on 17 small products,
so the features and the networks are evaluated by these loops, in the order written (no
fastmath), the same on every processor. They trust their arguments.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

from copi.core import EXPLAINED
from copi.learning._policies import compass

__all__ = [
    "CAP",
    "DELTA",
    "N_BLOCKS",
    "feature_block",
    "features_into",
    "kernel_net",
    "ring_features",
    "safety_features",
    "safety_of",
    "safety_probabilities",
    "template_directions",
]


CAP = 4.0
"""Ranges beyond this (agent steps) count as far: safety is decided nearby."""


DELTA = 1.5
"""Changes of a range between steps are clipped to +-this."""


N_BLOCKS = 4
"""Feature blocks per ray: near range, its change, closeness of what moves, approach when
close."""


@njit(cache=True, inline="always")
def _change(r, p):  # type: ignore[no-untyped-def]
    """A range's change since the last step, clipped to +-DELTA."""
    d = r - p
    if d > DELTA:
        return DELTA
    if d < -DELTA:
        return -DELTA
    return d


@njit(cache=True, inline="always")
def _feature(s, prev, static, i, block):  # type: ignore[no-untyped-def]
    r = s[i]
    d = _change(r, prev[i])
    if block == 0:
        return min(r, CAP) / CAP
    if block == 1:
        return d / DELTA
    if block == 2:
        return math.exp(-r) if r < static[i] - EXPLAINED else 0.0
    return min(d, 0.0) / DELTA * math.exp(-0.5 * r)


def feature_block(n_rays: int) -> int:
    """Length of one feature vector (the bias not included)."""
    return N_BLOCKS * n_rays


@njit(cache=True)
def features_into(s, prev, static, shift, mirror, out):  # type: ignore[no-untyped-def]
    n = s.shape[0]
    for b in range(N_BLOCKS):
        for j in range(n):
            i = (shift - j) % n if mirror else (shift + j) % n
            out[b * n + j] = _feature(s, prev, static, i, b)


def safety_features(
    s: NDArray[np.float64],
    prev: NDArray[np.float64],
    shift: int,
    mirror: bool = False,
    static: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """The feature vector of reading ``s`` (previous reading ``prev``; ``static``, the
    reading the static map alone would give, none by default) turned so that ray
    ``shift`` is ray 0 (and mirrored about it with ``mirror``)."""
    s = np.asarray(s, np.float64)
    st = np.full(s.shape, np.inf) if static is None else np.asarray(static, np.float64)
    out = np.empty(feature_block(s.shape[0]))
    features_into(s, np.asarray(prev, np.float64), st, int(shift), bool(mirror), out)
    return out


@njit(cache=True)
def ring_features(s, prev, static, feat):  # type: ignore[no-untyped-def]
    """The feature blocks of reading ``s`` after ``prev`` (``static``: the static map's
    reading, inf where unknown) into ``feat`` (8 n_rays), each block written twice, so
    that turning the reading is a slice (see :func:`safety_of`). The values are
    :func:`_feature`'s, computed a ray at a time (the change once, not once a block; the
    closeness block's exponential once for a run of equal ranges; the approach block's
    only for a ray that came nearer: otherwise the block is exactly 0)."""
    n = s.shape[0]
    last = np.nan  # the last range whose exponential was taken (rays at the sensor's
    e = 0.0  # reach often repeat one value)
    for i in range(n):
        r = s[i]
        d = _change(r, prev[i])
        v0 = min(r, CAP) / CAP
        v1 = d / DELTA
        if r != last:
            e = math.exp(-r)
            last = r
        v2 = e if r < static[i] - EXPLAINED else 0.0
        v3 = min(d, 0.0) / DELTA  # +-0 unless the ray came nearer (the sign kept)
        if d < 0.0:
            v3 = v3 * math.exp(-0.5 * r)
        feat[i] = v0
        feat[n + i] = v0
        feat[2 * n + i] = v1
        feat[3 * n + i] = v1
        feat[4 * n + i] = v2
        feat[5 * n + i] = v2
        feat[6 * n + i] = v3
        feat[7 * n + i] = v3


def kernel_net(net: NDArray[np.float64]) -> NDArray[np.float64]:
    """The networks ``net`` (2, h + 1, 1 + 4 n_rays), as :class:`SafetyModel` holds them,
    laid out for the kernels: (2, 4 n_rays + 3, h), row 0 the hidden biases, row 1 + i
    every hidden unit's weight of feature i, row 4 n_rays + 1 the output weights, and
    [4 n_rays + 2, 0] the output bias. Feature-major, so that one feature updates every
    hidden unit at once: the loop over units vectorises while each unit's sum keeps its
    order (bias, then the features in turn) on every processor."""
    net = np.asarray(net, dtype=np.float64)
    k, h1, f1 = net.shape
    h = h1 - 1
    out = np.zeros((k, f1 + 2, h))
    out[:, :f1, :] = net[:, :h, :].transpose(0, 2, 1)
    out[:, f1, :] = net[:, h, 1 : 1 + h]
    out[:, f1 + 1, 0] = net[:, h, 0]
    return np.ascontiguousarray(out)


@njit(cache=True)
def safety_of(net_t, k, shift, feat, n):  # type: ignore[no-untyped-def]
    """P(safe) by network ``k`` of ``net_t`` (:func:`kernel_net`; 0: a move along ray 0,
    1: waiting) of the features in ``feat`` (:func:`ring_features`) turned by ``shift``
    rays. No fastmath: every sum runs in the order written, the same on every processor.

    The features are taken eight at a time, each hidden unit's sum still adding them in
    turn (((z + w1 f1) + w2 f2) + ...): the same sums, bit for bit, with an eighth of the
    trips through the units' partial sums in memory (which the compiled loop cannot keep
    in registers; measured, 0.52 -> 0.34 us an evaluation of 16 units and 32 rays). A
    product of a feature that is exactly 0 is +-0, which leaves a sum as it is (a -0 sum
    may become +0, which neither the ReLU nor any later sum tells apart)."""
    h = net_t.shape[2]
    last = net_t.shape[1] - 2
    w = net_t[k]
    z = w[0].copy()
    for b in range(N_BLOCKS):
        w0 = 1 + b * n
        f0 = 2 * b * n + shift
        j = 0
        while j + 8 <= n:
            g = f0 + j
            f1, f2, f3, f4 = feat[g], feat[g + 1], feat[g + 2], feat[g + 3]
            f5, f6, f7, f8 = feat[g + 4], feat[g + 5], feat[g + 6], feat[g + 7]
            q = w0 + j
            r1, r2, r3, r4 = w[q], w[q + 1], w[q + 2], w[q + 3]
            r5, r6, r7, r8 = w[q + 4], w[q + 5], w[q + 6], w[q + 7]
            for u in range(h):
                z[u] = (((((((z[u] + r1[u] * f1) + r2[u] * f2) + r3[u] * f3) + r4[u] * f4)
                          + r5[u] * f5) + r6[u] * f6) + r7[u] * f7) + r8[u] * f8  # fmt: skip
            j += 8
        while j < n:  # the rays left over (a ring of other than a multiple of 8)
            f = feat[f0 + j]
            row = w[w0 + j]
            for u in range(h):
                z[u] += row[u] * f
            j += 1
    z2 = net_t[k, last + 1, 0]
    out_w = net_t[k, last]
    for u in range(h):
        if z[u] > 0.0:
            z2 += out_w[u] * z[u]
    return 1.0 / (1.0 + math.exp(-z2))


@njit(cache=True)
def safety_probabilities(s, prev, static, net_t, n_dir, feat, out):  # type: ignore[no-untyped-def]
    """P(safe) of each of ``n_dir`` compass directions (out[:n_dir]) and of waiting
    (out[n_dir]) for reading ``s`` after ``prev`` (``static``: the static map's reading,
    inf where unknown).

    ``net_t``: :func:`kernel_net` of the direction model and the wait model
    (:attr:`SafetyModel.net`), each a one-hidden-layer ReLU network. Direction d is
    judged on the features turned so that its ray is ray 0; waiting in the frame of
    direction 0. ``feat`` is scratch of length 8 n_rays (each block written twice, so
    that a turn is a slice). This is the model's whole evaluation, compiled: a decision
    budget of a few µs leaves no room for numpy's per-call overhead on 17 small
    products."""
    n = s.shape[0]
    per = n // n_dir
    ring_features(s, prev, static, feat)
    for d in range(n_dir):
        out[d] = safety_of(net_t, 0, d * per, feat, n)
    out[n_dir] = safety_of(net_t, 1, 0, feat, n)


def template_directions(matrices: NDArray[np.float64], n_dir: int) -> NDArray[np.int64]:
    """For symmetries ``matrices`` (m, 2, 2), world frame -> template frame: the compass
    index, in the template's frame, of each world compass direction (m, D)."""
    _, dirs = compass(n_dir)
    turned = np.einsum("mij,dj->mdi", matrices, dirs)
    return np.argmax(turned @ dirs.T, axis=2)
