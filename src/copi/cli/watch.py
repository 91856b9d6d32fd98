"""``copi watch``: one episode of any method, as an animation with its decisions."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from copi._files import check_outputs
from copi.cli._common import app, compiling_notice, out


@app.command("watch")
def watch_command(
    capabilities: Annotated[
        Path | None,
        typer.Argument(help="Capabilities file (.npz); needed by copi's methods only."),
    ] = None,
    output: Annotated[
        Path,
        typer.Option("-o", "--output", help="Animation to write: .gif, .mp4 (ffmpeg) or .png."),
    ] = Path("episode.gif"),
    method: Annotated[
        str | None,
        typer.Option(
            "--method",
            help="copi-faithful, copi-extended or a baseline (default: the copi mode that "
            "fits the capabilities' directions).",
        ),
    ] = None,
    world_file: Annotated[
        Path | None, typer.Option("--world-file", help="Draw the episode in these worlds.")
    ] = None,
    family: Annotated[str, typer.Option("--family", help="World family.")] = "star",
    episode: Annotated[
        int, typer.Option("--episode", min=0, help="Which episode (as copi evaluate's).")
    ] = 0,
    seed: Annotated[int, typer.Option("--seed", min=0, help="Seed of the episodes.")] = 0,
    sensing: Annotated[
        str | None,
        typer.Option("--sensing", help="sensor, map or oracle (default: map, or what it needs)."),
    ] = None,
    max_steps: Annotated[int, typer.Option("--max-steps", min=1, help="Step limit.")] = 1000,
    fps: Annotated[int, typer.Option("--fps", min=1, help="Frames per second.")] = 10,
    size: Annotated[int, typer.Option("--size", min=120, help="Picture width, pixels.")] = 480,
) -> None:
    """Watch one episode: the rays, the obstacles moving, and at every step the policy
    the method chose (copi: node, landmark, template and symmetry, policy among the
    template's), then the outcome. Episode K is the one copi evaluate runs as K."""
    from copi.errors import InvalidArgumentError
    from copi.experiments.methods import method_spec
    from copi.experiments.watch import FORMATS, save_watch, watch_episode
    from copi.learning import Capabilities
    from copi.world import check_family, load_worlds

    if output.suffix.lower() not in FORMATS:
        raise InvalidArgumentError(f"-o must end in {', '.join(FORMATS)}; got {output.name!r}")
    check_outputs(
        {"the animation": (output, output.suffix.lower().lstrip("."))},
        inputs=[capabilities, world_file],
    )
    caps = Capabilities.load(capabilities) if capabilities is not None else None
    if method is None:
        if caps is None:
            raise InvalidArgumentError(
                "give a capabilities file (for copi's methods) or --method NAME (a baseline)"
            )
        method = "copi-faithful" if len(caps.policies.names) <= 4 else "copi-extended"
    spec = method_spec(method)
    if spec.capabilities is not None and caps is None:
        raise InvalidArgumentError(f"{method} needs a capabilities file")
    if world_file is not None:
        load_worlds(world_file)  # a bad file is refused before anything runs
    else:
        check_family(family)
    compiling_notice()
    watched = watch_episode(
        method, caps, family=family, world_file=world_file, episode=episode, seed=seed,
        sensing=sensing, max_steps=max_steps,
    )  # fmt: skip
    output.parent.mkdir(parents=True, exist_ok=True)
    save_watch(watched, output, fps=fps, size=size)
    o = watched.outcome
    out.print(
        f"{output}: {method} ({watched.sensing}) in {watched.sim.world.name}: {o.outcome} "
        f"after {o.steps} steps, path {o.path_length:.1f}; "
        f"{1 if output.suffix.lower() == '.png' else watched.n_frames} frame(s)"
    )
