"""``copi world ...`` and ``copi plan``: worlds, pictures, grid maps, reference paths."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from copi._files import check_outputs
from copi.cli._common import app, out, progress, safe_name, world_app
from copi.errors import CopiError
from copi.world import shipped_map, shipped_maps


@world_app.command("sample")
def world_sample(
    output: Annotated[Path, typer.Option("-o", "--output", help="World file to write (JSON).")],
    seed: Annotated[int, typer.Option("--seed", min=0, help="Seed of the draw.")] = 0,
    count: Annotated[int, typer.Option("-n", "--count", min=1, help="Number of worlds.")] = 4,
) -> None:
    """Draw the paper's random worlds (4-12 sided polygons) into a world file.

    World k is drawn from numpy's default_rng(\\[seed, k]).
    """
    # "\[": help text is Rich markup, which would take "[seed, k]" for a style tag
    from copi._validation import check_count
    from copi.world import MAX_WORLDS, random_world, save_worlds

    check_count(count, "--count", MAX_WORLDS)  # what a world file may hold
    check_outputs({"the world file": (output, "json")})
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
    from copi._validation import check_count
    from copi.reports import save_episode_gif, save_episode_png, save_overview_png
    from copi.world import load_worlds, random_walk_episodes

    check_count(steps, "--steps", 10_000)
    if gif:  # every frame of a GIF is held in memory until it is written
        check_count(steps, "--steps with --gif", 2_000)
    worlds = load_worlds(world_file)
    pictures = {
        f"the picture of {w.name}": (output / f"{safe_name(w.name)}{suffix}", suffix[1:])
        for w in worlds
        for suffix in ([".png", ".gif"] if gif else [".png"])
    }
    check_outputs({**pictures, "the overview": (output / "worlds.png", "png")},
                  inputs=[world_file])  # fmt: skip
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
    map_file: Annotated[Path, typer.Argument(
        help="Moving AI .map file, or the name of one copi ships: "
             + ", ".join(shipped_maps()) + ".")],
    output: Annotated[Path, typer.Option("-o", "--output", help="World file to write (JSON).")],
    near: Annotated[
        tuple[int, int] | None,
        typer.Option(
            "--near",
            help="Keep the free region holding this map cell: column x, row y counted "
            "from the top, as in the .map file. Not world coordinates (copi plan's --start), "
            "whose y points up: cell (x, y) is at (x + 0.5, height - y - 0.5). "
            "Default: the largest region.",
        ),
    ] = None,
    passage: Annotated[
        float | None,
        typer.Option(
            "--passage",
            min=0.1,
            help="Scale the map so that its narrow passages are this many agent steps wide "
            "and give it moving obstacles sized to them, for navigation experiments "
            "(e.g. 3). Default: one cell is one step, as in Moving AI's scenarios.",
        ),
    ] = None,
) -> None:
    """Turn a Moving AI grid map into a world: blocked cells become walls and holes."""
    from copi.planning.movingai import map_world, read_map
    from copi.world import save_worlds, scaled_map_world

    map_file = shipped_map(map_file)
    check_outputs({"the world file": (output, "json")}, inputs=[map_file])
    grid = read_map(map_file)
    if passage is not None:
        if near is not None:
            raise CopiError("--near and --passage do not go together (--passage keeps the "
                            "largest region)")  # fmt: skip
        world = scaled_map_world(map_file, passage=passage)
    else:
        world = map_world(grid, near=near)
    output.parent.mkdir(parents=True, exist_ok=True)
    save_worlds([world], output)
    out.print(
        f"{output}: world {world.name!r}, {grid.width} x {grid.height} cells, "
        f"{len(world.boundary)} boundary vertices, {len(world.holes)} holes, "
        f"free area {world.area:.0f}"
    )


_PLAN_ENDS = 3
"""Vertices printed at each end of a long path."""


@app.command("plan")
def plan_command(
    world_file: Annotated[Path, typer.Argument(help="World file (JSON).")],
    start: Annotated[
        tuple[float, float] | None,
        typer.Option("--start", help="Start x y, world coordinates (default: the world's)."),
    ] = None,
    goal: Annotated[
        tuple[float, float] | None,
        typer.Option("--goal", help="Goal x y, world coordinates (default: the world's)."),
    ] = None,
    radius: Annotated[float, typer.Option("--radius", min=0.0, help="Agent radius.")] = 0.0,
    index: Annotated[int, typer.Option("--index", min=0, help="Which world of the file.")] = 0,
    output: Annotated[
        Path | None, typer.Option("-o", "--output", help="Draw the path to this PNG.")
    ] = None,
    vertices: Annotated[
        bool, typer.Option("--vertices", help="Print every vertex of the path.")
    ] = False,
) -> None:
    """Print the length of the shortest path between two points of a world (world
    coordinates, y up), its first and last vertices (all with --vertices), and draw it."""
    from copi.errors import InvalidArgumentError
    from copi.planning import shortest_path
    from copi.world import load_worlds

    if output is not None:
        check_outputs({"the picture": (output, "png")}, inputs=[world_file])
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
        out.print(
            f"no path from ({s[0]:g}, {s[1]:g}) to ({g[0]:g}, {g[1]:g}) in {world.name!r} "
            f"for radius {radius:g}"
        )
        raise typer.Exit(1)
    assert plan.path is not None
    out.print(f"length {plan.length:.6f} ({len(plan.path) - 1} segments)")
    shown = plan.path if vertices or len(plan.path) <= 2 * _PLAN_ENDS + 1 else [
        *plan.path[:_PLAN_ENDS], None, *plan.path[-_PLAN_ENDS:]
    ]  # fmt: skip
    for vertex in shown:
        if vertex is None:
            out.print(f"  ... {len(plan.path) - 2 * _PLAN_ENDS} more vertices (all: --vertices)")
        else:
            out.print(f"  {vertex[0]:.6g} {vertex[1]:.6g}")
    if output is not None:
        from copi.reports import save_plan_png

        output.parent.mkdir(parents=True, exist_ok=True)
        save_plan_png(world, plan.path, output, title=f"{world.name}: length {plan.length:.3f}")
        out.print(str(output))
