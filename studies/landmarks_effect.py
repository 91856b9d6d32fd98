"""What copi's landmark rule changes downstream: the same presets learnt with it and with
copi 0.2's rule (``skeleton_bootstrap=0``, the knee of the map's own H(k)), run on the
same episodes, paired.

    python studies/landmarks_effect.py --episodes 200 --seeds 0,1,2,3,4 \
        --out docs/landmarks-effect.md

Experiment 1 (1549 of the paper's worlds, level map) in the faithful and extended modes,
and the benchmark rows of copi's three presets (every family, levels sensor and map).
Differences are the new rule minus the old on the same episodes, in points, with 95 %
bootstrap intervals (success; median excess over episodes both succeeded in).

One learning seed is one draw of each rule's landmarks, so a difference on one seed
compares two draws; with ``--seeds`` the chain's modes are learnt anew under both rules
for every seed (the episodes stay seed 0's) and the report gives, per seed and row, the
new rule's numbers and the old's, and the mean over seeds of the paired difference with a
95 % t-interval over seeds (the learnt preset is left out there: its default never reads
the landmarks, so its rows are the same under both rules, as the seed-0 table shows).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from copi.experiments import BenchmarkConfig, NavigationConfig, evaluate, run_benchmark
from copi.methods import PRESETS
from copi.results import ResultsStore, format_difference, pair_episodes


def _learn_into(name: str, seed: int, extra: dict, path: Path, workers: int) -> Any:
    """The preset ``name``'s capabilities learnt with ``seed`` (and ``extra``), saved."""
    from copi.learning import learn

    c = learn(dataclasses.replace(PRESETS[name].learn, workers=workers, seed=seed, **extra))
    c.save(path)
    return c


def _experiment1(caps_path: str, name: str, out: Path, a: argparse.Namespace) -> list:
    """Experiment 1's episodes of preset ``name``'s method on ``caps_path``."""
    cfg = NavigationConfig(caps_path, method=PRESETS[name].method, worlds=a.worlds)
    rid = evaluate(cfg, out, workers=a.workers)
    with ResultsStore(out, readonly=True) as store:
        return store.episodes(rid)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--episodes", type=int, default=200, help="benchmark episodes per family")
    ap.add_argument("--worlds", type=int, default=1549, help="Experiment 1 episodes")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seeds", default="0", help="learning seeds (the first is the paired one)")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    seeds = [int(x) for x in a.seeds.split(",")]
    t0 = time.perf_counter()
    tmp = Path(tempfile.mkdtemp())

    caps: dict[str, dict[str, str]] = {"new": {}, "old": {}}
    counts: dict[str, dict[str, str]] = {"new": {}, "old": {}}
    for rule, extra in (("new", {}), ("old", {"skeleton_bootstrap": 0})):
        for name in ("faithful", "extended", "learnt"):
            path = tmp / f"{rule}-{name}.npz"
            c = _learn_into(name, seeds[0], extra, path, a.workers)
            caps[rule][name] = str(path)
            counts[rule][name] = f"{c.landmarks.n_landmarks} ({len(c.reduction.templates)})"
    lines = [
        "# The landmark rule downstream (`python studies/landmarks_effect.py "
        f"--episodes {a.episodes} --seeds {a.seeds}`)",
        "",
        "<!-- generated: written whole by studies/landmarks_effect.py -->",
        "",
        f"Learning seed {seeds[0]}, episodes of seed 0. Landmarks (templates): "
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
            rows[rule] = _experiment1(caps[rule][name], name, tmp / f"e1-{rule}-{name}.sqlite", a)
        ds, de = pair_episodes(rows["new"], rows["old"])
        sn = sum(r.outcome == "success" for r in rows["new"]) / len(rows["new"])
        so = sum(r.outcome == "success" for r in rows["old"]) / len(rows["old"])
        lines.append(f"| {PRESETS[name].method} | {len(rows['new'])} | {100 * sn:.1f} % | "
                     f"{100 * so:.1f} % | {format_difference(ds)} "
                     f"| {format_difference(de)} |")  # fmt: skip
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
        ds, de = pair_episodes(new, old)
        sn = sum(r.outcome == "success" for r in new) / len(new)
        so = sum(r.outcome == "success" for r in old) / len(old)
        lines.append(f"| {key[0]} | {key[1]} | {key[2]} | {100 * sn:.1f} % | {100 * so:.1f} % "
                     f"| {format_difference(ds)} | {format_difference(de)} |")  # fmt: skip
    if len(seeds) > 1:
        lines += over_seeds(seeds, a, tmp)
    lines += ["", f"({time.perf_counter() - t0:.0f} s on {a.workers} workers.)", ""]
    text = "\n".join(lines) + "\n"
    print(text)
    if a.out:
        Path(a.out).write_text(text, encoding="utf-8")


def _t_interval(d: list[float]) -> str:
    """Mean of the per-seed differences with a 95 % t-interval over seeds (points)."""
    x = np.asarray(d, dtype=float)
    x = x[np.isfinite(x)]
    if len(x) < 2:
        return "—"
    half = stats.t.ppf(0.975, len(x) - 1) * x.std(ddof=1) / math.sqrt(len(x))
    m = x.mean()
    return f"{m:+.1f} [{m - half:+.1f}, {m + half:+.1f}]"


def _one(x: float) -> str:
    return f"{x:.1f}" if math.isfinite(x) else "—"


def _summary(rows: list) -> tuple[float, float]:
    won = [r for r in rows if r.outcome == "success"]
    ex = [r.excess for r in won if r.excess is not None]
    return 100 * len(won) / len(rows), 100 * float(np.median(ex)) if ex else math.nan


def over_seeds(seeds: list[int], a: argparse.Namespace, tmp: Path) -> list[str]:
    """Experiment 1 and the chain's benchmark rows under both rules, each seed learnt
    anew: per seed, and the mean paired difference over seeds."""

    arms = ("copi-faithful", "copi-extended")
    # (row key) -> rule -> per seed (success %, median excess %)
    table: dict[tuple[str, ...], dict[str, list[tuple[float, float]]]] = {}
    landmarks: dict[str, list[int]] = {"new": [], "old": []}
    for seed in seeds:
        caps: dict[str, dict[str, str]] = {"new": {}, "old": {}}
        for rule, extra in (("new", {}), ("old", {"skeleton_bootstrap": 0})):
            for name in ("faithful", "extended"):
                path = tmp / f"s{seed}-{rule}-{name}.npz"
                c = _learn_into(name, seed, extra, path, a.workers)
                caps[rule][name] = str(path)
            landmarks[rule].append(c.landmarks.n_landmarks)
            for name in ("faithful", "extended"):
                rows = _experiment1(caps[rule][name], name,
                                    tmp / f"s{seed}-e1-{rule}-{name}.sqlite", a)  # fmt: skip
                key = ("Experiment 1", PRESETS[name].method, "map")
                table.setdefault(key, {}).setdefault(rule, []).append(_summary(rows))
            cfg = BenchmarkConfig(methods=arms, episodes=a.episodes, capabilities=caps[rule])
            store_path = tmp / f"s{seed}-bench-{rule}.sqlite"
            run_benchmark(cfg, store_path, workers=a.workers)
            with ResultsStore(store_path, readonly=True) as store:
                groups: dict[tuple[str, ...], list] = {}
                for r in store.episodes():
                    groups.setdefault((r.family, r.method, r.sensing), []).append(r)
            for key, rows in groups.items():
                table.setdefault(key, {}).setdefault(rule, []).append(_summary(rows))
        print(f"seed {seed} done", flush=True)
    lines = [
        "", f"## Over learning seeds {', '.join(map(str, seeds))} (each rule learnt anew)", "",
        f"Landmarks per seed: now {', '.join(map(str, landmarks['new']))}; with 0.2's rule "
        f"{', '.join(map(str, landmarks['old']))}. Success and median excess (%) per seed, "
        "now / 0.2's rule; Δ: the mean over seeds of now minus 0.2's rule (points), with a "
        "95 % t-interval over seeds. Episodes: seed 0's, the same for every seed and rule.",
        "",
        "| rows | method | sensing | success per seed, now / 0.2 | Δ success "
        "| median excess per seed, now / 0.2 | Δ median excess |",
        "|---|---|---|---|---|---|---|",
    ]  # fmt: skip
    order = sorted(table, key=lambda k: (k[0] != "Experiment 1", k[0], k[1], k[2]))
    for key in order:
        new, old = table[key]["new"], table[key]["old"]
        succ = " · ".join(f"{n[0]:.1f}/{o[0]:.1f}" for n, o in zip(new, old, strict=True))
        exc = " · ".join(f"{_one(n[1])}/{_one(o[1])}" for n, o in zip(new, old, strict=True))
        lines.append(
            f"| {key[0]} | {key[1]} | {key[2]} | {succ} "
            f"| {_t_interval([n[0] - o[0] for n, o in zip(new, old, strict=True)])} | {exc} "
            f"| {_t_interval([n[1] - o[1] for n, o in zip(new, old, strict=True)])} |"
        )
    return lines + ["", *multiplicity(lines)]


def multiplicity(lines: list[str]) -> list[str]:
    """Which Δ intervals of the over-seeds table exclude zero, and which stay so after
    Holm's correction over all of them (two-sided one-sample t-tests of the per-seed
    differences), computed from the table's own per-seed values (``lines``)."""
    tests: list[tuple[str, float, float]] = []  # (row and metric, mean difference, p)
    for line in lines:
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) != 7 or "/" not in cells[3] or cells[0] == "rows":
            continue
        for metric, col in (("success", 3), ("median excess", 5)):
            pairs = [pair.split("/") for pair in cells[col].split(" · ")]
            d = np.array([float(a) - float(b) for a, b in pairs if "—" not in (a, b)])
            if len(d) < 2 or not np.isfinite(d).all():
                continue
            pval = 1.0 if d.std(ddof=1) == 0 else float(stats.ttest_1samp(d, 0.0).pvalue)
            tests.append((f"{cells[0]}, {cells[1]}, {cells[2]}: {metric}", float(d.mean()), pval))
    n = len(tests)
    ranked = sorted(range(n), key=lambda i: tests[i][2])
    holm = [1.0] * n
    running = 0.0
    for rank, i in enumerate(ranked):  # Holm's step-down adjustment
        running = max(running, min(1.0, (n - rank) * tests[i][2]))
        holm[i] = running
    raw = [t for t in tests if t[2] < 0.05]
    kept = [t for t, h in zip(tests, holm, strict=True) if h < 0.05]

    def told(ts: list[tuple[str, float, float]]) -> str:
        return "; ".join(f"{name} {m:+.1f} (p = {pv:.3f})" for name, m, pv in ts) or "none"

    return [
        f"Of the {n} intervals above, {len(raw)} exclude{'s' if len(raw) == 1 else ''} zero "
        f"({told(raw)}); about "
        f"{0.05 * n:.1f} would by chance alone. After Holm's correction over the {n}: "
        f"{len(kept)} ({told(kept)}).",
    ]


if __name__ == "__main__":
    main()
