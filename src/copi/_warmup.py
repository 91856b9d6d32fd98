"""Compile copi's numba kernels ahead of time: ``python -m copi._warmup``.

``make install`` runs this once, so that the first ``make run`` or ``make test`` does not
pay the kernels' compilation (a few minutes on a slow machine). Every kernel is compiled
with ``cache=True``: numba keeps the machine code beside the sources and later processes
load it. The work is tiny (capabilities from 3 worlds, one episode of every method on
every family, one lifelong task, one pursuit game); nothing is written outside a
temporary directory.
"""

from __future__ import annotations

import dataclasses
import sys
import tempfile
import time
from pathlib import Path


def main() -> None:
    from copi.experiments.benchmark import BenchmarkConfig, run_benchmark
    from copi.experiments.pursuit import PursuitConfig, pursue
    from copi.learning import learn
    from copi.methods import PRESETS, method_spec, parse_methods

    t0 = time.perf_counter()
    print("copi: compiling kernels once (numba), about 30 s", file=sys.stderr, flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        paths = {}
        for name, preset in PRESETS.items():
            if name == "learnt-motion":
                continue
            small = dataclasses.replace(preset.learn, worlds=3, steps=60, probe_worlds=2,
                                        probe_steps=20)  # fmt: skip
            paths[name] = str(d / f"capabilities-{name}.npz")
            learn(small).save(paths[name])
        caps_path = paths["learnt"]
        families = ["star", "polygon", "indoor", "crowd", "maps"]
        methods = [r for r in parse_methods(None) if method_spec(r.method).available()]
        config = BenchmarkConfig(
            methods=tuple(methods), families=tuple(families), episodes=1, seed=0,
            capabilities=paths,
        )  # fmt: skip
        run_benchmark(config, d / "bench.sqlite")
        from copi.experiments.lifelong import LifelongConfig, run_lifelong
        from copi.methods import parse_lifelong_methods

        run_lifelong(
            LifelongConfig(str(caps_path), family="indoor", worlds=1, tasks=1,
                           methods=parse_lifelong_methods("copi-learnt@sensor:causal")),
            d / "lifelong.sqlite",
        )  # fmt: skip
        for dynamic in (False, True):
            for evader in ("capability", "game"):
                pursue(
                    PursuitConfig(capabilities=paths["extended"], evader=evader, dynamic=dynamic,
                                  games=1, horizon=30),
                    d / "pursuit.sqlite",
                )  # fmt: skip
    print(f"copi: kernels compiled in {time.perf_counter() - t0:.0f} s", file=sys.stderr)


if __name__ == "__main__":  # pragma: no cover
    main()
