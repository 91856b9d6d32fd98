"""``copi rl train``: a local policy learnt by deep RL (PPO) on copi's episodes."""

from __future__ import annotations

import shlex
import sys
from pathlib import Path
from typing import Annotated

import typer

from copi._files import check_outputs, check_writable
from copi.cli._common import app, out, progress, seed_option

rl_app = typer.Typer(help="Deep RL as copi's learning peer: train PPO policies.",
                     no_args_is_help=True)  # fmt: skip
app.add_typer(rl_app, name="rl")


@rl_app.command("train")
def train_command(
    output: Annotated[Path, typer.Option("-o", "--output", help="Policy file to write (.npz).")],
    families: Annotated[
        str, typer.Option("--families", help="Comma-separated families of the episodes.")
    ] = "star,polygon,indoor,maps,crowd",
    levels: Annotated[
        str, typer.Option("--levels", help="Sensing levels of the episodes: sensor, map.")
    ] = "sensor,map",
    task: Annotated[
        str, typer.Option("--task", help="navigation, or chauffeur (the game's evader).")
    ] = "navigation",
    steps: Annotated[int, typer.Option("--steps", min=1, help="Environment steps.")] = 2_000_000,
    seed: Annotated[int, seed_option("the network and the episodes' order")] = 0,
    envs: Annotated[int, typer.Option("--envs", min=1, max=256, help="Vectorised envs.")] = 8,
    learning_rate: Annotated[float, typer.Option("--lr", min=0.0, max=1.0,
                                                 help="PPO's learning rate.")] = 1e-3,
    ent_coef: Annotated[float, typer.Option("--ent", min=0.0, max=1.0)] = 0.0,
    log_std: Annotated[float, typer.Option("--log-std", min=-5.0, max=2.0,
                                           help="Initial log std of the actions.")] = -1.0,
    net: Annotated[str, typer.Option("--net", help="Hidden layer widths, e.g. 64,64.")] = "64,64",
    checkpoints: Annotated[
        Path | None,
        typer.Option("--checkpoints", help="Directory of checkpoints; a rerun resumes there."),
    ] = None,
    validate_every: Annotated[
        int, typer.Option("--validate-every", min=1000, help="Steps between validations.")
    ] = 100_000,
) -> None:
    """Train PPO (Stable-Baselines3) for a local policy in copi's factorisation: it sees
    the ranges, their change and its level's global direction, and acts with a velocity.
    Writes the policy (numpy weights, run by the methods ppo and ppo-guard), its
    learning curve on fixed validation episodes (.json, .png). Needs the extra rl."""
    from copi.errors import InvalidArgumentError
    from copi.rl import Reward, TrainConfig, check_apart, train

    check_outputs({"the policy": (output, "policy"),
                   "the learning curve": (output.with_suffix(".json"), "json"),
                   "the learning curve's figure": (output.with_suffix(".png"), "png")}
                  | ({} if checkpoints is None
                     else {"the checkpoints' directory": (checkpoints, "directory")}))  # fmt: skip
    check_apart(output, checkpoints)
    try:
        widths = tuple(int(w) for w in net.split(","))
    except ValueError:
        raise InvalidArgumentError(f"--net must be comma-separated ints; got {net!r}") from None
    config = TrainConfig(
        families=tuple(f.strip() for f in families.split(",") if f.strip()),
        levels=tuple(lv.strip() for lv in levels.split(",") if lv.strip()), task=task,
        steps=steps, seed=seed, envs=envs, learning_rate=learning_rate, ent_coef=ent_coef,
        log_std=log_std,
        net=widths, reward=Reward(),
    )  # fmt: skip
    check_writable(output.parent, "the policy")  # before hours of training, not after
    if checkpoints is not None:
        check_writable(checkpoints, "checkpoints")
    command = "copi " + " ".join(shlex.quote(a) for a in sys.argv[1:])
    if config.planned_steps != steps:
        out.print(f"training {config.planned_steps:,} steps: PPO trains in whole rollouts of "
                  f"{config.envs} envs x {config.n_steps} steps (asked for {steps:,})")
    with progress() as bar:
        tid = bar.add_task("rl: environment steps", total=config.planned_steps)
        summary = train(config, output, checkpoints=checkpoints, validate_every=validate_every,
                        progress=lambda done, total: bar.update(tid, completed=done),
                        resumed=lambda done: out.print(
                            f"resuming at {done:,} of {config.planned_steps:,} steps from "
                            f"{checkpoints}"),
                        command=command)  # fmt: skip
    last = summary["curve"][-1]
    out.print(
        f"{output}: PPO, {summary['steps']:,} steps in {summary['seconds']:.0f} s "
        f"({summary['steps_per_second']:,.0f} steps/s), validation success "
        f"{100 * last['success']:.1f} %"
    )
