"""The PPO policy's decision in numpy, without torch (issue goals: one decision <= 10 us,
a batch <= 3 us per agent).

The network is the shipped shape (observation 2 N + 3 = 67, two tanh layers of 64, a
velocity) with seeded random weights: the cost does not depend on the values. "Single"
is one call of :meth:`PolicyWeights.act` (numba); "observation" the features of one
reading (the ranges turned into the frame of the direction); "batched" one call of
:meth:`PolicyWeights.act_batch` on 256 observations, per agent. The reference row is
one (64 x 67) matrix-vector product in numpy in the same run, so the ratios say what a
decision costs next to the cheapest numpy call of its size.
"""

from __future__ import annotations

import numpy as np

from benchmarks._timing import Timing, median_time, report
from copi.baselines._ppo import PolicyWeights, features, observation_size


def main() -> bool:
    rng = np.random.default_rng(0)
    n = 32
    m = observation_size(n)
    sizes = [m, 64, 64, 2]
    layers = tuple(
        (rng.normal(0, 1 / np.sqrt(a), (b, a)), rng.normal(0, 0.1, b))
        for a, b in zip(sizes[:-1], sizes[1:], strict=True)
    )
    policy = PolicyWeights(layers, n_rays=n)
    x = rng.normal(size=m)
    batch = rng.normal(size=(256, m))
    ranges = rng.uniform(0.5, 10.0, n)
    previous = rng.uniform(0.5, 10.0, n)
    direction = np.array([0.6, 0.8])
    w0 = layers[0][0]
    rows = [
        Timing("numpy W @ x (64 x 67)", median_time(lambda: w0 @ x, number=20000)),
        Timing("observation (features)", median_time(
            lambda: features(ranges, previous, direction, 5.0, 10.0), number=20000)),
        Timing("single decision (act)", median_time(lambda: policy.act(x), number=20000)),
        Timing("batched decision (256 agents)",
               median_time(lambda: policy.act_batch(batch), number=2000), per=256),
    ]  # fmt: skip
    return report(
        "PPO policy in numpy",
        rows,
        "numpy W @ x (64 x 67)",
        {"single decision (act)": 10e-6, "batched decision (256 agents)": 3e-6},
    )


if __name__ == "__main__":
    main()
