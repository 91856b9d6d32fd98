"""``copi evaluate``, ``benchmark``, ``pursuit``, ``report``, ``reproduce``: experiments."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any

import typer

from copi._files import check_outputs
from copi.cli._common import _with_progress, app, console, out, progress
from copi.errors import CopiError

_SCHEDULER_HELP = (
    "Dask scheduler tcp://HOST:PORT instead; its workers must read the input files "
    "(capabilities, worlds) at the same paths."
)


def _resuming(
    report: Callable[[int, int], None], output: Path, unit: str
) -> Callable[[int, int], None]:
    """``report``, saying first, when a run resumes, how much of it was already done."""
    first = True

    def call(done: int, total: int) -> None:
        nonlocal first
        if first and 0 < done < total:
            console.print(
                f"copi: resuming: {done}/{total} {unit} already done in {output}", highlight=False
            )
        first = False
        report(done, total)

    return call


@app.command("evaluate")
def evaluate_command(
    capabilities: Annotated[
        Path | None,
        typer.Argument(help="Capabilities file (.npz); needed by copi's methods only."),
    ] = None,
    output: Annotated[
        Path | None, typer.Option("-o", "--output", help="Results file (SQLite).")
    ] = None,
    method: Annotated[
        str | None,
        typer.Option("--method", help="copi-faithful (default), copi-extended or a baseline."),
    ] = None,
    preset: Annotated[
        str | None,
        typer.Option(
            "--preset",
            help="copi's mode: faithful, extended, learnt or learnt-motion (method, guard).",
        ),
    ] = None,
    worlds: Annotated[int, typer.Option("--worlds", min=1, help="Episodes (paper: 1549).")] = 1549,
    family: Annotated[str, typer.Option("--family", help="World family.")] = "star",
    sensing: Annotated[str, typer.Option("--sensing", help="sensor, map or oracle.")] = "map",
    world_file: Annotated[
        Path | None, typer.Option("--world-file", help="Run these worlds instead of a family.")
    ] = None,
    seed: Annotated[int, typer.Option("--seed", min=0, help="Seed of the episodes.")] = 0,
    workers: Annotated[int, typer.Option("--workers", min=1, help="Local processes.")] = 1,
    scheduler: Annotated[str | None, typer.Option("--scheduler", help=_SCHEDULER_HELP)] = None,
    max_steps: Annotated[int, typer.Option("--max-steps", min=1, help="Step limit.")] = 1000,
    guard: Annotated[
        float | None,
        typer.Option("--guard", min=0.0, help="Guard of copi's methods (default: the method's)."),
    ] = None,
    continual: Annotated[
        bool, typer.Option("--continual", help="Learn unfamiliar contexts online.")
    ] = False,
    contact_continues: Annotated[
        bool,
        typer.Option(
            "--contact-continues", help="A contact does not end the episode (older behaviour)."
        ),
    ] = False,
    sensor_strategy: Annotated[
        str,
        typer.Option(
            "--sensor-strategy", help="Global strategy at level sensor: greedy or mapping."
        ),
    ] = "greedy",
) -> None:
    """Experiment 1 (paper §IV): reach goals in dynamic worlds never seen; each episode's
    path is compared with the optimum on the stationary snapshot. Rerunning the same
    command resumes an interrupted run."""
    from copi.experiments.navigation import NavigationConfig, evaluate
    from copi.experiments.report import summarize
    from copi.experiments.store import ResultsStore

    if output is None:
        raise CopiError("evaluate needs -o/--output: the results file to write")
    check_outputs({"the results store": (output, "results")}, inputs=[capabilities, world_file])
    method = _preset_method(preset, method, capabilities)
    if world_file is not None:
        from copi.world import load_worlds

        load_worlds(world_file)  # a bad file is refused before anything is written
    config = NavigationConfig(
        capabilities=str(capabilities) if capabilities is not None else None,
        method=method,
        worlds=worlds,
        family=family,
        sensing=sensing,
        world_file=str(world_file) if world_file is not None else None,
        seed=seed,
        max_steps=max_steps,
        guard=guard,
        continual=continual,
        end_on_contact=not contact_continues,
        sensor_strategy=sensor_strategy,
    )
    output.parent.mkdir(parents=True, exist_ok=True)
    run_id = _with_progress(
        f"{method}: episodes",
        worlds,
        lambda report: evaluate(
            config,
            output,
            workers=workers,
            scheduler=scheduler,
            progress=_resuming(report, output, "episodes"),
        ),  # fmt: skip
    )
    with ResultsStore(output, readonly=True) as store:
        s = summarize(store.episodes(run_id))
    skipped = f", {s['skipped']} skipped (no valid task)" if s["skipped"] else ""
    if not s["episodes"]:
        out.print(f"{output}: {method} ({sensing}): no episode ran{skipped}")
        return
    out.print(
        f"{output}: {method} ({sensing}): {s['episodes']} episodes{skipped}, success "
        f"{100 * s['success']:.1f} %, collision {100 * s['contact']:.1f} %, timeout "
        f"{100 * s['timeout']:.1f} %, median excess {100 * s['excess_median']:.1f} %, "
        f"standing still {100 * s['no_policy']:.1f} %, unfamiliar "
        f"{100 * s['unfamiliar']:.1f} %, {s['decisions_per_s']:,.0f} decisions/s"
    )
    from copi.experiments.report import warnings_for

    for w in warnings_for(method, s):
        console.print(f"copi: warning: {w}", highlight=False, markup=False)


def _preset_method(preset: str | None, method: str | None, capabilities: Path | None) -> str:
    """The method a ``--preset`` stands for (checked against ``--method`` and against how
    the capabilities file was learnt); without a preset, ``method`` or copi-faithful."""
    from copi.errors import InvalidArgumentError
    from copi.experiments.methods import check_preset_capabilities
    from copi.experiments.methods import preset as get_preset

    if preset is None:
        return method or "copi-faithful"
    p = get_preset(preset)
    if method is not None and method != p.method:
        raise InvalidArgumentError(f"--method {method} contradicts --preset {preset} ({p.method})")
    if capabilities is not None:
        from copi.learning import Capabilities

        check_preset_capabilities(preset, Capabilities.load(capabilities), str(capabilities))
    return p.method


@app.command("benchmark")
def benchmark_command(
    output: Annotated[Path, typer.Option("-o", "--output", help="Directory for everything.")],
    quick: Annotated[
        bool, typer.Option("--quick", help="30 episodes per family (a few minutes).")
    ] = False,
    families: Annotated[
        str | None, typer.Option("--families", help="Comma-separated families (default: all).")
    ] = None,
    methods: Annotated[
        str | None,
        typer.Option("--methods", help="Comma-separated methods, name or name@level."),
    ] = None,
    episodes: Annotated[
        int | None, typer.Option("--episodes", min=1, help="Episodes per family (1000).")
    ] = None,
    seed: Annotated[int, typer.Option("--seed", min=0, help="Seed of the episodes.")] = 0,
    workers: Annotated[int, typer.Option("--workers", min=1, help="Local processes.")] = 2,
    scheduler: Annotated[str | None, typer.Option("--scheduler", help=_SCHEDULER_HELP)] = None,
    sensor_strategy: Annotated[
        str,
        typer.Option(
            "--sensor-strategy", help="Global strategy at level sensor: greedy or mapping."
        ),
    ] = "greedy",
) -> None:
    """Every method at its sensing levels on the same episodes of every world family, into
    DIR/benchmark.sqlite (resumable), with DIR/benchmark.md: a table per family, paired
    differences against copi with 95 % bootstrap intervals, and a figure."""
    from copi.baselines import navground_available
    from copi.experiments.benchmark import (
        BENCHMARK_FAMILIES,
        BenchmarkConfig,
        ensure_capabilities,
        run_benchmark,
    )
    from copi.experiments.benchmark_report import write_benchmark_report
    from copi.experiments.methods import method_spec, parse_methods
    from copi.online import check_strategy
    from copi.world import check_family

    fams = (
        BENCHMARK_FAMILIES
        if families is None
        else tuple(f.strip() for f in families.split(",") if f.strip())
    )
    for f in fams:
        check_family(f)
    check_strategy(sensor_strategy)
    chosen = parse_methods(methods)
    if methods is None and not navground_available():
        console.print(
            "copi: navground is not installed: its peers are left out "
            "(pip install 'copi[peers]' to include them)",
            highlight=False,
        )
        chosen = [m for m in chosen if method_spec(m[0]).available]
    for m, _ in chosen:
        if not method_spec(m).available:
            raise CopiError(
                f"{m} needs navground, which is not installed: pip install 'copi[peers]'"
            )
    n = episodes if episodes is not None else (30 if quick else 1000)
    check_outputs(
        {"the benchmark's directory": (output, "directory"),
         "the results store": (output / "benchmark.sqlite", "results"),
         "the report": (output / "benchmark.md", "text")},
    )  # fmt: skip
    if "maps" in fams:
        from copi.world import movingai_dir

        movingai_dir()  # refuse a missing data directory before anything is written
    output.mkdir(parents=True, exist_ok=True)
    presets = {p for m, _ in chosen if (p := method_spec(m).capabilities) is not None}
    with progress() as bar:
        task = bar.add_task("learn capabilities", total=len(presets))
        caps = ensure_capabilities(output, presets, seed=seed)
        bar.update(task, completed=len(presets))
    config = BenchmarkConfig(
        methods=tuple(chosen), families=tuple(fams), episodes=n, seed=seed, capabilities=caps,
        sensor_strategy=sensor_strategy,
    )  # fmt: skip
    results = output / "benchmark.sqlite"
    total = n * len(fams) * len(chosen)
    _with_progress(
        "benchmark: episodes",
        total,
        lambda report: run_benchmark(
            config,
            results,
            workers=workers,
            scheduler=scheduler,
            progress=_resuming(report, results, "episodes"),
        ),  # fmt: skip
    )
    report = write_benchmark_report(results, output)
    out.print(report.read_text(encoding="utf-8").split("![")[0])
    out.print(str(report))


@app.command("pursuit")
def pursuit_command(
    capabilities: Annotated[Path, typer.Argument(help="Capabilities file (.npz).")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Results file (SQLite).")],
    games: Annotated[int, typer.Option("--games", min=1, help="Games to play.")] = 100,
    dynamic: Annotated[
        bool, typer.Option("--dynamic/--static", help="With or without moving obstacles.")
    ] = True,
    evader: Annotated[
        str,
        typer.Option("--evader", help="capability (through the capabilities), learnt (through "
                     "the learnt preset's agent) or game."),
    ] = "capability",
    seed: Annotated[int, typer.Option("--seed", min=0, help="Seed of the games.")] = 0,
    horizon: Annotated[int, typer.Option("--horizon", min=1, help="Steps to survive.")] = 300,
    workers: Annotated[int, typer.Option("--workers", min=1, help="Local processes.")] = 1,
    scheduler: Annotated[str | None, typer.Option("--scheduler", help=_SCHEDULER_HELP)] = None,
    guard: Annotated[
        float | None,
        typer.Option("--guard", min=0.0, help="The capability evader's guard (default 1.2)."),
    ] = None,
    preset: Annotated[
        str | None,
        typer.Option("--preset", help="copi's mode: faithful, extended (set the guard) or "
                     "learnt (the learnt evader and its guard)."),
    ] = None,
    contact_continues: Annotated[
        bool,
        typer.Option("--contact-continues", help="A contact does not end the game (older rule)."),
    ] = False,
) -> None:
    """Experiment 2 (paper §IV, Fig. 5): the homicidal chauffeur. A faster car with a
    turn radius chases the agent; the agent plays the game's strategy through its
    capabilities (or, with --evader game, directly). Resumable, like evaluate."""
    from copi.errors import InvalidArgumentError
    from copi.experiments.methods import check_preset_capabilities
    from copi.experiments.pursuit import PursuitConfig, pursue
    from copi.experiments.report import summarize_games
    from copi.experiments.store import ResultsStore
    from copi.learning import Capabilities

    if preset is not None:
        from copi.experiments.methods import preset as get_preset

        if preset == "learnt-motion":
            raise InvalidArgumentError(
                "the pursuit game plays presets faithful, extended and learnt; got learnt-motion"
            )
        want = get_preset(preset).guard
        check_preset_capabilities(preset, Capabilities.load(capabilities), str(capabilities))
        if guard is not None and guard != want:
            raise InvalidArgumentError(f"--guard {guard} contradicts --preset {preset} ({want})")
        guard = want
        if preset == "learnt":
            if evader == "game":
                raise InvalidArgumentError(
                    "--evader game plays no capabilities; --preset learnt sets the learnt evader"
                )
            evader = "learnt"
        elif evader == "learnt":
            raise InvalidArgumentError(f"--evader learnt needs --preset learnt, not {preset}")
    elif evader == "learnt":
        check_preset_capabilities("learnt", Capabilities.load(capabilities), str(capabilities))
        guard = 1.05 if guard is None else guard
    guard = 1.2 if guard is None else guard
    check_outputs({"the results store": (output, "results")}, inputs=[capabilities])
    config = PursuitConfig(
        capabilities=str(capabilities), evader=evader, dynamic=dynamic, games=games,
        seed=seed, horizon=horizon, guard=guard, contact_ends=not contact_continues,
    )  # fmt: skip
    output.parent.mkdir(parents=True, exist_ok=True)
    run_id = _with_progress(
        f"{config.method}: games",
        games,
        lambda report: pursue(
            config,
            output,
            workers=workers,
            scheduler=scheduler,
            progress=_resuming(report, output, "games"),
        ),  # fmt: skip
    )
    with ResultsStore(output, readonly=True) as store:
        s = summarize_games(store.games(run_id))
    out.print(
        f"{output}: {config.method}: {s['games']} games, capture {100 * s['capture']:.1f} %, "
        f"collision {100 * s['collision']:.1f} %, "
        f"mean survival {s['survival_mean']:.1f} steps, games with contact "
        f"{100 * s['contact_games']:.1f} %"
    )


@app.command("lifelong")
def lifelong_command(
    capabilities: Annotated[
        Path, typer.Argument(help="The learnt preset's capabilities (copi learn --preset learnt).")
    ],
    output: Annotated[Path, typer.Option("-o", "--output", help="Results file (SQLite).")],
    family: Annotated[str, typer.Option("--family", help="World family.")] = "indoor",
    worlds: Annotated[int, typer.Option("--worlds", min=1, help="Worlds (lives).")] = 20,
    tasks: Annotated[int, typer.Option("--tasks", min=1, help="Tasks in each life.")] = 50,
    methods: Annotated[
        str | None, typer.Option("--methods", help="Comma-separated methods (default: all).")
    ] = None,
    seed: Annotated[int, typer.Option("--seed", min=0, help="Seed of the worlds and tasks.")] = 0,
    workers: Annotated[int, typer.Option("--workers", min=1, help="Local processes.")] = 2,
    scheduler: Annotated[str | None, typer.Option("--scheduler", help=_SCHEDULER_HELP)] = None,
    maps: Annotated[
        Path | None,
        typer.Option("--maps", help="Directory to save each life's causal map in (.npz)."),
    ] = None,
    from_maps: Annotated[
        Path | None,
        typer.Option("--from-maps", help="Start each causal life from the map saved here "
                     "by an earlier run's --maps (same world, same capabilities)."),
    ] = None,
) -> None:
    """Experiment 3, lifelong: in each world, successive tasks (new goal, obstacles
    moving), the agent keeping its causal map (and grid, and grown contexts) from task to
    task; beside it the mapping baselines, which keep their grids. Resumable (a life at a
    time); writes OUTPUT.md and OUTPUT.png: success and median excess early and late in
    life, paired differences with 95 % intervals, and the goals measured."""
    from copi.experiments.lifelong import LifelongConfig, parse_lifelong_methods, run_lifelong
    from copi.experiments.lifelong_report import lifelong_report_paths, write_lifelong_report
    from copi.world import check_family

    check_family(family)
    chosen = parse_lifelong_methods(methods)
    report_path, figure_path = lifelong_report_paths(output)
    check_outputs(
        {"the results store": (output, "results"), "the report": (report_path, "text"),
         "the report's figure": (figure_path, "png")},
        inputs=[capabilities],
    )  # fmt: skip
    if family == "maps":
        from copi.world import movingai_dir

        movingai_dir()  # refuse a missing data directory before anything is written
    config = LifelongConfig(
        capabilities=str(capabilities), family=family, worlds=worlds, tasks=tasks, seed=seed,
        methods=chosen, maps=None if maps is None else str(maps),
        from_maps=None if from_maps is None else str(from_maps),
    )  # fmt: skip
    config = config.resolved()  # refuses bad inputs (capabilities, maps) before writing
    output.parent.mkdir(parents=True, exist_ok=True)
    _with_progress(
        "lifelong: lives",
        worlds * len(chosen),
        lambda report: run_lifelong(
            config, output, workers=workers, scheduler=scheduler,
            progress=_resuming(report, output, "lives"),
        ),  # fmt: skip
    )
    report = write_lifelong_report(output, report_path)
    out.print(report.read_text(encoding="utf-8").split("![")[0])
    out.print(str(report))


@app.command("report")
def report_command(
    results: Annotated[list[Path], typer.Argument(help="Results files (SQLite).")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Directory for the report.")],
) -> None:
    """Write report.md with the summary table and the paper's Fig. 3 and Fig. 4."""
    from copi.errors import InvalidArgumentError
    from copi.experiments.report import write_report
    from copi.experiments.store import ResultsStore

    for r in results:
        if not r.exists():
            raise InvalidArgumentError(f"{r}: no such results file")
        ResultsStore(r, readonly=True).close()  # refused before anything is written
    check_outputs(
        {"the report's directory": (output, "directory"),
         "the report": (output / "report.md", "text")},
        inputs=results,
    )  # fmt: skip
    path = write_report([str(r) for r in results], output)
    out.print(str(path))


@app.command("reproduce")
def reproduce_command(
    output: Annotated[Path, typer.Option("-o", "--output", help="Directory for everything.")],
    quick: Annotated[
        bool, typer.Option("--quick", help="A small run (100 episodes) to try things out.")
    ] = False,
    workers: Annotated[int, typer.Option("--workers", min=1, help="Local processes.")] = 2,
    seed: Annotated[int, typer.Option("--seed", min=0, help="Seed of learning and episodes.")] = 0,
) -> None:
    """The paper's experiments end to end: learn capabilities (100 worlds x 300 steps),
    Experiment 1 on 1549 dynamic worlds in the faithful mode (4 directions, the paper's
    chain) and the extended mode (16 directions, candidates checked against the live
    reading with a guard of 1.2: the agent radius, an obstacle's step and a margin),
    Experiment 2 (200
    homicidal-chauffeur games, stationary and dynamic, capability and game evaders), the
    benchmark, Experiment 3 (lifelong: 20 indoor worlds of 50 tasks), and the report."""
    from copi.experiments.store import ResultsError

    output.mkdir(parents=True, exist_ok=True)
    try:
        _reproduce(output, quick, workers, seed)
    except ResultsError as exc:
        if "different configuration" not in str(exc):
            raise
        other = "a full" if quick else "a --quick"
        raise CopiError(
            f"{output} holds results of {other} run or of other settings; reproduce into "
            f"another directory (-o), or delete {output} to start over"
        ) from None


def _reproduce(output: Path, quick: bool, workers: int, seed: int) -> None:
    from copi.experiments.benchmark import ensure_capabilities
    from copi.experiments.navigation import NavigationConfig, evaluate
    from copi.experiments.pursuit import PursuitConfig, pursue
    from copi.experiments.report import write_report

    episodes = 100 if quick else 1549
    results = output / "experiment1.sqlite"
    from copi.experiments.methods import PRESETS

    modes = [(name, PRESETS[name].guard) for name in ("faithful", "extended")]
    with progress() as bar:
        for name, guard in modes:
            bar_task = bar.add_task(f"learn ({name})", total=1)
            caps_path = Path(ensure_capabilities(output, {name}, seed=seed)[name])
            bar.update(bar_task, completed=1)
            eval_task = bar.add_task(f"evaluate ({name})", total=episodes)

            def advance(done: int, total: int, task: Any = eval_task) -> None:
                bar.update(task, completed=done)

            config = NavigationConfig(
                capabilities=str(caps_path),
                method=f"copi-{name}",
                worlds=episodes,
                seed=seed,
                guard=guard,
            )
            evaluate(
                config, results, workers=workers,
                progress=_resuming(advance, results, "episodes"),
            )  # fmt: skip
        caps_path = output / "capabilities-extended.npz"
        for kind in ("capability", "game"):
            for dynamic in (False, True):
                game_cfg = PursuitConfig(
                    capabilities=str(caps_path), evader=kind, dynamic=dynamic,
                    games=20 if quick else 200, seed=seed,
                )  # fmt: skip
                game_task = bar.add_task(f"pursuit ({game_cfg.method})", total=game_cfg.games)

                def advance_games(done: int, total: int, task: Any = game_task) -> None:
                    bar.update(task, completed=done)

                pursue(
                    game_cfg, results, workers=workers,
                    progress=_resuming(advance_games, results, "games"),
                )  # fmt: skip
        # The benchmark's quick version: every method on the same episodes of every family.
        from copi.baselines import navground_available
        from copi.experiments.benchmark import BENCHMARK_FAMILIES, BenchmarkConfig, run_benchmark
        from copi.experiments.benchmark_report import write_benchmark_report
        from copi.experiments.methods import method_spec, parse_methods

        chosen = [m for m in parse_methods(None) if method_spec(m[0]).available]
        if not navground_available():
            console.print("copi: navground is not installed: its peers are left out of the "
                          "benchmark (pip install 'copi[peers]')", highlight=False)  # fmt: skip
        bench = BenchmarkConfig(
            methods=tuple(chosen), families=BENCHMARK_FAMILIES, episodes=10 if quick else 30,
            seed=seed, capabilities=ensure_capabilities(
                output, {p for m, _ in chosen if (p := method_spec(m).capabilities)}, seed=seed
            ),
        )  # fmt: skip
        bench_task = bar.add_task(
            "benchmark (quick)", total=bench.episodes * len(chosen) * len(BENCHMARK_FAMILIES)
        )

        def advance_bench(done: int, total: int, task: Any = bench_task) -> None:
            bar.update(task, completed=done)

        bench_out = output / "benchmark.sqlite"
        run_benchmark(
            bench, bench_out, workers=workers,
            progress=_resuming(advance_bench, bench_out, "episodes"),
        )  # fmt: skip
        # Experiment 3, lifelong (quick: 2 worlds of 10 tasks).
        from copi.experiments.lifelong import LifelongConfig, run_lifelong

        life = LifelongConfig(
            ensure_capabilities(output, {"learnt"}, seed=seed)["learnt"], family="indoor",
            worlds=2 if quick else 20, tasks=10 if quick else 50, seed=seed,
        )  # fmt: skip
        life_task = bar.add_task("lifelong (lives)", total=life.worlds * len(life.methods))

        def advance_lives(done: int, total: int, task: Any = life_task) -> None:
            bar.update(task, completed=done)

        run_lifelong(life, results, workers=workers,
                     progress=_resuming(advance_lives, results, "lives"))  # fmt: skip
    write_benchmark_report(output / "benchmark.sqlite", output)
    report = write_report([str(results)], output)
    text = report.read_text(encoding="utf-8")
    out.print(text.split("Runs:")[0])
    if "# Experiment 2" in text:
        out.print("# Experiment 2" + text.split("# Experiment 2")[1].split("![")[0])
    if "# Experiment 3" in text:
        out.print("# Experiment 3" + text.split("# Experiment 3")[1].split("![")[0])
    out.print(str(report))
    out.print(str(output / "benchmark.md"))
