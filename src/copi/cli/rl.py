"""``copi rl train``: a local policy learnt by deep RL (PPO or SAC) on copi's episodes."""

from __future__ import annotations

import shlex
import sys
from pathlib import Path
from typing import Annotated, Any

import typer

from copi._files import check_outputs, check_writable
from copi.cli._common import app, out, progress, seed_option

rl_app = typer.Typer(help="Deep RL as copi's learning peer: train PPO or SAC policies, or "
                     "CrowdNav's SARL.",
                     no_args_is_help=True)  # fmt: skip
app.add_typer(rl_app, name="rl")


@rl_app.command("train")
def train_command(
    output: Annotated[Path, typer.Option("-o", "--output", help="Policy file to write (.npz).")],
    families: Annotated[
        str, typer.Option("--families", help="Comma-separated families of the episodes.")
    ] = "star,polygon,indoor,maps,crowd",
    levels: Annotated[
        str, typer.Option("--levels", help="Sensing level of the episodes: sensor or map "
                          "(one for copi-local-v3; copi-local-v2 may mix them).")
    ] = "map",
    task: Annotated[
        str, typer.Option("--task", help="navigation, or chauffeur (the game's evader).")
    ] = "navigation",
    algo: Annotated[
        str, typer.Option("--algo", help="ppo (on-policy), sac (off-policy, a replay "
                          "buffer; its own entropy target), or clone (no RL: a classifier of "
                          "--imitate's moves, DAgger, scoring a step along each ray and "
                          "standing still).")
    ] = "ppo",
    steps: Annotated[int, typer.Option("--steps", min=1, help="Environment steps.")] = 2_000_000,
    seed: Annotated[int, seed_option("the network and the episodes' order")] = 0,
    envs: Annotated[int, typer.Option("--envs", min=1, max=256, help="Vectorised envs.")] = 8,
    learning_rate: Annotated[float, typer.Option("--lr", min=0.0, max=1.0,
                                                 help="The learning rate.")] = 3e-4,
    ent_coef: Annotated[float, typer.Option("--ent", min=0.0, max=1.0,
                                            help="PPO's entropy bonus.")] = 0.005,
    log_std: Annotated[float, typer.Option("--log-std", min=-5.0, max=2.0,
                                           help="PPO: initial log std of the actions.")] = -0.5,
    net: Annotated[str, typer.Option("--net", help="Hidden layer widths, e.g. 64,64.")] = "128,128",
    observation: Annotated[
        str, typer.Option("--observation", help="What the policy sees: copi-local-v2 (ranges "
                          "and their change, any level) or copi-local-v3 (one level's reading: "
                          "the hits the map does not explain at map, --frames readings "
                          "stacked, its own velocity).")
    ] = "copi-local-v3",
    frames: Annotated[
        int, typer.Option("--frames", min=2, max=16, help="Readings stacked (copi-local-v3).")
    ] = 3,
    proximity: Annotated[
        float, typer.Option("--proximity", min=0.0, max=1000.0, help="Most a step costs for "
                            "coming within 1.5 steps of a moving obstacle (0: none).")
    ] = 0.5,
    normalize_reward: Annotated[
        bool, typer.Option("--normalize-reward/--raw-reward", help="Scale the reward by the "
                           "running spread of its return (the observation stays raw).")
    ] = True,
    contact: Annotated[
        float, typer.Option("--contact", min=0.0, max=1000.0, help="What a contact costs.")
    ] = 10.0,
    n_steps: Annotated[
        int, typer.Option("--n-steps", min=1, help="PPO: steps per environment between "
                          "updates.")
    ] = 512,
    batch_size: Annotated[int, typer.Option("--batch-size", min=1, help="Minibatch size.")] = 512,
    buffer_size: Annotated[
        int, typer.Option("--buffer-size", min=1, max=10_000_000, help="SAC: transitions its "
                          "replay buffer keeps.")
    ] = 100_000,
    learning_starts: Annotated[
        int, typer.Option("--learning-starts", min=0, help="SAC: steps of random actions "
                          "before it learns.")
    ] = 10_000,
    gradient_steps: Annotated[
        int, typer.Option("--gradient-steps", min=1, max=1000, help="SAC: gradient steps "
                          "after each step of the environments.")
    ] = 1,
    checkpoints: Annotated[
        Path | None,
        typer.Option("--checkpoints", help="Directory of checkpoints; a rerun resumes there."),
    ] = None,
    validation_episodes: Annotated[
        int, typer.Option("--validation-episodes", min=1, max=10_000,
                          help="Episodes of validation seed 1 each point of the curve runs.")
    ] = 60,
    keep: Annotated[
        str, typer.Option("--keep", help="The policy written: best (the highest validation "
                          "success, on seed 1, which no report uses) or last.")
    ] = "best",
    validate_every: Annotated[
        int, typer.Option("--validate-every", min=1000, help="Steps between validations.")
    ] = 100_000,
    imitate: Annotated[
        str, typer.Option("--imitate", help="PPO: a registered method whose moves the policy "
                          "clones first (at its level; DAgger), then PPO improves on it; "
                          "clone: the method cloned.")
    ] = "",
    imitation_episodes: Annotated[
        int, typer.Option("--imitation-episodes", min=1, max=100_000,
                          help="Episodes the demonstrator drives.")  # fmt: skip
    ] = 2000,
    episodes: Annotated[
        int, typer.Option("--episodes-per-family", min=1, max=1_000_000,
                          help="A family's pool of training episodes.")  # fmt: skip
    ] = 1000,
    dagger_rounds: Annotated[
        int, typer.Option("--dagger-rounds", min=0, max=100,
                          help="Rounds of the clone driving, the demonstrator labelling.")
    ] = 2,
    curriculum: Annotated[
        str, typer.Option("--curriculum", help="PPO or SAC: stages before --families, "
                          "FAMILY:STEP each (the step it ends at, at the first rollout from "
                          "there), e.g. star:400000,polygon:800000 (then --families to the "
                          "end).")
    ] = "",
) -> None:
    """Train PPO or SAC (Stable-Baselines3) for a local policy in copi's factorisation: it sees
    its level's reading (at map, the hits the static map does not explain), the last
    --frames readings, its own velocity and its level's global direction, and acts with a
    velocity (--algo clone: no RL, a classifier of --imitate's moves). Writes the policy
    (numpy weights: copi.baselines.PPOAgent(weights=FILE) runs it, without torch), its
    learning curve on fixed validation episodes (.json, .png). Needs the extra rl."""
    from copi.errors import InvalidArgumentError
    from copi.rl import Reward, TrainConfig, check_apart, check_demonstrator, train

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
        log_std=log_std, net=widths, reward=Reward(proximity=proximity, contact=contact),
        observation=observation, frames=frames, normalize_reward=normalize_reward,
        n_steps=n_steps, batch_size=batch_size, algorithm=algo, buffer_size=buffer_size,
        learning_starts=learning_starts, gradient_steps=gradient_steps, imitate=imitate,
        imitation_episodes=imitation_episodes, dagger_rounds=dagger_rounds, episodes=episodes,
        curriculum=_stages(curriculum),
    )  # fmt: skip
    if imitate:
        check_demonstrator(imitate, config.levels[0])
    check_writable(output.parent, "the policy")  # before hours of training, not after
    if checkpoints is not None:
        check_writable(checkpoints, "checkpoints")
    command = "copi " + " ".join(shlex.quote(a) for a in sys.argv[1:])
    clone = algo == "clone"
    if config.planned_steps != steps and not clone:
        how = (f"PPO trains in whole rollouts of {config.envs} envs x {config.n_steps} steps"
               if algo == "ppo" else f"SAC steps its {config.envs} envs together")  # fmt: skip
        out.print(f"training {config.planned_steps:,} steps: {how} (asked for {steps:,})")
    with progress() as bar:
        tid = None if clone else bar.add_task("rl: environment steps",
                                              total=config.planned_steps)  # fmt: skip
        cloning: dict[str, Any] = {}

        def imitating(stage: str, done: int, total: int) -> None:
            if stage not in cloning:
                cloning[stage] = bar.add_task(stage, total=total)
            bar.update(cloning[stage], completed=done)

        summary = train(config, output, checkpoints=checkpoints, validate_every=validate_every,
                        validation_episodes=validation_episodes, keep=keep,
                        progress=None if tid is None else
                        lambda done, total: bar.update(tid, completed=done),
                        resumed=lambda done: out.print(
                            f"resuming at {done:,} of {config.planned_steps:,} steps from "
                            f"{checkpoints}"),
                        command=command, imitating=imitating)  # fmt: skip
    if clone:
        rounds = ", ".join(f"{100 * c['success']:.1f}" for c in summary["curve"])
        out.print(f"{output}: the clone of {imitate} ({summary['states']:,} states, "
                  f"{summary['seconds']:.0f} s); validation success by round {rounds} %; "
                  f"kept: round {summary['kept_round']} "
                  f"({100 * summary['kept_success']:.1f} %)")  # fmt: skip
        return
    if "imitation" in summary:
        first = summary["curve"][0]
        out.print(f"the clone of {imitate} ({summary['imitation']['states']:,} states): "
                  f"validation success {100 * first['success']:.1f} % before PPO")
    out.print(
        f"{output}: {algo.upper()}, {summary['steps']:,} steps in {summary['seconds']:.0f} s "
        f"({summary['steps_per_second']:,.0f} steps/s), validation success "
        f"{100 * summary['curve'][-1]['success']:.1f} % at the end; kept: the policy of "
        f"{summary['kept_steps']:,} steps ({100 * summary['kept_success']:.1f} %)"
    )


def _stages(text: str) -> tuple[tuple[str, int], ...]:
    """--curriculum's FAMILY:STEP,... as TrainConfig's stages."""
    from copi.errors import InvalidArgumentError

    stages = []
    for part in (p.strip() for p in text.split(",") if p.strip()):
        family, _, end = part.rpartition(":")
        try:
            stages.append((family.strip(), int(end)))
        except ValueError:
            raise InvalidArgumentError(f"--curriculum must be FAMILY:STEP stages, e.g. "
                                       f"star:400000,polygon:800000; got {part!r}") from None
        if not family.strip():
            raise InvalidArgumentError(f"--curriculum must be FAMILY:STEP stages, e.g. "
                                       f"star:400000,polygon:800000; got {part!r}")
    if text.strip() and not stages:
        raise InvalidArgumentError(f"--curriculum must be FAMILY:STEP stages, e.g. "
                                   f"star:400000,polygon:800000; got {text!r}")
    return tuple(stages)


@rl_app.command("sarl")
def sarl_command(
    output: Annotated[Path, typer.Option("-o", "--output", help="Network file to write (.npz).")],
    family: Annotated[str, typer.Option("--family", help="Family of the episodes.")] = "crowd",
    demonstrator: Annotated[
        str, typer.Option("--demonstrator", help="Registered method imitated first (level "
                          "oracle; CrowdNav's: crowdnav-orca).")
    ] = "model-oracle",
    demo_episodes: Annotated[
        int, typer.Option("--demo-episodes", min=1, max=100_000, help="Demonstrations.")
    ] = 300,
    il_epochs: Annotated[
        int, typer.Option("--il-epochs", min=0, max=10_000, help="Passes over them.")
    ] = 50,
    rl_episodes: Annotated[
        int, typer.Option("--rl-episodes", min=0, max=1_000_000, help="Episodes of RL.")
    ] = 1000,
    epsilon: Annotated[
        str, typer.Option("--epsilon", help="Exploration: first, last, over how many episodes.")
    ] = "0.5,0.1,400",
    validation_episodes: Annotated[
        int, typer.Option("--validation-episodes", min=1, max=10_000,
                          help="Validation episodes (seed 1) every 100 episodes of RL.")
    ] = 60,
    seed: Annotated[int, seed_option("the network and the exploration")] = 0,
) -> None:
    """Train SARL as CrowdNav trains it (imitation of the demonstrator's returns, then RL
    with a target network) on the family's training episodes at level oracle. Writes the
    network that did best on validation episodes (copi.baselines.SARLAgent(weights=FILE)
    runs it, without torch) and its learning curve (.json, .png). Needs the extra rl."""
    from copi.errors import InvalidArgumentError
    from copi.rl import RLMissingError, SARLConfig, rl_available, train_sarl, write_sarl

    check_outputs({"the network": (output, "SARL network"),
                   "the learning curve": (output.with_suffix(".json"), "json"),
                   "the learning curve's figure": (output.with_suffix(".png"), "png")})
    try:
        e0, e1, span = (x.strip() for x in epsilon.split(","))
        eps = (float(e0), float(e1), int(span))
    except ValueError:
        raise InvalidArgumentError("--epsilon must be three comma-separated numbers (first, "
                                   f"last, episodes); got {epsilon!r}") from None
    config = SARLConfig(family=family, demonstrator=demonstrator, demo_episodes=demo_episodes,
                        il_epochs=il_epochs, rl_episodes=rl_episodes, epsilon=eps,
                        validation_episodes=validation_episodes,
                        seed=seed)  # fmt: skip
    if not rl_available():
        raise RLMissingError("training SARL needs the optional extra rl (torch): pip install "
                             "'copi[rl]'")  # fmt: skip
    check_writable(output.parent, "the network")
    with progress() as bar:
        tid = bar.add_task("sarl: episodes", total=demo_episodes + rl_episodes)
        weights, curve = train_sarl(config, log=lambda line: None,
                                    progress=lambda done, total: bar.update(tid, completed=done))
    weights.info["command"] = " ".join(shlex.quote(str(a)) for a in (
        "copi", "rl", "sarl", "-o", output, "--family", family, "--demonstrator", demonstrator,
        "--demo-episodes", demo_episodes, "--il-epochs", il_epochs, "--rl-episodes",
        rl_episodes, "--epsilon", epsilon, "--validation-episodes", validation_episodes,
        "--seed", seed))  # fmt: skip
    write_sarl(weights, curve, output)
    out.print(f"{output}: SARL, {demo_episodes:,} demonstrations of {demonstrator} and "
              f"{rl_episodes:,} episodes of RL in {weights.info['seconds']:,} s; kept: "
              f"validation success {100 * weights.info['validation']:.1f} %")
