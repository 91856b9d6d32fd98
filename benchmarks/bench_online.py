"""Speed of online policy instantiation and of Experiment 1.

Goals (issue: online policy instantiation and Experiment 1):
- one decision (scan excluded) <= 10 µs for one agent, <= 3 µs per agent batched;
- the learnt preset's decision (issue: capabilities that earn their keep) <= 10 µs for
  one agent, <= 3 µs per agent batched;
- 2 workers >= 1.8x one worker on the same episodes (the full `copi reproduce` at
  paper scale, <= 120 s on 2 cores, is timed by `make run`).
"""

from __future__ import annotations

import tempfile
import time
import timeit
from collections.abc import Callable
from pathlib import Path

import numpy as np

from benchmarks._timing import Timing, median_time, note, report
from copi.experiments import NavigationConfig, evaluate
from copi.learning import LearnParams, explore, learn
from copi.methods import make_agent
from copi.online import ContextController, LearntAgent


def main() -> bool:
    tmp = Path(tempfile.mkdtemp())
    caps = learn(LearnParams(directions=16))
    caps_path = caps.save(tmp / "caps.npz")
    readings = explore(4, 500, seed=9).readings
    rng = np.random.default_rng(0)
    want = rng.normal(size=(len(readings), 2))
    plain = ContextController(caps)
    guarded = ContextController(caps, guard=1.2)
    plain.decide(readings[0], want[0])
    guarded.decide(readings[0], want[0])
    batch = readings[:1000]
    plain.decide_batch(batch, want[:1000])

    def single(ctl: ContextController) -> float:
        i = iter(range(10**9))
        return (
            min(
                timeit.repeat(
                    lambda: ctl.decide(readings[(k := next(i) % 2000)], want[k]),
                    number=20000,
                    repeat=5,
                )
            )
            / 20000
        )

    rows = [
        Timing("decide, one agent", single(plain)),
        Timing("decide, one agent, guard 1.2", single(guarded)),
        Timing(
            "decide_batch, 1000 agents",
            min(timeit.repeat(lambda: plain.decide_batch(batch, want[:1000]), number=20, repeat=5))
            / 20,
            per=1000,
        ),
    ]
    from copi.online import _learnt_kernels

    static = np.full(caps.n_rays, np.inf)
    p, out, feat = np.empty(17), np.empty(5), np.empty(8 * caps.n_rays)
    j = iter(range(1, 10**9))

    def one_decision(a: LearntAgent) -> Callable[[], None]:
        """One of ``a``'s decisions (the kernel alone) on the next stored reading."""
        args = (a._nodes_t, a._prior, a._net)

        def decide() -> None:
            k = next(j) % 2000
            _learnt_kernels.decide_learnt(
                readings[k], readings[k - 1], static, *args, want[k, 0], want[k, 1], 5.0,
                a.guard, a.alpha, a.beta, a.wait, a._cos, a._sin, 10.0, a._compass, feat, p, out,
                a._landmarks, -1, -1, 0.0, True, a.model.static_aware,
            )  # fmt: skip

        decide()
        return decide

    learnt = learn(LearnParams(directions=16, safety=True))
    agent = make_agent("copi-learnt", learnt)  # the registered preset
    learnt_decision = one_decision(agent)
    rows.append(
        Timing(
            "learnt preset: decide, one agent",
            sorted(timeit.repeat(learnt_decision, number=20000, repeat=5))[2] / 20000,
        )
    )
    # contexts that see motion (copi-learnt-motion, an ablation: no goal of its own)
    moving = learn(LearnParams(directions=16, safety=True, motion=True))
    motion_decision = one_decision(
        make_agent("copi-learnt-motion", moving)
    )
    rows.append(
        Timing(
            "learnt, contexts that see motion: decide, one agent",
            sorted(timeit.repeat(motion_decision, number=20000, repeat=5))[2] / 20000,
        )
    )
    prev_batch = readings[999:1999]
    static_batch = np.full(batch.shape, np.inf)
    agent.decide_batch(batch, prev_batch, want[:1000], 5.0, static_batch)
    rows.append(
        Timing(
            "learnt preset: decide_batch, 1000 agents",
            median_time(
                lambda: agent.decide_batch(batch, prev_batch, want[:1000], 5.0, static_batch),
                number=20,
            ),
            per=1000,
        )
    )
    # the registered preset's choice uses no context (beta 0): the same actions without
    # recognising any
    rows.append(
        Timing(
            "learnt preset: decide_batch, 1000 agents, recognise=False",
            median_time(
                lambda: agent.decide_batch(batch, prev_batch, want[:1000], 5.0, static_batch,
                                           recognise=False),  # fmt: skip
                number=20,
            ),
            per=1000,
        )
    )
    ok = report(
        "online decision (scan excluded)",
        rows,
        None,
        {rows[0].name: 10e-6, rows[1].name: 10e-6, rows[2].name: 3e-6, rows[3].name: 10e-6,
         rows[5].name: 3e-6, rows[6].name: 3e-6},
    )
    cfg = NavigationConfig(str(caps_path), worlds=400, method="copi-extended", guard=1.2)
    walls = {}
    for workers in (1, 2):
        t0 = time.perf_counter()
        evaluate(cfg, tmp / f"w{workers}.sqlite", workers=workers)
        walls[workers] = time.perf_counter() - t0
    speedup = walls[1] / walls[2]
    note(
        f"Experiment 1, 400 episodes: 1 worker {walls[1]:.1f} s, 2 workers {walls[2]:.1f} s, "
        f"speed-up {speedup:.2f}x (goal >= 1.8x)"
    )
    return ok and speedup >= 1.8


if __name__ == "__main__":
    raise SystemExit(0 if main() else 1)
