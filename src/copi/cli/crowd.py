"""``copi crowd``: many agents among each other. Thin: parse, check the outputs, call the
library, print."""

from __future__ import annotations

import math
import os
import time
from pathlib import Path
from typing import Annotated

import typer

from copi._files import check_outputs
from copi.cli._common import Scheduler, Seed, app, console, out, progress
from copi.errors import CopiError

_CORES = max(1, min(os.cpu_count() or 1, 512))
_MOST_FRAMES = 100
"""Frames of the animation at most (a run of more steps is shown every k-th step)."""


def _names(text: str, what: str) -> list[str]:
    names = list(dict.fromkeys(t.strip() for t in text.split(",") if t.strip()))
    if not names:
        raise CopiError(f"--{what} needs at least one value; got {text!r}")
    return names


def _densities(text: str) -> list[float]:
    values = []
    for t in _names(text, "density"):
        try:
            values.append(float(t))
        except ValueError:
            raise CopiError(f"--density takes numbers (agents per square agent step), "
                            f"comma-separated; got {t!r}") from None  # fmt: skip
    return values


@app.command("crowd")
def crowd_command(
    capabilities: Annotated[
        Path | None,
        typer.Argument(help="Capabilities file (.npz) for copi's methods (default: the "
                       "preset's, learnt into the output directory)."),
    ] = None,
    output: Annotated[
        Path | None, typer.Option("-o", "--output", help="Directory for everything.")
    ] = None,
    agents: Annotated[
        int, typer.Option("--agents", help="Agents in each crowd (at most 100,000).")
    ] = 1000,
    method: Annotated[
        str,
        typer.Option("--method", help="Registered methods driving the agents, comma-separated "
                     "(copi list names them)."),
    ] = "copi-learnt",
    steps: Annotated[
        int, typer.Option("--steps", help="Steps of each run (at most 100,000).")
    ] = 200,
    density: Annotated[
        str,
        typer.Option("--density", help="Agents per square agent step, comma-separated (at "
                     "most 2.7; random placement gives up from about 1.5); the room's side is "
                     "sqrt(agents / density)."),
    ] = "0.1",
    runs: Annotated[
        int, typer.Option("--runs", help="Crowds per method and density (seeds).")
    ] = 1,
    seed: Seed = 0,
    sensing: Annotated[
        str | None,
        typer.Option("--sensing", help="sensor, map or oracle (default: each method's least)."),
    ] = None,
    steady: Annotated[
        bool,
        typer.Option("--steady", help="Agents stay: a new goal on arrival, contacts counted "
                     "(rows still tell each first trip)."),
    ] = False,
    workers: Annotated[
        int,
        typer.Option("--workers", min=1, max=512, help="Local processes: one run shares its "
                     "agents among them, a sweep runs that many runs at once (default: the "
                     "cores)."),
    ] = _CORES,
    scheduler: Scheduler = None,
    gif: Annotated[
        bool, typer.Option("--gif/--no-gif", help="Animate run 0 of the first method.")
    ] = True,
    size: Annotated[
        int, typer.Option("--size", min=120, max=4096, help="Animation width, pixels.")
    ] = 480,
) -> None:
    """N agents among each other in a square room, each driven by a registered method and
    each an obstacle in every other's 32-ray reading; an agent's trip ends at its goal or
    its first contact. Every method at every density, --runs crowds each, into
    DIR/crowd.sqlite (one row per agent; resumable), with DIR/crowd.png (success and time
    to goal against density) and DIR/crowd.gif (run 0 of the first method at the first
    density)."""
    from copi.experiments.benchmark import ensure_capabilities
    from copi.experiments.crowd import CrowdConfig, draw_crowd, run_crowd, run_crowds
    from copi.methods import check_method_capabilities, method_spec
    from copi.reports import check_frames
    from copi.reports.crowd import crowd_summary, save_crowd_figure, save_crowd_gif

    if output is None:
        raise CopiError("crowd needs -o/--output: the directory to write")
    methods = _names(method, "method")
    for m in methods:
        method_spec(m)  # an unknown name, listing the known ones
    presets = sorted({p for m in methods if (p := method_spec(m).capabilities) is not None})
    if capabilities is not None:
        if not presets:
            raise CopiError(f"{', '.join(methods)} run(s) on no capabilities; leave the file out")
        if len(presets) > 1:
            raise CopiError(f"these methods run on {len(presets)} presets "
                            f"({', '.join(presets)}): give no file, and each is learnt into "
                            "the output directory")  # fmt: skip
        caps = {presets[0]: str(capabilities)}
    else:
        caps = {p: str(output / f"capabilities-{p}.npz") for p in presets}
    config = CrowdConfig(agents=agents, methods=tuple(methods),
                         densities=tuple(_densities(density)), runs=runs, steps=steps, seed=seed,
                         sensing=sensing, steady=steady, capabilities=caps)  # fmt: skip
    store, figure, animation = output / "crowd.sqlite", output / "crowd.png", output / "crowd.gif"
    every = max(1, math.ceil(steps / _MOST_FRAMES))
    if gif:
        check_frames(size, steps // every + 1)
    check_outputs(
        {"the crowd's directory": (output, "directory"), "the results store": (store, "results"),
         "the figure": (figure, "png")} | ({"the animation": (animation, "gif")} if gif else {}),
        inputs=[capabilities],
    )  # fmt: skip
    if capabilities is not None:  # a bad file is refused before anything is written
        from copi.learning import Capabilities

        loaded = Capabilities.load(capabilities)
        for m in methods:
            check_method_capabilities(m, loaded, str(capabilities))
    config.check_placement()  # a crowd that cannot be placed, before anything is written
    output.mkdir(parents=True, exist_ok=True)
    if capabilities is None and presets:
        missing = [p for p in presets if not (output / f"capabilities-{p}.npz").exists()]
        if missing:
            console.print(f"copi: learning the {', '.join(missing)} capabilities into {output} "
                          "(about a minute each)", highlight=False)  # fmt: skip
        ensure_capabilities(output, set(presets), seed=0)
    total = len(methods) * len(config.densities) * runs * steps
    t0 = time.perf_counter()
    with progress() as bar:
        task = bar.add_task("crowd: world steps", total=total)
        ids, kept = run_crowds(config, store, workers=workers, scheduler=scheduler,
                               progress=lambda done, _t: bar.update(task, completed=done),
                               record_every=every if gif else 0)  # fmt: skip
    took = time.perf_counter() - t0
    save_crowd_figure(store, figure)
    if gif:
        first = (config.methods[0], config.densities[0])
        if kept is None:  # run elsewhere, or stored before: run 0 again, here, to watch it
            kept = run_crowd(config.resolved(), *first, 0, processes=1 if scheduler else workers,
                             record_every=every)  # fmt: skip
        fresh = draw_crowd(config, first[1], 0)  # the world and agent 0's first goal
        save_crowd_gif(fresh.world, kept.crowd.frames, animation, radius=config.agent_radius,
                       goal=fresh.goals[0], size=size)  # fmt: skip
    for s in crowd_summary(store):
        if (s.method, s.density) not in ids or s.agents != agents:
            continue
        time_text = "—" if math.isnan(s.time_median) else f"{s.time_median:.0f} steps"
        out.print(
            f"{s.method} ({s.sensing}), {s.agents:,} agents at density {s.density:g}, "
            f"{s.runs} run(s): success {100 * s.success:.1f} %, collision "
            f"{100 * s.collision:.1f} %, timeout {100 * s.timeout:.1f} %, median time to goal "
            f"{time_text}, {s.decision_us:.2f} µs a decision", highlight=False,
        )  # fmt: skip
    if kept is not None and kept.seconds > 0:
        out.print(f"run 0 of {config.methods[0]}: {kept.steps} world steps in "
                  f"{kept.seconds:.2f} s ({kept.steps_per_s:,.1f} a second, "
                  f"{kept.processes} process(es))", highlight=False)  # fmt: skip
    out.print(f"{store}, {figure}" + (f", {animation}" if gif else "") + f" ({took:.1f} s)",
              highlight=False)  # fmt: skip
