"""Same seed, same result on every processor: learning and decisions computed with the
kernels compiled for this machine, then compiled for a generic x86-64 (no SIMD beyond
the baseline, no FMA) with OpenBLAS's Nehalem kernels and numpy's dispatched SIMD turned
off, must agree to the last bit.

Each run is a fresh interpreter (the settings act when numba, numpy and OpenBLAS load);
it learns a small faithful and a small learnt preset, decides on stored readings with
both controllers and a PPO policy, and plays an episode of a few methods, printing a
digest of every array. Without the fixed-order kernels (fastmath reassociation and
contraction, BLAS products where a choice follows) the map's nodes already differed.
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys

SCRIPT = r"""
import hashlib, json
import numpy as np
from copi.baselines import CompassGuard
from copi.baselines import PolicyWeights
from copi.runs import draw_episode, run_episode
from copi.learning import LearnParams, explore, learn
from copi.online import ContextController, LearntAgent

def h(*arrays):
    d = hashlib.sha256()
    for a in arrays:
        d.update(np.ascontiguousarray(a).tobytes())
    return d.hexdigest()[:16]

out = {}
faithful = learn(LearnParams(worlds=8, steps=200, directions=4, seed=3))
out["map"] = h(faithful.nodes, faithful.edges, faithful.landmarks.node_landmark)
out["landmarks"] = int(faithful.landmarks.n_landmarks)
learnt = learn(LearnParams(worlds=6, steps=150, directions=16, safety=True, probe_worlds=4,
                           probe_steps=60, seed=1))
out["learnt"] = h(learnt.nodes, learnt.safety.net, learnt.safety.template_safe)
s = explore(2, 200, seed=9).readings
want = np.random.default_rng(0).normal(size=(len(s), 2))
ctl = ContextController(faithful, guard=1.2)
out["decide"] = h(np.array([ctl.decide(s[k], want[k])[0] for k in range(len(s))]))
out["decide_batch"] = h(*ctl.decide_batch(s, want))
agent = LearntAgent(learnt)
out["learnt_batch"] = h(*agent.decide_batch(s[1:], s[:-1], want[1:], 5.0))
rng = np.random.default_rng(4)
policy = PolicyWeights(((rng.normal(0, 0.3, (16, 67)), rng.normal(0, 0.1, 16)),
                        (rng.normal(0, 0.3, (2, 16)), rng.normal(0, 0.1, 2))))
x = rng.uniform(-1, 1, (50, 67))
out["ppo"] = h(np.array([policy.act(xi) for xi in x]))
episodes = []
for family in ("star", "crowd"):
    for agent in (CompassGuard(), LearntAgent(learnt)):
        r = run_episode(agent, draw_episode(family, 0, 0), sensing="map", max_steps=300)
        episodes.append([r.outcome, r.steps, float(r.path_length).hex()])
out["episodes"] = episodes
print(json.dumps(out))
"""


def _run(extra: dict[str, str]) -> dict[str, object]:
    env = {**os.environ, **extra}
    res = subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True,
                         text=True, timeout=600)  # fmt: skip
    assert res.returncode == 0, res.stderr[-3000:]
    return json.loads(res.stdout.strip().splitlines()[-1])


def _elsewhere() -> dict[str, str]:
    """Settings that make this machine compute as a plainer processor would."""
    from numpy._core import _multiarray_umath as m

    env = {"NUMBA_CPU_NAME": "generic"}
    dispatched = [f for f in m.__cpu_dispatch__ if m.__cpu_features__.get(f)]
    if dispatched:
        env["NPY_DISABLE_CPU_FEATURES"] = " ".join(dispatched)
    if platform.machine().lower() in ("x86_64", "amd64"):
        env["OPENBLAS_CORETYPE"] = "Nehalem"
    return env


def test_learning_and_decisions_are_the_same_on_another_processor() -> None:
    here = _run({})
    there = _run(_elsewhere())
    assert here["landmarks"] > 1
    differ = {k: (here[k], there[k]) for k in here if here[k] != there[k]}
    assert not differ, f"results depend on the processor: {differ}"


PROBE = r"""
import json
import numba, threadpoolctl
import numpy as np
from numpy._core import _multiarray_umath as m

@numba.njit
def axpy(a, x, y):
    for i in range(x.shape[0]):
        y[i] += a * x[i]

axpy(2.0, np.ones(64), np.ones(64))
asm = axpy.inspect_asm(axpy.signatures[0]).lower()
print(json.dumps({
    "ymm": "%ymm" in asm or "%zmm" in asm,
    "numpy": {f: bool(m.__cpu_features__.get(f)) for f in m.__cpu_dispatch__},
    "blas": sorted({str(i.get("architecture")) for i in threadpoolctl.threadpool_info()
                    if i.get("internal_api") == "openblas"}),
}))
"""


def _probe(extra: dict[str, str]) -> dict:
    res = subprocess.run([sys.executable, "-c", PROBE], env={**os.environ, **extra},
                         capture_output=True, text=True, timeout=120)  # fmt: skip
    assert res.returncode == 0, res.stderr[-3000:]
    return json.loads(res.stdout.strip().splitlines()[-1])


def test_the_other_run_compiles_for_another_processor() -> None:
    """The comparison above means something only if the other run really computed as
    another processor would: asked, in a fresh interpreter with the same settings, what
    each library actually does. numba's code for a loop it vectorises uses no AVX
    register (a generic x86-64 has none; this machine's code does, where it has AVX);
    numpy's dispatched SIMD features this machine has read as absent; OpenBLAS runs its
    Nehalem kernels."""
    here, there = _probe({}), _probe(_elsewhere())
    dispatched = [f for f, on in here["numpy"].items() if on]
    assert not any(there["numpy"][f] for f in dispatched), there["numpy"]
    if platform.machine().lower() in ("x86_64", "amd64"):
        assert not there["ymm"], "numba compiled the other run with AVX registers"
        if here["numpy"].get("X86_V3") or here["numpy"].get("AVX2"):
            assert here["ymm"], "this machine has AVX, yet its own run did not use it"
        if here["blas"]:
            assert there["blas"] == ["Nehalem"], there["blas"]
