"""Entry point of the ``copi`` command.

Errors on bad input (a CopiError, or an OSError on a path the user gave) are printed as
one line and exit with code 2, without a traceback; usage errors are typer's (also 2).
"""

from __future__ import annotations

import re
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any, TypeVar

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from copi.errors import CopiError

T = TypeVar("T")

app = typer.Typer(
    name="copi",
    help="Context-based Online Policy Instantiation: worlds, capabilities, experiments.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
world_app = typer.Typer(help="Sample, show and import worlds.", no_args_is_help=True)
app.add_typer(world_app, name="world")

console = Console(stderr=True, soft_wrap=True)
out = Console(soft_wrap=True)


def progress() -> Progress:
    """The progress bar used by long commands (on stderr; silent when not a terminal)."""
    return Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=console,
        transient=True,
    )


def _with_progress(label: str, total: int, run: Callable[[Callable[[int, int], None]], T]) -> T:
    """``run(report)`` under a progress bar that ``report(done, total)`` advances."""
    with progress() as bar:
        task = bar.add_task(label, total=total)
        return run(lambda done, _total: bar.update(task, completed=done))


def safe_name(name: str) -> str:
    """A file name made from a world name."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("._") or "world"


@world_app.command("sample")
def world_sample(
    output: Annotated[Path, typer.Option("-o", "--output", help="World file to write (JSON).")],
    seed: Annotated[int, typer.Option("--seed", min=0, help="Seed of the draw.")] = 0,
    count: Annotated[int, typer.Option("-n", "--count", min=1, help="Number of worlds.")] = 4,
) -> None:
    """Draw the paper's random worlds (4-12 sided polygons) into a world file.

    World k is drawn from numpy's default_rng([seed, k]).
    """
    from copi.world import random_world, save_worlds

    worlds = []
    for k in range(count):
        w = random_world(np.random.default_rng([seed, k]))
        worlds.append(w.replace(name=f"{k:03d}-{len(w.boundary)}gon"))
    output.parent.mkdir(parents=True, exist_ok=True)
    save_worlds(worlds, output)
    table = Table("world", "sides", "area", "width", "height", title=str(output))
    for w in worlds:
        x0, y0, x1, y1 = w.bounds
        table.add_row(
            w.name, str(len(w.boundary)), f"{w.area:.0f}", f"{x1 - x0:.1f}", f"{y1 - y0:.1f}"
        )
    out.print(table)


@world_app.command("show")
def world_show(
    world_file: Annotated[Path, typer.Argument(help="World file (JSON).")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Directory for the pictures.")],
    seed: Annotated[int, typer.Option("--seed", min=0, help="Seed of tasks and walks.")] = 0,
    steps: Annotated[int, typer.Option("--steps", min=1, help="Random-walk steps.")] = 150,
    gif: Annotated[bool, typer.Option("--gif", help="Also animate each walk as a GIF.")] = False,
) -> None:
    """Draw each world with a random-walk episode (PNG per world, plus worlds.png)."""
    from copi.experiments import (
        random_walk_episodes,
        save_episode_gif,
        save_episode_png,
        save_overview_png,
    )
    from copi.world import load_worlds

    worlds = load_worlds(world_file)
    output.mkdir(parents=True, exist_ok=True)
    written = []
    with progress() as bar:
        task = bar.add_task("random walks", total=len(worlds))
        sims = random_walk_episodes(
            worlds, seed=seed, steps=steps, progress=lambda _: bar.advance(task)
        )
        task = bar.add_task("pictures", total=len(sims))
        for sim in sims:
            stem = output / safe_name(sim.world.name)
            written.append(save_episode_png(sim, stem.with_suffix(".png")))
            if gif:
                written.append(save_episode_gif(sim, stem.with_suffix(".gif")))
            bar.advance(task)
        written.append(save_overview_png(sims, output / "worlds.png"))
    for path in written:
        out.print(str(path))


@world_app.command("import-movingai")
def world_import_movingai(
    map_file: Annotated[Path, typer.Argument(help="Moving AI .map file.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="World file to write (JSON).")],
    near: Annotated[
        tuple[int, int] | None,
        typer.Option(
            "--near", help="Keep the free region holding this cell (x y); default: the largest."
        ),
    ] = None,
) -> None:
    """Turn a Moving AI grid map into a world: blocked cells become walls and holes."""
    from copi.planning.movingai import map_world, read_map
    from copi.world import save_worlds

    grid = read_map(map_file)
    world = map_world(grid, near=near)
    output.parent.mkdir(parents=True, exist_ok=True)
    save_worlds([world], output)
    out.print(
        f"{output}: world {world.name!r}, {grid.width} x {grid.height} cells, "
        f"{len(world.boundary)} boundary vertices, {len(world.holes)} holes, "
        f"free area {world.area:.0f}"
    )


@app.command("plan")
def plan_command(
    world_file: Annotated[Path, typer.Argument(help="World file (JSON).")],
    start: Annotated[
        tuple[float, float] | None,
        typer.Option("--start", help="Start x y (default: the world's)."),
    ] = None,
    goal: Annotated[
        tuple[float, float] | None, typer.Option("--goal", help="Goal x y (default: the world's).")
    ] = None,
    radius: Annotated[float, typer.Option("--radius", min=0.0, help="Agent radius.")] = 0.0,
    index: Annotated[int, typer.Option("--index", min=0, help="Which world of the file.")] = 0,
    output: Annotated[
        Path | None, typer.Option("-o", "--output", help="Draw the path to this PNG.")
    ] = None,
) -> None:
    """Print the shortest path between two points of a world (and draw it)."""
    from copi.errors import InvalidArgumentError
    from copi.planning import shortest_path
    from copi.world import load_worlds

    worlds = load_worlds(world_file)
    if index >= len(worlds):
        raise InvalidArgumentError(f"--index {index}: {world_file} holds {len(worlds)} world(s)")
    world = worlds[index]
    s = np.array(start) if start is not None else world.start
    g = np.array(goal) if goal is not None else world.goal
    if s is None or g is None:
        raise InvalidArgumentError(
            f"world {world.name!r} has no {'start' if s is None else 'goal'}; "
            "give --start and --goal"
        )
    plan = shortest_path(world, s, g, radius=radius)
    if not plan.found:
        out.print(f"no path from {tuple(s)} to {tuple(g)} in {world.name!r} for radius {radius:g}")
        raise typer.Exit(1)
    assert plan.path is not None
    out.print(f"length {plan.length:.6f} ({len(plan.path) - 1} segments)")
    for x, y in plan.path:
        out.print(f"  {x:.6g} {y:.6g}")
    if output is not None:
        from copi.experiments.figures import save_plan_png

        output.parent.mkdir(parents=True, exist_ok=True)
        save_plan_png(world, plan.path, output, title=f"{world.name}: length {plan.length:.3f}")
        out.print(str(output))


@app.command("learn")
def learn_command(
    output: Annotated[
        Path, typer.Option("-o", "--output", help="Capabilities file to write (.npz).")
    ],
    worlds: Annotated[int, typer.Option("--worlds", min=1, help="Random worlds explored.")] = 100,
    steps: Annotated[
        int, typer.Option("--steps", min=1, help="Random-walk steps per world.")
    ] = 300,
    seed: Annotated[int, typer.Option("--seed", min=0, help="Seed of exploration and map.")] = 0,
    max_nodes: Annotated[
        int | None, typer.Option("--max-nodes", min=2, help="Cap on the context map's nodes.")
    ] = None,
    epochs: Annotated[
        int, typer.Option("--epochs", min=1, help="GNG passes over the readings.")
    ] = 2,
    landmarks: Annotated[
        int | None, typer.Option("--landmarks", min=1, help="Force this many landmarks (paper: 9).")
    ] = None,
    directions: Annotated[
        int, typer.Option("--directions", help="Policies per template: 4, 8 or 16.")
    ] = 4,
    learner: Annotated[
        str, typer.Option("--learner", help="astar (the paper's) or value-iteration.")
    ] = "astar",
    workers: Annotated[int, typer.Option("--workers", min=1, help="Exploring processes.")] = 1,
) -> None:
    """Learn capabilities offline, without any task (paper §II): explore, grow the
    context map, skeletonise it into landmarks, reduce them by symmetry, learn local
    policies."""
    from copi.learning import LearnParams, learn

    params = LearnParams(
        worlds=worlds,
        steps=steps,
        seed=seed,
        workers=workers,
        max_nodes=max_nodes,
        epochs=epochs,
        landmarks=landmarks,
        directions=directions,
        learner=learner,
    )
    output.parent.mkdir(parents=True, exist_ok=True)
    with progress() as bar:
        tasks: dict[str, object] = {}

        def report(stage: str, done: int, total: int) -> None:
            if stage not in tasks:
                tasks[stage] = bar.add_task(stage, total=total)
            bar.update(tasks[stage], completed=done)  # type: ignore[arg-type]

        caps = learn(params, progress=report)
    caps.save(output)
    _print_stages(caps.stats["stages"])
    out.print(f"{output}: {_summary_line(caps.summary())}")


def _summary_line(s: dict[str, object]) -> str:
    return (
        f"{s['nodes']} nodes -> {s['landmarks']} landmarks -> {s['reduced_landmarks']} reduced "
        f"landmarks -> {s['policies']} policies ({s['directions']} directions, {s['learner']})"
    )


def _print_stages(stages: list[dict[str, object]]) -> None:
    table = Table("stage", "result", "seconds", title="capability learning")
    for st in stages:
        result = ", ".join(
            f"{k.replace('_', ' ')} {v:.4g}"
            if isinstance(v, float)
            else f"{k.replace('_', ' ')} {v}"
            for k, v in st.items()
            if k not in ("stage", "seconds")
        )
        table.add_row(str(st["stage"]), result, f"{float(st['seconds']):.2f}")  # type: ignore[arg-type]
    out.print(table)


@app.command("inspect")
def inspect_command(
    capabilities: Annotated[Path, typer.Argument(help="Capabilities file (.npz).")],
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON instead of tables.")] = False,
) -> None:
    """Describe a capabilities file: what each stage produced, and how it was learnt."""
    import json

    from copi.learning import Capabilities

    caps = Capabilities.load(capabilities)
    templates: list[dict[str, Any]] = [
        {
            "template": t,
            "landmark": int(caps.reduction.templates[t]),
            "landmarks": int((caps.reduction.template_of == t).sum()),
            "policies": [
                caps.policies.names[d]
                for d in range(len(caps.policies.names))
                if caps.policies.passable[t, d]
            ],
        }
        for t in range(len(caps.reduction.templates))
    ]
    info = {
        "file": str(capabilities),
        "summary": caps.summary(),
        "operators": [o.name for o in caps.group.operators],
        "group_words": caps.group.words,
        "templates": templates,
        "params": caps.params,
        "stats": caps.stats,
    }
    if as_json:
        print(json.dumps(info, indent=1))
        return
    out.print(f"{capabilities}: {_summary_line(caps.summary())}")
    _print_stages(caps.stats.get("stages", []))
    table = Table("template", "from landmark", "landmarks", "policies", title="templates")
    for t in templates:
        table.add_row(
            str(t["template"]), str(t["landmark"]), str(t["landmarks"]), " ".join(t["policies"])
        )
    out.print(table)
    out.print("parameters: " + ", ".join(f"{k}={v}" for k, v in caps.params.items()))


@app.command("figures")
def figures_command(
    capabilities: Annotated[Path, typer.Argument(help="Capabilities file (.npz).")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Directory for the figures.")],
) -> None:
    """Draw the paper's Fig. 1 panels (context map, H(k), landmarks and templates,
    policies) and Fig. 2 (the permutation automaton of the toy domain)."""
    from copi.experiments.capability_figures import save_capability_figures
    from copi.learning import Capabilities

    caps = Capabilities.load(capabilities)
    for path in save_capability_figures(caps, output):
        out.print(str(path))


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
        str, typer.Option("--method", help="copi-faithful, copi-extended or a baseline.")
    ] = "copi-faithful",
    worlds: Annotated[int, typer.Option("--worlds", min=1, help="Episodes (paper: 1549).")] = 1549,
    family: Annotated[str, typer.Option("--family", help="World family.")] = "star",
    sensing: Annotated[
        str, typer.Option("--sensing", help="sensor, map or oracle.")
    ] = "map",
    world_file: Annotated[
        Path | None, typer.Option("--world-file", help="Run these worlds instead of a family.")
    ] = None,
    seed: Annotated[int, typer.Option("--seed", min=0, help="Seed of the episodes.")] = 0,
    workers: Annotated[int, typer.Option("--workers", min=1, help="Local processes.")] = 1,
    scheduler: Annotated[
        str | None, typer.Option("--scheduler", help="Dask scheduler tcp://HOST:PORT instead.")
    ] = None,
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
) -> None:
    """Experiment 1 (paper §IV): reach goals in dynamic worlds never seen; each episode's
    path is compared with the optimum on the stationary snapshot. Rerunning the same
    command resumes an interrupted run."""
    from copi.experiments.navigation import NavigationConfig, evaluate
    from copi.experiments.report import summarize
    from copi.experiments.store import ResultsStore

    if output is None:
        raise CopiError("evaluate needs -o/--output: the results file to write")
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
    )
    output.parent.mkdir(parents=True, exist_ok=True)
    run_id = _with_progress(
        f"{method}: episodes",
        worlds,
        lambda report: evaluate(
            config, output, workers=workers, scheduler=scheduler, progress=report
        ),
    )
    with ResultsStore(output) as store:
        s = summarize(store.episodes(run_id))
    out.print(
        f"{output}: {method} ({sensing}): {s['episodes']} episodes, success "
        f"{100 * s['success']:.1f} %, collision {100 * s['contact']:.1f} %, timeout "
        f"{100 * s['timeout']:.1f} %, median excess {100 * s['excess_median']:.1f} %, "
        f"{s['decisions_per_s']:,.0f} decisions/s"
    )


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
    scheduler: Annotated[
        str | None, typer.Option("--scheduler", help="Dask scheduler tcp://HOST:PORT instead.")
    ] = None,
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
    from copi.world import check_family

    fams = BENCHMARK_FAMILIES if families is None else tuple(
        f.strip() for f in families.split(",") if f.strip()
    )
    for f in fams:
        check_family(f)
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
        methods=tuple(chosen), families=tuple(fams), episodes=n, seed=seed, capabilities=caps
    )
    results = output / "benchmark.sqlite"
    total = n * len(fams) * len(chosen)
    _with_progress(
        "benchmark: episodes",
        total,
        lambda report: run_benchmark(
            config, results, workers=workers, scheduler=scheduler, progress=report
        ),
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
        str, typer.Option("--evader", help="capability (through the capabilities) or game.")
    ] = "capability",
    seed: Annotated[int, typer.Option("--seed", min=0, help="Seed of the games.")] = 0,
    horizon: Annotated[int, typer.Option("--horizon", min=1, help="Steps to survive.")] = 300,
    workers: Annotated[int, typer.Option("--workers", min=1, help="Local processes.")] = 1,
    scheduler: Annotated[
        str | None, typer.Option("--scheduler", help="Dask scheduler tcp://HOST:PORT instead.")
    ] = None,
    guard: Annotated[
        float, typer.Option("--guard", min=0.0, help="The capability evader's guard.")
    ] = 1.2,
    contact_continues: Annotated[
        bool,
        typer.Option("--contact-continues", help="A contact does not end the game (older rule)."),
    ] = False,
) -> None:
    """Experiment 2 (paper §IV, Fig. 5): the homicidal chauffeur. A faster car with a
    turn radius chases the agent; the agent plays the game's strategy through its
    capabilities (or, with --evader game, directly). Resumable, like evaluate."""
    from copi.experiments.pursuit import PursuitConfig, pursue
    from copi.experiments.report import summarize_games
    from copi.experiments.store import ResultsStore

    config = PursuitConfig(
        capabilities=str(capabilities), evader=evader, dynamic=dynamic, games=games,
        seed=seed, horizon=horizon, guard=guard, contact_ends=not contact_continues,
    )  # fmt: skip
    output.parent.mkdir(parents=True, exist_ok=True)
    run_id = _with_progress(
        f"{config.method}: games",
        games,
        lambda report: pursue(
            config, output, workers=workers, scheduler=scheduler, progress=report
        ),
    )
    with ResultsStore(output) as store:
        s = summarize_games(store.games(run_id))
    out.print(
        f"{output}: {config.method}: {s['games']} games, capture {100 * s['capture']:.1f} %, "
        f"collision {100 * s['collision']:.1f} %, "
        f"mean survival {s['survival_mean']:.1f} steps, games with contact "
        f"{100 * s['contact_games']:.1f} %"
    )


@app.command("report")
def report_command(
    results: Annotated[list[Path], typer.Argument(help="Results files (SQLite).")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Directory for the report.")],
) -> None:
    """Write report.md with the summary table and the paper's Fig. 3 and Fig. 4."""
    from copi.errors import InvalidArgumentError
    from copi.experiments.report import write_report

    for r in results:
        if not r.exists():
            raise InvalidArgumentError(f"{r}: no such results file")
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
    homicidal-chauffeur games, stationary and dynamic, capability and game evaders), and
    the report."""
    from copi.experiments.navigation import NavigationConfig, evaluate
    from copi.experiments.pursuit import PursuitConfig, pursue
    from copi.experiments.report import write_report
    from copi.learning import LearnParams, learn

    output.mkdir(parents=True, exist_ok=True)
    episodes = 100 if quick else 1549
    results = output / "experiment1.sqlite"
    modes = [("faithful", 4, 0.0), ("extended", 16, 1.2)]
    with progress() as bar:
        for name, directions, guard in modes:
            caps_path = output / f"capabilities-{name}.npz"
            if not caps_path.exists():
                bar_task = bar.add_task(f"learn ({name})", total=1)
                learn(LearnParams(seed=seed, directions=directions)).save(caps_path)
                bar.update(bar_task, completed=1)
            eval_task = bar.add_task(f"evaluate ({name})", total=episodes)

            def advance(done: int, total: int, task: Any = eval_task) -> None:
                bar.update(task, completed=done)

            config = NavigationConfig(
                capabilities=str(caps_path), method=f"copi-{name}", worlds=episodes, seed=seed,
                guard=guard,
            )
            evaluate(config, results, workers=workers, progress=advance)
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

                pursue(game_cfg, results, workers=workers, progress=advance_games)
        # The benchmark's quick version: every method on the same episodes of every family.
        from copi.baselines import navground_available
        from copi.experiments.benchmark import (
            BENCHMARK_FAMILIES,
            BenchmarkConfig,
            ensure_capabilities,
            run_benchmark,
        )
        from copi.experiments.benchmark_report import write_benchmark_report
        from copi.experiments.methods import method_spec, parse_methods

        chosen = [m for m in parse_methods(None) if method_spec(m[0]).available]
        if not navground_available():
            console.print("copi: navground is not installed: its peers are left out of the "
                          "benchmark (pip install 'copi[peers]')", highlight=False)  # fmt: skip
        bench = BenchmarkConfig(
            methods=tuple(chosen), families=BENCHMARK_FAMILIES, episodes=10 if quick else 30,
            seed=seed, capabilities=ensure_capabilities(output, {"faithful", "extended"},
                                                        seed=seed),
        )  # fmt: skip
        bench_task = bar.add_task(
            "benchmark (quick)", total=bench.episodes * len(chosen) * len(BENCHMARK_FAMILIES)
        )

        def advance_bench(done: int, total: int, task: Any = bench_task) -> None:
            bar.update(task, completed=done)

        run_benchmark(bench, output / "benchmark.sqlite", workers=workers, progress=advance_bench)
    write_benchmark_report(output / "benchmark.sqlite", output)
    report = write_report([str(results)], output)
    text = report.read_text(encoding="utf-8")
    out.print(text.split("Runs:")[0])
    if "# Experiment 2" in text:
        out.print("# Experiment 2" + text.split("# Experiment 2")[1].split("![")[0])
    out.print(str(report))
    out.print(str(output / "benchmark.md"))


def main(argv: list[str] | None = None) -> None:
    """Run the command line; bad input ends with one line on stderr and exit code 2."""
    try:
        app(args=argv, prog_name="copi")
    except CopiError as exc:
        console.print(f"[red]copi: error:[/red] {exc}", highlight=False, markup=True)
        sys.exit(2)
    except OSError as exc:
        where = f" {exc.filename}" if exc.filename else ""
        console.print(f"[red]copi: error:[/red]{where}: {exc.strerror or exc}", highlight=False)
        sys.exit(2)
    except KeyboardInterrupt:
        console.print("copi: interrupted")
        sys.exit(130)


if __name__ == "__main__":  # pragma: no cover
    main()
