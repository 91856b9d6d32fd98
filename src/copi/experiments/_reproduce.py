"""The paper's experiments end to end, into one directory (``copi reproduce``).

Learn capabilities at the paper's scale (100 worlds x 300 steps), run Experiment 1 on
1549 dynamic worlds in the faithful mode (the paper's chain) and the extended mode,
Experiment 2 (homicidal-chauffeur games, stationary and dynamic, capability and game
evaders), the benchmark's quick version (every default method on the same episodes of
every family), Experiment 3 (lifelong: indoor worlds of successive tasks), and write the
reports. Everything resumes: rerunning the same call finishes what an interruption left.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from copi._rng import check_seed
from copi.errors import CopiError, ResultsError
from copi.experiments.benchmark import BenchmarkConfig, ensure_capabilities, run_benchmark
from copi.experiments.lifelong import LifelongConfig, run_lifelong
from copi.experiments.navigation import NavigationConfig, evaluate
from copi.experiments.pursuit import PursuitConfig, pursue
from copi.methods import PRESETS, method_spec, parse_methods
from copi.reports import write_benchmark_report, write_report
from copi.world import BENCHMARK_FAMILIES

__all__ = ["Reproduced", "reproduce"]

Tasks = Callable[[str, int], Callable[[int, int], None]]
"""tasks(label, total) -> progress(done, total): one progress display per stage."""


@dataclass(frozen=True)
class Reproduced:
    """What :func:`reproduce` wrote."""

    report: Path
    """``report.md``: Experiment 1, 2 and 3 (tables, Fig. 3, 4 and 5, Experiment 3's figure)."""
    benchmark: Path
    """``benchmark.md``: the quick benchmark's tables and figure."""
    summaries: dict[str, str]
    """Each experiment's table, as Markdown (what the command prints)."""


def _silent(label: str, total: int) -> Callable[[int, int], None]:
    return lambda done, total: None


def reproduce(
    output: str | os.PathLike[str],
    *,
    quick: bool = False,
    workers: int = 2,
    seed: int = 0,
    tasks: Tasks | None = None,
) -> Reproduced:
    """Run every experiment of the paper into ``output`` (see the module); ``quick``: a
    small version of each (100 episodes, 20 games, 10 benchmark episodes per family, 2
    lives of 10 tasks) to try things out. The faithful mode stays the paper's: its
    capabilities and method are the paper's own."""
    check_seed(seed)
    out = Path(output)
    out.mkdir(parents=True, exist_ok=True)
    try:
        return _reproduce(out, quick, workers, seed, tasks or _silent)
    except ResultsError as exc:
        if "different configuration" not in str(exc):
            raise
        other = "a full" if quick else "a --quick"
        raise CopiError(
            f"{out} holds results of {other} run or of other settings; reproduce into "
            f"another directory, or delete {out} to start over"
        ) from None


def _reproduce(out: Path, quick: bool, workers: int, seed: int, tasks: Tasks) -> Reproduced:
    results = out / "experiment1.sqlite"
    episodes = 100 if quick else 1549
    # Experiment 1 in the paper's mode and the extended one
    for name in ("faithful", "extended"):
        learnt = tasks(f"learn ({name})", 1)
        caps = ensure_capabilities(out, {name}, seed=seed)[name]
        learnt(1, 1)
        config = NavigationConfig(capabilities=caps, method=PRESETS[name].method,
                                  worlds=episodes, seed=seed)  # fmt: skip
        evaluate(config, results, workers=workers,
                 progress=tasks(f"evaluate ({name})", episodes))  # fmt: skip
    # Experiment 2: the homicidal chauffeur, through the extended mode's capabilities
    extended = str(out / "capabilities-extended.npz")
    for kind in ("capability", "game"):
        for dynamic in (False, True):
            game = PursuitConfig(capabilities=extended, evader=kind, dynamic=dynamic,
                                 games=20 if quick else 200, seed=seed,
                                 guard=PRESETS["extended"].guard)  # fmt: skip
            pursue(game, results, workers=workers,
                   progress=tasks(f"pursuit ({game.method})", game.games))  # fmt: skip
    # The benchmark's quick version: every default method on the same episodes
    arms = [r for r in parse_methods(None) if method_spec(r.method).available()]
    presets = {p for r in arms if (p := method_spec(r.method).capabilities)}
    bench = BenchmarkConfig(
        methods=tuple(arms), families=BENCHMARK_FAMILIES, episodes=10 if quick else 30,
        seed=seed, capabilities=ensure_capabilities(out, presets, seed=seed),
    )  # fmt: skip
    bench_out = out / "benchmark.sqlite"
    total = bench.episodes * len(arms) * len(BENCHMARK_FAMILIES)
    run_benchmark(bench, bench_out, workers=workers, progress=tasks("benchmark (quick)", total))
    # Experiment 3, lifelong
    life = LifelongConfig(
        ensure_capabilities(out, {"learnt"}, seed=seed)["learnt"], family="indoor",
        worlds=2 if quick else 20, tasks=10 if quick else 50, seed=seed,
    )  # fmt: skip
    run_lifelong(life, results, workers=workers,
                 progress=tasks("lifelong (lives)", life.worlds * len(life.methods)))  # fmt: skip
    benchmark = write_benchmark_report(bench_out, out)
    report = write_report([str(results)], out)
    return Reproduced(report.path, benchmark, report.summaries)
