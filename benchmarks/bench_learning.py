"""Speed of capability learning.

Goals (issue: capability learning):
- GNG on 60,000 signals of 32-d sensor readings, growing 2 -> ~600 nodes with Fritzke's
  parameters: <= 0.15 s (compile time excluded and reported apart), quantisation error
  within 2 % of the plain reference implementation fed the same stream;
- skeletonisation of ~600 nodes <= 1 s;
- the whole `copi learn` at paper scale (100 worlds x 300 steps) <= 20 s.
"""

from __future__ import annotations

import os
import time

import numpy as np
from scipy.spatial.distance import cdist

from benchmarks._timing import Timing, note, report
from copi.learning import GrowingNeuralGas, LearnParams, _gng_kernels, explore, learn, skeletonize
from copi.learning._gng import signal_stream
from copi.learning.reference import reference_gng


def _kernel_once(X: np.ndarray, first: np.ndarray, order: np.ndarray) -> tuple[float, int]:
    cap = 2 + len(order) // 100
    w = np.zeros((cap, X.shape[1]))
    w[0], w[1] = X[first[0]], X[first[1]]
    err = np.zeros(cap)
    age = np.full((cap, cap), -1, dtype=np.int32)
    nbr = np.zeros((cap, cap), dtype=np.int32)
    deg = np.zeros(cap, dtype=np.int32)
    t0 = time.perf_counter()
    n, _ = _gng_kernels.gng_run(
        X, order, w, err, age, nbr, deg, 2, 0, cap, 0.2, 0.006, 100, 50, 0.5, 0.995
    )
    return time.perf_counter() - t0, int(n)


def main() -> bool:
    ex = explore(100, 300, seed=0)
    X = ex.readings
    first, order = signal_stream(len(X), 2, 0)
    t0 = time.perf_counter()
    _kernel_once(X[:300], np.array([0, 1]), np.arange(300))  # compiles (or loads the cache)
    compile_s = time.perf_counter() - t0
    runs = [_kernel_once(X, first, order) for _ in range(5)]
    kernel = float(np.median([r[0] for r in runs]))
    nodes = runs[0][1]
    fit_times = []
    for _ in range(3):
        t0 = time.perf_counter()
        gng = GrowingNeuralGas(random_state=0).fit(X)
        fit_times.append(time.perf_counter() - t0)
    qe = gng.quantization_error(X)
    skel = []
    for _ in range(3):
        t0 = time.perf_counter()
        lm = skeletonize(gng)
        skel.append(time.perf_counter() - t0)
    t0 = time.perf_counter()
    caps = learn(LearnParams())
    whole = time.perf_counter() - t0
    rows = [
        Timing(f"GNG kernel, {len(order):,} signals -> {nodes} nodes", kernel),
        Timing("GrowingNeuralGas.fit (kernel + labels)", float(np.median(fit_times))),
        Timing(
            f"skeletonize {len(gng.nodes_)} nodes -> {lm.n_landmarks} landmarks",
            float(np.median(skel)),
        ),
        Timing("learn() at paper scale (100 x 300)", whole),
    ]
    quick = os.environ.get("COPI_BENCH_QUICK")
    if not quick:
        t0 = time.perf_counter()
        ref_nodes, _ = reference_gng(X, first, order)
        rows.append(Timing("plain reference GNG, same stream", time.perf_counter() - t0))
        ref_qe = float(np.sqrt(cdist(X, ref_nodes, "sqeuclidean").min(1)).mean())
    ok = report(
        "capability learning (medians)",
        rows,
        "plain reference GNG, same stream" if not quick else None,
        {
            rows[0].name: 0.15,
            rows[2].name: 1.0,
            rows[3].name: 20.0,
        },
    )
    note(f"GNG compile (or cache load): {compile_s:.2f} s, excluded above")
    note(f"learn(): {caps.summary()}")
    if not quick:
        rel = abs(qe / ref_qe - 1)
        note(
            f"quantisation error {qe:.6f} vs plain reference {ref_qe:.6f}: "
            f"{rel:.2e} relative (goal < 2 %)"
        )
        ok &= rel < 0.02
    return ok


if __name__ == "__main__":
    raise SystemExit(0 if main() else 1)
