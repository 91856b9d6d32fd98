"""What copi's landmark rule changes downstream: the same presets learnt with it and with
copi 0.2's rule (``skeleton_bootstrap=0``, the knee of the map's own H(k)), run on the
same episodes, paired.

    python benchmarks/landmarks_effect.py --episodes 200 --out docs/landmarks-effect.md

Experiment 1 (1549 of the paper's worlds, level map) in the faithful and extended modes,
and the benchmark rows of copi's three presets (every family, levels sensor and map).
Differences are the new rule minus the old on the same episodes, in points, with 95 %
bootstrap intervals (success; median excess over episodes both succeeded in).
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
import time
from pathlib import Path

from copi.experiments import BenchmarkConfig, NavigationConfig, evaluate, run_benchmark
from copi.experiments.benchmark_report import _diff, _pair
from copi.experiments.presets import PRESETS
from copi.experiments.store import ResultsStore


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--episodes", type=int, default=200, help="benchmark episodes per family")
    ap.add_argument("--worlds", type=int, default=1549, help="Experiment 1 episodes")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    t0 = time.perf_counter()
    tmp = Path(tempfile.mkdtemp())
    from copi.learning import learn

    caps: dict[str, dict[str, str]] = {"new": {}, "old": {}}
    counts: dict[str, dict[str, str]] = {"new": {}, "old": {}}
    for rule, extra in (("new", {}), ("old", {"skeleton_bootstrap": 0})):
        for name in ("faithful", "extended", "learnt"):
            c = learn(dataclasses.replace(PRESETS[name].learn, workers=a.workers, **extra))
            path = tmp / f"{rule}-{name}.npz"
            c.save(path)
            caps[rule][name] = str(path)
            counts[rule][name] = f"{c.landmarks.n_landmarks} ({len(c.reduction.templates)})"
    lines = [
        "# The landmark rule downstream (`python benchmarks/landmarks_effect.py "
        f"--episodes {a.episodes}`)",
        "",
        "Seed 0 throughout. Landmarks (templates): "
        + "; ".join(f"{n}: {counts['new'][n]} now, {counts['old'][n]} with copi 0.2's rule"
                    for n in ("faithful", "extended", "learnt"))
        + ". Δ: now minus 0.2's rule on the same episodes, points, 95 % bootstrap intervals.",
        "",
        "## Experiment 1 (the paper's worlds, level map)",
        "",
        "| mode | episodes | success now | success 0.2 | Δ success | Δ median excess |",
        "|---|---|---|---|---|---|",
    ]  # fmt: skip
    for name in ("faithful", "extended"):
        rows = {}
        for rule in ("new", "old"):
            cfg = NavigationConfig(caps[rule][name], method=PRESETS[name].method,
                                   worlds=a.worlds)  # fmt: skip
            out = tmp / f"e1-{rule}-{name}.sqlite"
            rid = evaluate(cfg, out, workers=a.workers)
            with ResultsStore(out, readonly=True) as store:
                rows[rule] = store.episodes(rid)
        ds, de = _pair(rows["new"], rows["old"])
        sn = sum(r.outcome == "success" for r in rows["new"]) / len(rows["new"])
        so = sum(r.outcome == "success" for r in rows["old"]) / len(rows["old"])
        lines.append(f"| {PRESETS[name].method} | {len(rows['new'])} | {100 * sn:.1f} % | "
                     f"{100 * so:.1f} % | {_diff(ds)} | {_diff(de)} |")  # fmt: skip
    lines += ["", f"## Benchmark rows ({a.episodes} episodes per family)", "",
              "| family | method | sensing | success now | success 0.2 | Δ success "
              "| Δ median excess |", "|---|---|---|---|---|---|---|"]  # fmt: skip
    arms = ("copi-faithful", "copi-extended", "copi-learnt")
    stores = {}
    for rule in ("new", "old"):
        cfg = BenchmarkConfig(methods=arms, episodes=a.episodes, capabilities=caps[rule])
        stores[rule] = tmp / f"bench-{rule}.sqlite"
        run_benchmark(cfg, stores[rule], workers=a.workers)
    by: dict[str, dict[tuple[str, str, str], list]] = {}
    for rule, path in stores.items():
        with ResultsStore(path, readonly=True) as store:
            for r in store.episodes():
                by.setdefault(rule, {}).setdefault((r.family, r.method, r.sensing), []).append(r)
    for key in sorted(by["new"], key=lambda k: (k[0], arms.index(k[1]), k[2])):
        new, old = by["new"][key], by["old"][key]
        ds, de = _pair(new, old)
        sn = sum(r.outcome == "success" for r in new) / len(new)
        so = sum(r.outcome == "success" for r in old) / len(old)
        lines.append(f"| {key[0]} | {key[1]} | {key[2]} | {100 * sn:.1f} % | {100 * so:.1f} % "
                     f"| {_diff(ds)} | {_diff(de)} |")  # fmt: skip
    lines += ["", f"({time.perf_counter() - t0:.0f} s on {a.workers} workers.)", ""]
    text = "\n".join(lines) + "\n"
    print(text)
    if a.out:
        Path(a.out).write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
