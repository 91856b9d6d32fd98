"""``copi learn``, ``copi inspect``, ``copi figures``: capabilities (paper §II)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table

from copi._files import check_outputs
from copi.cli._common import app, out, progress, seed_option


@app.command("learn")
def learn_command(
    output: Annotated[
        Path, typer.Option("-o", "--output", help="Capabilities file to write (.npz).")
    ],
    worlds: Annotated[int, typer.Option("--worlds", min=1, help="Random worlds explored.")] = 100,
    steps: Annotated[
        int, typer.Option("--steps", min=1, help="Random-walk steps per world.")
    ] = 300,
    seed: Annotated[int, seed_option("the exploration and the map")] = 0,
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
        int | None,
        typer.Option("--directions", help="Policies per template: 4, 8 or 16 (default: the "
                     "preset's)."),
    ] = None,
    learner: Annotated[
        str, typer.Option("--learner", help="astar (the paper's) or value-iteration.")
    ] = "astar",
    family: Annotated[
        str,
        typer.Option("--family", help="World family explored (star: the paper's worlds)."),
    ] = "star",
    workers: Annotated[int, typer.Option("--workers", min=1, help="Exploring processes.")] = 1,
    preset: Annotated[
        str | None,
        typer.Option(
            "--preset",
            help="Learn for a mode: learnt (the default: 16 directions and safety priors), "
            "faithful (the paper's: 4 directions), extended (16), learnt-motion, predictive "
            "(a model of what moves, for copi-predictive).",
        ),
    ] = None,
    probe_worlds: Annotated[
        int,
        typer.Option("--probe-worlds", min=1, help="Worlds of the probing walks of the safety "
                     "priors (learnt presets)."),
    ] = 60,
    probe_steps: Annotated[
        int,
        typer.Option("--probe-steps", min=1, help="Random-walk steps per probing world "
                     "(every second state is probed)."),
    ] = 150,
    probe_families: Annotated[
        str,
        typer.Option("--probe-families", help="Comma-separated families of the probing "
                     "walks (task-free)."),
    ] = "star,crowd,polygon,indoor",
    probe_label: Annotated[
        str,
        typer.Option("--probe-label", help="How a probe is judged safe: hold (its move held "
                     "3 steps without contact) or escape (taken once, leaving a clear "
                     "second move: the model-oracle's check)."),
    ] = "hold",
    safety_static: Annotated[
        bool,
        typer.Option("--safety-static", help="The safety networks learn with the static "
                     "map's reading (what a map-level agent is handed), so that they tell "
                     "what moves from walls."),
    ] = False,
    motion: Annotated[
        bool,
        typer.Option(
            "--motion",
            help="Contexts that see motion: the reading and its change (as --preset "
            "learnt-motion).",
        ),
    ] = False,
) -> None:
    """Learn capabilities offline, without any task (paper §II): explore, grow the
    context map, skeletonise it into landmarks, reduce them by symmetry, learn local
    policies. Without --preset (or --directions), learns the default preset, learnt;
    --preset faithful learns the paper's. A learnt preset also probes task-free walks for
    its safety priors (--probe-*); the simulated steps of it all are printed."""
    from copi.errors import InvalidArgumentError
    from copi.learning import LearnParams, learn, simulated_steps
    from copi.methods import DEFAULT_PRESET
    from copi.methods import preset as get_preset

    if preset is None and directions is None and not motion:
        preset = DEFAULT_PRESET
    if preset is not None:
        want = get_preset(preset).learn.directions
        if directions is not None and directions != want:
            raise InvalidArgumentError(
                f"--directions {directions} contradicts --preset {preset} ({want} directions)"
            )
        directions = want
    safety = preset is not None and get_preset(preset).learn.safety
    if motion and preset != "learnt-motion":
        # only the learnt preset's agent recognises such contexts, and it needs the
        # safety priors that preset learns
        raise InvalidArgumentError(
            f"--motion needs --preset learnt-motion (got {preset or 'no preset'}): only the "
            "learnt preset's agent recognises contexts that see motion"
        )
    predict = False
    if preset is not None:  # what the preset learns beyond the options
        chosen = get_preset(preset).learn
        motion = chosen.motion
        predict = chosen.predict
        safety_static = safety_static or chosen.safety_static
    params = LearnParams(
        worlds=worlds,
        steps=steps,
        seed=seed,
        workers=workers,
        max_nodes=max_nodes,
        epochs=epochs,
        landmarks=landmarks,
        directions=4 if directions is None else directions,
        learner=learner,
        family=family,
        safety=safety,
        motion=motion,
        probe_worlds=probe_worlds,
        probe_steps=probe_steps,
        probe_families=probe_families,
        probe_label=probe_label,
        safety_static=safety_static,
        predict=predict,
    )
    check_outputs({"the capabilities file": (output, "capabilities")})
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
    cost = simulated_steps(params)
    out.print(f"learning samples: {cost['total']:,} simulated steps ({cost['exploration']:,} "
              f"exploring, {cost['walks']:,} walking to probe, at most {cost['probes']:,} "
              "probing)")  # fmt: skip


def _summary_line(s: dict[str, object]) -> str:
    return (
        f"{s['nodes']} nodes ({s['contexts']}) -> {s['landmarks']} landmarks -> "
        f"{s['reduced_landmarks']} reduced landmarks -> {s['policies']} policies "
        f"({s['directions']} directions, {s['learner']})"
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
        seconds = st.get("seconds")  # not stored in files: the same content, the same bytes
        shown = f"{float(seconds):.2f}" if isinstance(seconds, int | float) else "-"
        table.add_row(str(st["stage"]), result, shown)
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
    from copi.learning import Capabilities
    from copi.reports import save_capability_figures

    caps = Capabilities.load(capabilities)
    for path in save_capability_figures(caps, output):
        out.print(str(path))
