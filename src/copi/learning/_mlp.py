"""A one-hidden-layer ReLU network with a logistic output, trained by minibatch Adam with
early stopping: the safety model's learner (:mod:`copi.learning._safety`).

Why by hand: scikit-learn's ``MLPClassifier`` runs the same algorithm (and was copi's
learner), but its matrix products are BLAS's, whose summation order is that of the kernel
BLAS picks for the processor; over tens of epochs those last bits grow into different
weights, so the same seed learnt a different network, and a different agent, on
different machines. Here every sum runs in a fixed order (compiled without fastmath,
each loop running across hidden units so that it vectorises without reordering any
sum), and the random numbers are numpy's seeded generator: the same seed, the same
network on every processor.

The algorithm is scikit-learn's default for ``MLPClassifier((h,), alpha, max_iter,
early_stopping=True)``: Glorot-uniform initialisation (bound sqrt(6 / (fan_in +
fan_out)), biases too), log loss with an L2 penalty alpha / 2 |W|^2 per batch of 200,
Adam (step 1e-3, betas 0.9 and 0.999, epsilon 1e-8), the samples shuffled every epoch,
a tenth held out for early stopping (stop when the held-out score has not improved by
1e-4 for 10 epochs; keep the best epoch's weights). One difference: the held-out score
is the log loss, not the accuracy (smoother, so the best epoch is better defined).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

__all__ = ["fit_mlp"]

BATCH = 200
LEARNING_RATE = 1e-3
BETA1 = 0.9
BETA2 = 0.999
EPSILON = 1e-8
PATIENCE = 10
TOL = 1e-4
VALIDATION = 0.1


@njit(cache=True, inline="always")
def _forward(x, w1, b1, w2, b2, z):  # type: ignore[no-untyped-def]
    """Hidden pre-activations into z (h,), returns the output's logit. w1 (f, h) is
    input-major: one input updates every unit, each unit's sum in input order."""
    h = b1.shape[0]
    for u in range(h):
        z[u] = b1[u]
    for i in range(x.shape[0]):
        xi = x[i]
        row = w1[i]
        for u in range(h):
            z[u] += xi * row[u]
    o = b2
    for u in range(h):
        if z[u] > 0.0:
            o += w2[u] * z[u]
    return o


@njit(cache=True, inline="always")
def _layers(params, f):  # type: ignore[no-untyped-def]
    """Views of the flat vector ``params`` = [w1 (f x h), b1 (h), w2 (h), b2] for f
    inputs: (w1, b1, w2); b2 is params[-1]."""
    h = (params.shape[0] - 1) // (f + 2)
    nw1 = f * h
    return params[:nw1].reshape((f, h)), params[nw1 : nw1 + h], params[nw1 + h : nw1 + 2 * h]


@njit(cache=True)
def _epoch(x, y, order, params, grads, m1, m2, step, alpha):  # type: ignore[no-untyped-def]
    """One pass of minibatch Adam over the rows ``order`` of (x, y); returns the step
    count. ``params`` is the flat vector [w1 (f x h), b1 (h), w2 (h), b2], ``grads``,
    ``m1`` and ``m2`` (Adam's moments) alike."""
    f = x.shape[1]
    w1, b1, w2 = _layers(params, f)
    g1, gb1, gw2 = _layers(grads, f)
    h = b1.shape[0]
    nw1 = f * h
    z = np.empty(h)
    da = np.empty(h)
    n = order.shape[0]
    for start in range(0, n, BATCH):
        stop = min(start + BATCH, n)
        bs = stop - start
        for k in range(grads.shape[0]):
            grads[k] = 0.0
        for t in range(start, stop):
            r = order[t]
            xr = x[r]
            o = _forward(xr, w1, b1, w2, params[-1], z)
            d = 1.0 / (1.0 + math.exp(-o)) - y[r]  # d(log loss)/d(logit)
            grads[-1] += d
            for u in range(h):
                if z[u] > 0.0:
                    gw2[u] += d * z[u]
                    da[u] = d * w2[u]
                else:
                    da[u] = 0.0
                gb1[u] += da[u]
            for i in range(f):
                xi = xr[i]
                row = g1[i]
                for u in range(h):
                    row[u] += xi * da[u]
        # the L2 penalty on the weights (not the biases), then the batch mean
        for k in range(nw1):
            grads[k] += alpha * params[k]
        for u in range(h):
            gw2[u] += alpha * w2[u]
        step += 1
        lr = LEARNING_RATE * math.sqrt(1.0 - BETA2**step) / (1.0 - BETA1**step)
        for k in range(params.shape[0]):
            g = grads[k] / bs
            m1[k] = BETA1 * m1[k] + (1.0 - BETA1) * g
            m2[k] = BETA2 * m2[k] + (1.0 - BETA2) * g * g
            params[k] -= lr * m1[k] / (math.sqrt(m2[k]) + EPSILON)
    return step


@njit(cache=True)
def _log_loss(x, y, params):  # type: ignore[no-untyped-def]
    """Mean log loss of the network ``params`` on (x, y)."""
    w1, b1, w2 = _layers(params, x.shape[1])
    z = np.empty(b1.shape[0])
    total = 0.0
    for r in range(x.shape[0]):
        o = _forward(x[r], w1, b1, w2, params[-1], z)
        # log(1 + e^-o) for y = 1, log(1 + e^o) for y = 0, computed stably
        s = -o if y[r] > 0.5 else o
        total += max(s, 0.0) + math.log1p(math.exp(-abs(s)))
    return total / max(x.shape[0], 1)


def fit_mlp(
    x: NDArray[np.float64],
    y: NDArray[np.bool_],
    hidden: int,
    *,
    alpha: float,
    max_iter: int,
    seed: int,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], float]:
    """Train the network on rows ``x`` (n, f) with labels ``y`` (n,); returns (W1 (f, h),
    b1 (h,), w2 (h,), b2) of the best epoch on the held-out tenth."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    yf = np.ascontiguousarray(y, dtype=np.float64)
    n, f = x.shape
    rng = np.random.default_rng(seed)
    perm = rng.permutation(n)
    n_val = max(1, int(round(VALIDATION * n))) if n >= 10 else 0
    val, fit = perm[:n_val], perm[n_val:]
    params = np.empty(f * hidden + 2 * hidden + 1)
    b_in = math.sqrt(6.0 / (f + hidden))
    b_out = math.sqrt(6.0 / (hidden + 1))
    params[: f * hidden + hidden] = rng.uniform(-b_in, b_in, f * hidden + hidden)
    params[f * hidden + hidden :] = rng.uniform(-b_out, b_out, hidden + 1)
    grads, m1, m2 = np.zeros_like(params), np.zeros_like(params), np.zeros_like(params)
    xv, yv = x[val], yf[val]
    best, best_loss, stale, step = params.copy(), np.inf, 0, 0
    for _ in range(max_iter):
        order = fit[rng.permutation(len(fit))]
        step = _epoch(x, yf, order, params, grads, m1, m2, step, float(alpha))
        if n_val == 0:
            best = params.copy()
            continue
        loss = float(_log_loss(xv, yv, params))
        if loss < best_loss - TOL:
            best_loss, best, stale = loss, params.copy(), 0
        else:
            stale += 1
            if best_loss < np.inf and loss < best_loss:
                best_loss, best = loss, params.copy()
            if stale >= PATIENCE:
                break
    w1, b1, w2 = _layers(best, f)
    return w1.copy(), b1.copy(), w2.copy(), float(best[-1])
