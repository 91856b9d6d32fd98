"""``copi evaluate``, ``benchmark``, ``pursuit``, ``lifelong``, ``report``, ``reproduce``,
``list``: experiments. Thin: parse, check the outputs, call the library, print."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Annotated

import typer

from copi._files import check_outputs, check_writable
from copi.cli._common import (
    Guard,
    Method,
    Preset,
    Scheduler,
    Seed,
    SensorStrategy,
    Workers,
    _with_progress,
    app,
    console,
    out,
    progress,
    seed_option,
)
from copi.errors import CopiError


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


def _load_capabilities(path: Path | None):  # type: ignore[no-untyped-def]
    if path is None:
        return None
    from copi.learning import Capabilities

    return Capabilities.load(path)


def _stored_methods(store: Path) -> set[str]:
    """The methods a benchmark store already holds rows of (none when there is no store, or
    it cannot be read: the run itself then says what is wrong with it)."""
    import sqlite3
    from contextlib import closing

    if not store.is_file():
        return set()
    try:
        with closing(sqlite3.connect(f"file:{store}?mode=ro", uri=True)) as db:
            return {m for (m,) in db.execute("SELECT DISTINCT method FROM episodes")}
    except sqlite3.Error:
        return set()


def _warn_if_mapping_closes(world_file: Path, sensor_strategy: str) -> None:
    """Warn of the worlds whose every way the mapping strategy's grid may close."""
    if sensor_strategy != "mapping":
        return
    from copi.runs import mapping_closes

    for w in mapping_closes(world_file):
        console.print(f"copi: warning: {w}", highlight=False, markup=False)


@app.command("evaluate")
def evaluate_command(
    capabilities: Annotated[
        Path | None,
        typer.Argument(help="Capabilities file (.npz); needed by copi's modes only."),
    ] = None,
    output: Annotated[
        Path | None, typer.Option("-o", "--output", help="Results file (SQLite).")
    ] = None,
    method: Method = None,
    preset: Preset = None,
    worlds: Annotated[int, typer.Option("--worlds", min=1, help="Episodes (paper: 1549).")] = 1549,
    family: Annotated[str, typer.Option("--family", help="World family (copi list).")] = "star",
    sensing: Annotated[str, typer.Option("--sensing", help="sensor, map or oracle.")] = "map",
    world_file: Annotated[
        Path | None, typer.Option("--world-file", help="Run these worlds instead of a family.")
    ] = None,
    seed: Seed = 0,
    workers: Workers = 1,
    scheduler: Scheduler = None,
    max_steps: Annotated[int, typer.Option("--max-steps", min=1, help="Step limit.")] = 1000,
    guard: Guard = None,
    continual: Annotated[
        bool, typer.Option("--continual", help="Learn unfamiliar contexts online.")
    ] = False,
    contact_continues: Annotated[
        bool,
        typer.Option(
            "--contact-continues", help="A contact does not end the episode (older behaviour)."
        ),
    ] = False,
    sensor_strategy: SensorStrategy = "greedy",
) -> None:
    """Experiment 1 (paper §IV): reach goals in dynamic worlds never seen; each episode's
    path is compared with the optimum on the stationary snapshot. Without --method or
    --preset, runs the mode the capabilities file was learnt for. Rerunning the same
    command resumes an interrupted run."""
    from copi.experiments.navigation import NavigationConfig, evaluate
    from copi.methods import resolve
    from copi.reports import summarize, warnings_for
    from copi.results import ResultsStore

    if output is None:
        raise CopiError("evaluate needs -o/--output: the results file to write")
    if sensing not in ("sensor", "map", "oracle"):  # "future" is the clairvoyant bound's
        raise CopiError(f"--sensing must be sensor, map or oracle; got {sensing!r} (level "
                        "future belongs to the clairvoyant bound: copi benchmark --methods "
                        "clairvoyant)")  # fmt: skip
    check_outputs({"the results store": (output, "results")}, inputs=[capabilities, world_file])
    caps = _load_capabilities(capabilities)
    chosen = resolve(preset_name=preset, method=method, capabilities=caps,
                     where=str(capabilities), guard=guard)  # fmt: skip
    if world_file is not None:
        from copi.world import load_worlds

        load_worlds(world_file)  # a bad file is refused before anything is written
        _warn_if_mapping_closes(world_file, sensor_strategy)
    from copi.methods import method_spec

    needs_caps = method_spec(chosen.method).capabilities is not None
    config = NavigationConfig(
        capabilities=str(capabilities) if capabilities is not None and needs_caps else None,
        method=chosen.method, worlds=worlds, family=family, sensing=sensing,  # type: ignore[arg-type]
        world_file=str(world_file) if world_file is not None else None, seed=seed,
        max_steps=max_steps, guard=chosen.params.get("guard"), continual=continual,
        end_on_contact=not contact_continues, sensor_strategy=sensor_strategy,
    )  # fmt: skip
    output.parent.mkdir(parents=True, exist_ok=True)
    run_id = _with_progress(
        f"{chosen.method}: episodes",
        worlds,
        lambda report: evaluate(config, output, workers=workers, scheduler=scheduler,
                                progress=_resuming(report, output, "episodes")),  # fmt: skip
    )
    with ResultsStore(output, readonly=True) as store:
        s = summarize(store.episodes(run_id))
    skipped = (f", {s['skipped']} skipped (no valid task; the first: {s['skip_reason']})"
               if s["skipped"] else "")  # fmt: skip
    where = f"worlds of {world_file.name}" if world_file is not None else family
    if not s["episodes"]:
        out.print(f"{output}: {chosen.method} ({sensing}, {where}): no episode ran{skipped}")
        return
    excess = ("— (no success)" if math.isnan(s["excess_median"])
              else f"{100 * s['excess_median']:.1f} %")  # fmt: skip
    out.print(
        f"{output}: {chosen.method} ({sensing}, {where}): {s['episodes']} episodes{skipped}, "
        f"success {100 * s['success']:.1f} %, collision {100 * s['contact']:.1f} %, timeout "
        f"{100 * s['timeout']:.1f} %, median excess {excess}, "
        f"standing still {100 * s['no_policy']:.1f} %, unfamiliar "
        f"{100 * s['unfamiliar']:.1f} %, {s['decisions_per_s']:,.0f} decisions/s"
    )
    for w in warnings_for(chosen.method, s):
        console.print(f"copi: warning: {w}", highlight=False, markup=False)


@app.command("benchmark")
def benchmark_command(
    output: Annotated[Path, typer.Option("-o", "--output", help="Directory for everything.")],
    quick: Annotated[
        bool, typer.Option("--quick", help="30 episodes per family (a few minutes).")
    ] = False,
    families: Annotated[
        str | None,
        typer.Option("--families", help="Comma-separated families (default: copi's five)."),
    ] = None,
    world_file: Annotated[
        Path | None,
        typer.Option("--world-file", help="Run the episodes in these worlds instead of the "
                     "families (episode k in world k mod n)."),
    ] = None,
    methods: Annotated[
        str | None,
        typer.Option("--methods", help="Comma-separated arms NAME\\[@LEVEL]\\[:STRATEGY] "
                     "(e.g. dwa@sensor:mapping); 'ablations' for the learnt preset's."),
    ] = None,
    against: Annotated[
        str | None,
        typer.Option("--against", help="The method every row is paired against, at the "
                     "row's own level and strategy: a name, no @LEVEL (default: copi-learnt, "
                     "else the first method run)."),
    ] = None,
    episodes: Annotated[
        int | None, typer.Option("--episodes", min=1, help="Episodes per family (1000).")
    ] = None,
    seed: Seed = 0,
    workers: Workers = 2,
    scheduler: Scheduler = None,
    sensor_strategy: SensorStrategy = "greedy",
) -> None:
    """Every method at its sensing levels on the same episodes of every world family (or
    of a world file), into DIR/benchmark.sqlite (resumable), with DIR/benchmark.md: a
    table per family, paired differences against a reference method with 95 % bootstrap
    intervals, and a figure."""
    from copi.experiments.benchmark import BenchmarkConfig, ensure_capabilities, run_benchmark
    from copi.methods import method_spec, parse_methods
    from copi.reports import write_benchmark_report
    from copi.world import BENCHMARK_FAMILIES, check_family, family_inputs, family_spec

    if world_file is not None and families is not None:
        raise CopiError("--world-file and --families do not go together: the world file's "
                        "worlds replace the families")  # fmt: skip
    fams = (
        BENCHMARK_FAMILIES
        if families is None
        else tuple(dict.fromkeys(f.strip() for f in families.split(",") if f.strip()))
    )
    for f in fams:
        check_family(f)
    chosen = parse_methods(methods, strategy=sensor_strategy)
    missing = {r.method for r in chosen if not method_spec(r.method).available()}
    if methods is None and missing:
        for name in sorted(missing):
            console.print(f"copi: {name} is left out: it needs {method_spec(name).missing}",
                          highlight=False)  # fmt: skip
        chosen = [r for r in chosen if r.method not in missing]
    for r in chosen:
        spec = method_spec(r.method)
        if not spec.available():
            raise CopiError(f"{r.method} needs {spec.missing}")
    if against is not None:
        if any(c in against for c in "@:"):
            name = against.split("@")[0].split(":")[0]
            raise CopiError(f"--against takes a method's name (its rows are paired at each "
                            f"level with the reference's row at the same level); got "
                            f"{against!r}: try --against {name}")  # fmt: skip
        method_spec(against)
        stored = _stored_methods(output / "benchmark.sqlite")
        if against not in {r.method for r in chosen} | stored:
            raise CopiError(f"--against {against}: it is not among the methods run "
                            f"({', '.join(dict.fromkeys(r.method for r in chosen))})"
                            + (" nor among those the store holds" if stored else ""))  # fmt: skip
    own = [s.episodes for f in fams if (s := family_spec(f).episode) is not None and s.episodes]
    n = episodes if episodes is not None else (30 if quick else min([1000, *own]))
    check_outputs(
        {"the benchmark's directory": (output, "directory"),
         "the results store": (output / "benchmark.sqlite", "results"),
         "the report": (output / "benchmark.md", "text"),
         "the report's figure": (output / "benchmark_success_excess.png", "png")},
        inputs=[world_file],
    )  # fmt: skip
    if world_file is not None:
        from copi.runs import check_world_file

        check_world_file(world_file)  # a bad file is refused before anything is written
        _warn_if_mapping_closes(world_file, sensor_strategy)
    else:
        for f in fams:
            family_inputs(f)  # a family's missing data is refused before anything is written
    presets = {p for r in chosen if (p := method_spec(r.method).capabilities) is not None}
    config = BenchmarkConfig(
        methods=tuple(chosen), families=tuple(fams), episodes=n, seed=seed,
        world_file=None if world_file is None else str(world_file),
        capabilities={p: str(output / f"capabilities-{p}.npz") for p in presets},
    )  # fmt: skip
    output.mkdir(parents=True, exist_ok=True)
    missing = {p for p in presets if not (output / f"capabilities-{p}.npz").exists()}
    if missing:  # a progress line only for what is learnt (a file there is only checked)
        with progress() as bar:
            task = bar.add_task("learn capabilities", total=len(missing))
            ensure_capabilities(output, presets, seed=seed)
            bar.update(task, completed=len(missing))
    else:
        ensure_capabilities(output, presets, seed=seed)
    results = output / "benchmark.sqlite"
    total = n * len(config.groups) * len(chosen)
    _with_progress(
        "benchmark: episodes",
        total,
        lambda report: run_benchmark(config, results, workers=workers, scheduler=scheduler,
                                     progress=_resuming(report, results, "episodes")),
    )  # fmt: skip
    report = write_benchmark_report(results, output, against=against)
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
        str | None,
        typer.Option("--evader", help="capability (through the capability chain), learnt "
                     "(through the learnt preset's agent), game (the game's direction "
                     "itself) or a registered method of level sensor (e.g. "
                     "ppo-chauffeur-sensor); default: the capabilities' mode."),
    ] = None,
    seed: Annotated[int, seed_option("the games")] = 0,
    horizon: Annotated[int, typer.Option("--horizon", min=1, help="Steps to survive.")] = 300,
    workers: Workers = 1,
    scheduler: Scheduler = None,
    guard: Guard = None,
    preset: Preset = None,
    contact_continues: Annotated[
        bool,
        typer.Option("--contact-continues", help="A contact does not end the game (older rule)."),
    ] = False,
) -> None:
    """Experiment 2 (paper §IV, Fig. 5): the homicidal chauffeur. A faster car with a
    turn radius chases the agent; the agent plays the game's strategy through its
    capabilities (or, with --evader game, directly). Resumable, like evaluate."""
    from copi.experiments.pursuit import PursuitConfig, pursue, resolve_evader
    from copi.reports import summarize_games
    from copi.results import ResultsStore

    check_outputs({"the results store": (output, "results")}, inputs=[capabilities])
    caps = _load_capabilities(capabilities)
    kind, chosen_guard = resolve_evader(caps, str(capabilities), preset=preset, evader=evader,
                                        guard=guard)  # fmt: skip
    config = PursuitConfig(
        capabilities=str(capabilities), evader=kind, dynamic=dynamic, games=games,
        seed=seed, horizon=horizon, guard=chosen_guard, contact_ends=not contact_continues,
    )  # fmt: skip
    output.parent.mkdir(parents=True, exist_ok=True)
    run_id = _with_progress(
        f"{config.method}: games",
        games,
        lambda report: pursue(config, output, workers=workers, scheduler=scheduler,
                              progress=_resuming(report, output, "games")),  # fmt: skip
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
        str | None,
        typer.Option("--methods", help="Comma-separated arms NAME\\[@LEVEL]\\[:STRATEGY] "
                     "(default: all six; a name alone: at sensor, causal for copi's modes, "
                     "mapping for the others)."),
    ] = None,
    seed: Annotated[int, seed_option("the worlds and tasks")] = 0,
    workers: Workers = 2,
    scheduler: Scheduler = None,
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
    from copi.experiments.lifelong import LifelongConfig, run_lifelong
    from copi.methods import parse_lifelong_methods
    from copi.reports import lifelong_report_paths, write_lifelong_report
    from copi.world import check_family, family_inputs

    check_family(family)
    chosen = parse_lifelong_methods(methods)
    report_path, figure_path = lifelong_report_paths(output)
    check_outputs(
        {"the results store": (output, "results"), "the report": (report_path, "text"),
         "the report's figure": (figure_path, "png")}
        | ({} if maps is None else {"the maps' directory": (maps, "directory")}),
        inputs=[capabilities],
    )  # fmt: skip
    family_inputs(family)  # a family's missing data is refused before anything is written
    config = LifelongConfig(
        capabilities=str(capabilities), family=family, worlds=worlds, tasks=tasks, seed=seed,
        methods=chosen, maps=None if maps is None else str(maps),
        from_maps=None if from_maps is None else str(from_maps),
    )  # fmt: skip
    config = config.resolved()  # refuses bad inputs (capabilities, maps) before writing
    if maps is not None:  # made before the store, so that a path that cannot be leaves none
        check_writable(maps, "the maps' directory")
    output.parent.mkdir(parents=True, exist_ok=True)
    _with_progress(
        "lifelong: lives",
        worlds * len(chosen),
        lambda report: run_lifelong(config, output, workers=workers, scheduler=scheduler,
                                    progress=_resuming(report, output, "lives")),  # fmt: skip
    )
    report = write_lifelong_report(output, report_path)
    out.print(report.read_text(encoding="utf-8").split("![")[0])
    out.print(str(report))


@app.command("report")
def report_command(
    results: Annotated[list[Path], typer.Argument(help="Results files (SQLite).")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Directory for the report.")],
) -> None:
    """Write report.md with the summary tables and the paper's Fig. 3, 4 and 5 (and
    Experiment 3's report where the files hold lives)."""
    from copi.errors import InvalidArgumentError
    from copi.reports import write_report
    from copi.results import ResultsStore

    for r in results:
        if not r.exists():
            raise InvalidArgumentError(f"{r}: no such results file")
        with ResultsStore(r, readonly=True) as store:  # refused before anything is written
            kinds = {run.experiment for run in store.runs()}  # (a damaged one's too)
        if kinds == {"crowd"}:
            raise InvalidArgumentError(f"{r} holds crowd runs: copi crowd writes their "
                                       "figure and GIF beside the store (copi report reads "
                                       "Experiments 1 to 3)")  # fmt: skip
    check_outputs(
        {"the report's directory": (output, "directory"),
         "the report": (output / "report.md", "text")},
        inputs=results,
    )  # fmt: skip
    report = write_report([str(r) for r in results], output)
    out.print(str(report.path))


@app.command("reproduce")
def reproduce_command(
    output: Annotated[Path, typer.Option("-o", "--output", help="Directory for everything.")],
    quick: Annotated[
        bool, typer.Option("--quick", help="A small run (100 episodes) to try things out.")
    ] = False,
    workers: Workers = 2,
    seed: Annotated[int, seed_option("learning and episodes")] = 0,
) -> None:
    """The paper's experiments end to end: learn capabilities (100 worlds x 300 steps),
    Experiment 1 on 1549 dynamic worlds in the faithful mode (the paper's chain) and the
    extended mode, Experiment 2 (homicidal-chauffeur games), the benchmark's quick
    version, Experiment 3 (lifelong), and the reports."""
    from copi.experiments import reproduce

    check_outputs(
        {"the directory": (output, "directory"),
         "the report": (output / "report.md", "text"),
         "the benchmark's report": (output / "benchmark.md", "text"),
         "the results": (output / "experiment1.sqlite", "results"),
         "the benchmark's results": (output / "benchmark.sqlite", "results")},
    )  # fmt: skip
    with progress() as bar:

        def task(label: str, total: int) -> Callable[[int, int], None]:
            tid = bar.add_task(label, total=total)
            return lambda done, _total: bar.update(tid, completed=done)

        done = reproduce(output, quick=quick, workers=workers, seed=seed, tasks=task)
    for text in done.summaries.values():
        out.print(text + "\n")
    out.print(str(done.report))
    out.print(str(done.benchmark))


@app.command("list")
def list_command() -> None:
    """The registered methods (what each needs and is), world families and presets,
    copi's and those other packages add through their entry points."""
    from rich.table import Table
    from rich.text import Text

    from copi.methods import PRESETS, method_names, method_replaced, method_spec
    from copi.world import family_names, family_replaced, family_spec

    def about(summary: str, origin: dict[str, str], replaced: bool) -> Text:
        """What it is, and for another package's, where it comes from (user text is never
        read as markup)."""
        text = Text(summary)
        if origin:
            from_ = next(v for k, v in origin.items() if k.endswith("_origin"))
            text.append(f" [from {from_}" + ("; registered over copi's own]" if replaced
                                            else "]"), style="italic")  # fmt: skip
        elif replaced:  # copi's own code, registered over another of copi's names
            text.append(" [registered over copi's own]", style="italic")
        return text

    table = Table("method", "needs", "levels", "extra", "what it is", title="methods")
    for name in method_names():
        spec = method_spec(name)
        extra = "" if spec.requires is None else (
            spec.requires + ("" if spec.available() else " (not installed)"))  # fmt: skip
        table.add_row(Text(name), spec.sensing, ", ".join(spec.levels), extra,
                      about(spec.summary, spec.origin, method_replaced(name)))  # fmt: skip
    out.print(table)
    fams = Table("family", "what it is", title="world families")
    for name in family_names():
        fam = family_spec(name)
        fams.add_row(Text(name), about(fam.summary, fam.origin, family_replaced(name)))
    out.print(fams)
    presets = Table("preset", "method", "what it is", title="presets (copi learn --preset)")
    for name, p in PRESETS.items():
        presets.add_row(name, p.method, p.summary)
    out.print(presets)
