"""``copi watch``: one episode of any method, as an animation with its decisions."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from copi._files import check_outputs
from copi.cli._common import (
    Guard,
    Method,
    Preset,
    Seed,
    SensorStrategy,
    app,
    compiling_notice,
    out,
)


@app.command("watch")
def watch_command(
    capabilities: Annotated[
        Path | None,
        typer.Argument(help="Capabilities file (.npz); needed by copi's modes only."),
    ] = None,
    output: Annotated[
        Path,
        typer.Option("-o", "--output", help="Animation to write: .gif, .mp4 (ffmpeg) or .png."),
    ] = Path("episode.gif"),
    method: Method = None,
    preset: Preset = None,
    world_file: Annotated[
        Path | None, typer.Option("--world-file", help="Draw the episode in these worlds.")
    ] = None,
    family: Annotated[str, typer.Option("--family", help="World family (copi list).")] = "star",
    episode: Annotated[
        int, typer.Option("--episode", min=0, help="Which episode (as copi evaluate's).")
    ] = 0,
    seed: Seed = 0,
    sensing: Annotated[
        str | None,
        typer.Option("--sensing", help="sensor, map or oracle (default: map, or what it needs)."),
    ] = None,
    sensor_strategy: SensorStrategy = "greedy",
    guard: Guard = None,
    max_steps: Annotated[int, typer.Option("--max-steps", min=1, help="Step limit.")] = 1000,
    fps: Annotated[int, typer.Option("--fps", min=1, max=100, help="Frames per second.")] = 10,
    size: Annotated[
        int, typer.Option("--size", min=120, max=4096, help="Picture width, pixels.")
    ] = 480,
) -> None:
    """Watch one episode: the rays, the obstacles moving, the global direction, and at
    every step the move the method chose among its candidates (copi: node, landmark,
    template and symmetry, each candidate's score), then the outcome. Episode K is the
    one copi evaluate runs as K; without --method or --preset, the mode the capabilities
    file was learnt for."""
    from copi.errors import InvalidArgumentError
    from copi.learning import Capabilities
    from copi.methods import resolve
    from copi.reports import FORMATS, check_frames, save_watch, watch_episode
    from copi.world import check_family, load_worlds

    if output.suffix.lower() not in FORMATS:
        raise InvalidArgumentError(f"-o must end in {', '.join(FORMATS)}; got {output.name!r}")
    if output.suffix.lower() != ".png":
        check_frames(size, max_steps + 1)  # before the episode runs
    check_outputs(
        {"the animation": (output, output.suffix.lower().lstrip("."))},
        inputs=[capabilities, world_file],
    )
    caps = Capabilities.load(capabilities) if capabilities is not None else None
    chosen = resolve(preset_name=preset, method=method, capabilities=caps,
                     where=str(capabilities), guard=guard)  # fmt: skip
    if world_file is not None:
        load_worlds(world_file)  # a bad file is refused before anything runs
    else:
        check_family(family)
    compiling_notice()
    watched = watch_episode(
        chosen.method, caps, family=family, world_file=world_file, episode=episode, seed=seed,
        sensing=sensing,  # type: ignore[arg-type]  # checked by watch_episode
        max_steps=max_steps, strategy=sensor_strategy, params=chosen.params,
    )  # fmt: skip
    output.parent.mkdir(parents=True, exist_ok=True)
    save_watch(watched, output, fps=fps, size=size)
    o = watched.outcome
    out.print(
        f"{output}: {chosen.method} ({watched.sensing}) in {watched.sim.world.name}: "
        f"{o.outcome} after {o.steps} steps, path {o.path_length:.1f}; "
        f"{1 if output.suffix.lower() == '.png' else watched.n_frames} frame(s)"
    )
