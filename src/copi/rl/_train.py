"""PPO or SAC (Stable-Baselines3) training of a local policy in copi's episodes, with
checkpoints, a learning curve on fixed validation episodes, and the export of the actor
to numpy weights (:func:`copi.baselines.save_policy`).

Needs the optional extra ``rl`` (Stable-Baselines3 and a CPU build of torch); nothing
else of copi imports this module's dependencies.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from copi._files import write_text
from copi.baselines import OBSERVATION, PolicyWeights, PPOAgent, load_policy, save_policy
from copi.envs.local_policy import LocalPolicyEnv
from copi.errors import (
    CopiError,
    Interrupted,
    InvalidArgumentError,
    InvalidWorldError,
    ctrl_c_behind,
)
from copi.experiments import PursuitConfig, run_game
from copi.reports import finish_figure, new_figure
from copi.rl._checkpoint import (
    CHECKPOINT_FILES,
    _beside,
    _read_checkpoint,
    _restore,
    _whole,
    _write_checkpoint,
    check_apart,
)
from copi.rl._config import TrainConfig
from copi.runs import Episode

__all__ = [
    "CHECKPOINT_FILES",
    "RLMissingError",
    "TrainConfig",
    "check_apart",
    "export_policy",
    "rl_available",
    "train",
    "validation_success",
]

VALIDATION_SEED = 1
"""The learning curve is measured on episodes of this seed (tuning's; reports use 0)."""


class RLMissingError(CopiError):
    """The optional extra ``rl`` (Stable-Baselines3, torch) is not installed."""


def rl_available() -> bool:
    """Whether Stable-Baselines3 and torch can be imported."""
    try:
        import stable_baselines3  # noqa: F401
        import torch  # noqa: F401
    except ImportError:
        return False
    return True


def _need_rl() -> None:
    if not rl_available():
        raise RLMissingError(
            "training needs the optional extra rl (Stable-Baselines3 on a CPU build of torch): "
            "pip install 'torch==2.13.0' --index-url https://download.pytorch.org/whl/cpu, "
            "then pip install 'copi[rl]'"
        )


def export_policy(model: Any, n_rays: int = 32, max_range: float = 10.0,
                  info: dict[str, Any] | None = None,
                  config: TrainConfig | None = None) -> PolicyWeights:  # fmt: skip
    """The actor of a Stable-Baselines3 PPO or SAC ``MlpPolicy`` (tanh) as numpy weights:
    the policy network's linear layers, then the action network (PPO's mean, clipped; SAC's
    mean, squashed by tanh); what it sees as ``config`` says (``copi-local-v2`` without
    one)."""
    import torch

    policy = model.policy
    sac = hasattr(policy, "actor")
    modules = [*policy.actor.latent_pi, policy.actor.mu] if sac else \
        [*policy.mlp_extractor.policy_net, policy.action_net]  # fmt: skip
    layers = []
    for module in modules:
        if isinstance(module, torch.nn.Linear):
            w = module.weight.detach().cpu().numpy().astype(np.float64)
            b = module.bias.detach().cpu().numpy().astype(np.float64)
            layers.append((w, b))
        elif not isinstance(module, torch.nn.Tanh):
            raise InvalidArgumentError(f"cannot export a {type(module).__name__} layer (tanh "
                                       "MLPs only)")  # fmt: skip
    output = "tanh" if sac else "clip"
    if config is None or config.observation == OBSERVATION:
        return PolicyWeights(tuple(layers), n_rays, max_range, info or {}, output=output)
    # one level (a copi-local-v3 policy's, a chauffeur's evader too)
    return PolicyWeights(tuple(layers), n_rays, max_range, info or {}, config.observation,
                         config.levels[0], config.frames, output)  # fmt: skip


def validation_success(
    policy: PolicyWeights | None, config: TrainConfig, episodes: int, agent: Any = None
) -> float:
    """Success of ``policy`` (or of any ``agent``, e.g. copi's, for comparison) on fixed
    episodes of the validation seed (the training families and levels in turn; the
    game's survival for the chauffeur task)."""
    if agent is None:
        agent = PPOAgent(policy=policy)
    if config.task == "chauffeur":
        cfg = PursuitConfig(capabilities=None, evader="game", games=episodes,
                            seed=VALIDATION_SEED)  # fmt: skip
        survived = [run_game(cfg, k, agent).outcome == "escaped" for k in range(episodes)]
        return float(np.mean(survived))
    wins = []
    for k in range(episodes):
        family = config.families[k % len(config.families)]
        level = config.levels[(k // len(config.families)) % len(config.levels)]
        try:
            episode = Episode.draw(family, k, VALIDATION_SEED)
        except InvalidWorldError:  # a world with no valid task: the family's others count
            continue
        out = episode.run(agent, sensing=level)  # type: ignore[arg-type]
        wins.append(out.outcome == "success")
    return float(np.mean(wins)) if wins else math.nan


def train(
    config: TrainConfig,
    output: str | os.PathLike[str],
    *,
    checkpoints: str | os.PathLike[str] | None = None,
    validate_every: int = 100_000,
    validation_episodes: int = 60,
    progress: Callable[[int, int], None] | None = None,
    resumed: Callable[[int], None] | None = None,
    command: str = "",
    keep: str = "best",
    imitating: Callable[[str, int, int], None] | None = None,
) -> dict[str, Any]:
    """Train PPO or SAC as ``config`` says and write the exported policy to ``output`` (and
    ``output`` with ``.json`` and ``.png``: the learning curve). With ``checkpoints``, the
    model is saved there every ``validate_every`` steps (weights and optimiser state as
    torch tensors, loaded with ``weights_only``: no pickle), and a rerun resumes from the
    last one (``resumed`` is told the steps it resumes at). ``progress(done, total)`` counts
    to :attr:`TrainConfig.planned_steps`. ``keep``: the policy written, ``"best"`` (the
    snapshot of the highest validation success, the latest of equals: model selection on
    the validation seed, which no report uses) or ``"last"``. With ``config.imitate``,
    the policy first clones that method (:func:`copi.rl._imitate.warm_start`;
    ``imitating(stage, done, total)`` follows it) and the clone is validated at step 0
    (a resumed run finds it in its checkpoint). Returns the run's summary
    (steps, seconds, steps per second, curve, the steps of the policy kept)."""
    if keep not in ("best", "last"):
        raise InvalidArgumentError(f"keep must be best or last; got {keep!r}")
    check_apart(output, checkpoints)
    _need_rl()
    if config.imitate:
        from copi.rl._imitate import check_demonstrator

        check_demonstrator(config.imitate, config.levels[0])
    if config.algorithm == "clone":
        if checkpoints is not None:
            raise InvalidArgumentError("a clone takes no checkpoints (its rounds are minutes; "
                                       "rerun it)")  # fmt: skip
        return _train_clone(config, Path(output), validation_episodes=validation_episodes,
                            command=command, keep=keep, imitating=imitating)  # fmt: skip
    import torch
    from stable_baselines3 import PPO, SAC
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    torch.set_num_threads(1)
    out = Path(output)
    curve_path, figure_path = _beside(out)

    def make(i: int) -> Callable[[], LocalPolicyEnv]:
        def env() -> LocalPolicyEnv:
            e = LocalPolicyEnv(config.families_at(0), levels=config.levels, task=config.task,
                               reward=config.reward, max_steps=config.max_steps,
                               observation=config.observation, frames=config.frames,
                               episodes=config.episodes)  # fmt: skip
            e.reset(seed=config.seed * 1000 + i)
            return e

        return env

    vec = DummyVecEnv([make(i) for i in range(config.envs)])
    vec.seed(config.seed)
    # the reward scaled by the running spread of its discounted return (the observation
    # is left as it is: the exported policy reads it raw)
    norm = VecNormalize(vec, norm_obs=False, norm_reward=True, gamma=config.gamma) \
        if config.normalize_reward else None  # fmt: skip
    env = vec if norm is None else norm
    if config.algorithm == "sac":
        model: Any = SAC(
            "MlpPolicy", env, learning_rate=config.learning_rate,
            buffer_size=config.buffer_size, learning_starts=config.learning_starts,
            batch_size=config.batch_size, tau=config.tau, gamma=config.gamma, train_freq=1,
            gradient_steps=config.gradient_steps, ent_coef="auto", seed=config.seed,
            device="cpu", verbose=0,
            policy_kwargs={"net_arch": {"pi": list(config.net), "qf": list(config.net)},
                           "activation_fn": torch.nn.Tanh},
        )  # fmt: skip
    else:
        model = PPO(
            "MlpPolicy", env, learning_rate=config.learning_rate, n_steps=config.n_steps,
            batch_size=config.batch_size, n_epochs=config.n_epochs, gamma=config.gamma,
            ent_coef=config.ent_coef, seed=config.seed, device="cpu", verbose=0,
            policy_kwargs={"net_arch": {"pi": list(config.net), "vf": list(config.net)},
                           "activation_fn": torch.nn.Tanh, "log_std_init": config.log_std},
        )  # fmt: skip
    curve: list[dict[str, float]] = []
    best: PolicyWeights | None = None  # the best validation's (its success in its info)
    elapsed0 = 0.0
    checkpointed = 0  # steps of the last checkpoint written whole (0: none yet)
    ckpt = None if checkpoints is None else Path(checkpoints)
    saved = None
    if ckpt is not None:
        ckpt.mkdir(parents=True, exist_ok=True)
        saved = _read_checkpoint(ckpt, config)
        if saved is not None:
            elapsed0 = _restore(model, vec, saved, ckpt, norm)
            curve = list(saved["meta"]["curve"])
            checkpointed = int(model.num_timesteps)
            if (ckpt / "best.npz").is_file():
                best = load_policy(ckpt / "best.npz")
            if resumed is not None:
                resumed(int(model.num_timesteps))
    def follow_curriculum() -> None:
        """The training episodes' families for the steps done (a curriculum's stage)."""
        if config.curriculum:
            vec.set_attr("families", config.families_at(int(model.num_timesteps)))

    follow_curriculum()  # a resumed run goes on in its stage
    t0 = time.perf_counter()
    imitation: dict[str, Any] = {}
    if config.imitate and saved is None:  # a resumed run has its clone in its checkpoint
        from copi.rl._imitate import warm_start

        imitation = warm_start(model, config, imitating)
    if progress is not None:
        progress(int(model.num_timesteps), config.planned_steps)

    name = {"ppo": "PPO", "sac": "SAC"}[config.algorithm]

    def snapshot() -> PolicyWeights:
        return export_policy(model, info={**config.identity(), "algorithm": name},
                             config=config)  # fmt: skip

    class Watch(BaseCallback):  # type: ignore[misc]
        """Progress at every step; validation (and a checkpoint) between rollouts, where
        PPO's rollout buffer is empty (SAC's: after a step's gradient updates), so that a
        resumed run goes on exactly as it would have."""

        def __init__(self) -> None:
            super().__init__()
            self.next = (model.num_timesteps // validate_every + 1) * validate_every

        def _on_step(self) -> bool:
            if progress is not None:
                progress(self.num_timesteps, config.planned_steps)
            return True

        def _on_rollout_start(self) -> None:
            follow_curriculum()
            if model.num_timesteps >= self.next:
                self.next = (model.num_timesteps // validate_every + 1) * validate_every
                record()

    def record(checkpoint: bool = True) -> None:
        nonlocal checkpointed, best
        seconds = elapsed0 + time.perf_counter() - t0
        now = snapshot()
        success = validation_success(now, config, validation_episodes)
        curve.append({"steps": int(model.num_timesteps), "seconds": round(seconds, 1),
                      "success": success})  # fmt: skip
        improved = best is None or success >= best.info["validation_success"]
        if improved:
            now.info.update(validation_success=success, kept_steps=int(model.num_timesteps))
            best = now
        if ckpt is not None:
            with _whole():
                if improved:
                    save_policy(now, ckpt / "best.npz")
                if checkpoint:
                    _write_checkpoint(ckpt, model, vec, config, curve, seconds, norm)
                    checkpointed = int(model.num_timesteps)

    left = config.steps - model.num_timesteps
    try:
        if imitation:  # the clone's own validation, at step 0 (checkpoints come with PPO's)
            record(checkpoint=False)
        if left > 0:
            model.learn(total_timesteps=left, callback=Watch(), reset_num_timesteps=False,
                        progress_bar=False)  # fmt: skip
        if not curve or curve[-1]["steps"] < model.num_timesteps:
            record()
    except BaseException as exc:
        # a Ctrl-C that lands in a compiled call of the validation comes out as the
        # SystemError numba makes of it
        if ctrl_c_behind(exc) is None:
            raise
        raise Interrupted(_what_is_saved(config, ckpt, checkpointed, validate_every)) from None
    seconds = elapsed0 + time.perf_counter() - t0
    summary = {
        "steps": int(model.num_timesteps),
        "seconds": round(seconds, 1),
        "steps_per_second": round(model.num_timesteps / max(seconds, 1e-9), 1),
        "curve": curve,
        "validation_episodes": validation_episodes,
        "config": config.identity(),
        "command": command,
    }
    if imitation:
        summary["imitation"] = imitation
    policy = export_policy(model, info={**config.identity(),
                                        "algorithm": f"{name} (Stable-Baselines3)",
                                        "steps_per_second": summary["steps_per_second"],
                                        "seconds": summary["seconds"], "command": command},
                           config=config)  # fmt: skip
    policy.info.update(validation_success=curve[-1]["success"],
                       kept_steps=int(model.num_timesteps), kept="last")  # fmt: skip
    if keep == "best" and best is not None and \
            best.info["validation_success"] > curve[-1]["success"]:  # fmt: skip
        policy = dataclasses.replace(policy, layers=best.layers, info={
            **policy.info, "validation_success": best.info["validation_success"],
            "kept_steps": best.info["kept_steps"]})  # fmt: skip
    policy.info["kept"] = keep
    summary["kept_steps"] = policy.info["kept_steps"]
    summary["kept_success"] = policy.info["validation_success"]
    save_policy(policy, out)
    write_text(curve_path, json.dumps(summary, indent=1) + "\n", "json")
    _curve_figure(curve, figure_path, title=out.stem, stages=config.curriculum,
                  target=",".join(config.families))  # fmt: skip
    return summary


def _train_clone(config: TrainConfig, out: Path, *, validation_episodes: int, command: str,
                 keep: str, imitating: Callable[[str, int, int], None] | None
                 ) -> dict[str, Any]:  # fmt: skip
    """:func:`train` of a clone (:func:`copi.rl._imitate.train_clone`): the policy, its
    curve over DAgger's rounds (.json, .png) and the summary."""
    import torch

    from copi.rl._imitate import train_clone

    torch.set_num_threads(1)
    curve_path, figure_path = _beside(out)
    t0 = time.perf_counter()
    info = {**config.identity(), "algorithm": "behaviour cloning (DAgger)", "command": command}
    try:
        policy, curve, imitation = train_clone(
            config, lambda p: validation_success(p, config, validation_episodes),
            imitating=imitating, info=info, keep=keep,
        )  # fmt: skip
    except BaseException as exc:
        if ctrl_c_behind(exc) is None:
            raise
        raise Interrupted("nothing saved (a clone's rounds are not checkpointed); rerun the "
                          "same command") from None  # fmt: skip
    seconds = round(time.perf_counter() - t0, 1)
    policy.info["seconds"] = seconds
    states = imitation["states"]
    summary = {
        "steps": 0, "states": states, "seconds": seconds, "steps_per_second": 0.0,
        "curve": curve, "validation_episodes": validation_episodes,
        "config": config.identity(), "command": command, "imitation": imitation,
        "kept_steps": 0, "kept_round": policy.info["kept_round"],
        "kept_success": policy.info["validation_success"],
    }  # fmt: skip
    save_policy(policy, out)
    write_text(curve_path, json.dumps(summary, indent=1) + "\n", "json")
    _curve_figure(curve, figure_path, title=out.stem,
                  xlabel="states demonstrated (one point a DAgger round)")  # fmt: skip
    return summary


def _what_is_saved(config: TrainConfig, ckpt: Path | None, checkpointed: int,
                   validate_every: int) -> str:  # fmt: skip
    """What a run stopped by Ctrl-C has saved, and what rerunning it does."""
    if ckpt is None:
        return "nothing saved (give --checkpoints DIR to resume an interrupted run)"
    if checkpointed:
        return f"{checkpointed:,} steps checkpointed in {ckpt}; rerun the same command to resume"
    # checkpoints are taken between rollouts, at the first past validate_every, and at
    # the end of a run shorter than that
    first = min(-(-validate_every // config.rollout) * config.rollout, config.planned_steps)
    return (f"nothing checkpointed yet in {ckpt} (the first checkpoint is taken after "
            f"{first:,} steps); rerunning the same command starts over, and resumes from "
            "the checkpoints once there are some")  # fmt: skip


def _curve_figure(curve: list[dict[str, float]], path: Path, *, title: str,
                  xlabel: str = "environment steps",
                  stages: tuple[tuple[str, int], ...] = (), target: str = "") -> None:  # fmt: skip
    """The learning curve; a curriculum's stages shaded, each named by its family, and
    the ``target`` families' part after them named too."""
    fig = new_figure(5.0, 3.4)
    ax = fig.add_subplot()
    start = 0
    for i, (family, end) in enumerate(stages):
        ax.axvspan(start, end, color="0.85" if i % 2 == 0 else "0.93", lw=0, zorder=0)
        ax.text((start + end) / 2, 0.98, family, transform=ax.get_xaxis_transform(),
                ha="center", va="top", fontsize=7, color="0.35")  # fmt: skip
        start = end
    if stages and curve and curve[-1]["steps"] > start:
        ax.text((start + curve[-1]["steps"]) / 2, 0.98, target, ha="center", va="top",
                transform=ax.get_xaxis_transform(), fontsize=7, color="0.35")  # fmt: skip
    ax.plot([c["steps"] for c in curve], [100 * c["success"] for c in curve], marker="o", ms=3)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("validation success (%)")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    finish_figure(fig, path)
