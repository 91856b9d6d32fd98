"""PPO (Stable-Baselines3) training of a local policy in copi's episodes, with
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
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from copi._files import write_text
from copi.baselines import PolicyWeights, PPOAgent, save_policy
from copi.envs.local_policy import LocalPolicyEnv, Reward
from copi.errors import CopiError, InvalidArgumentError
from copi.experiments import PursuitConfig, run_game
from copi.reports import finish_figure, new_figure
from copi.runs import Episode
from copi.world import check_family

__all__ = [
    "RLMissingError",
    "TrainConfig",
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


@dataclass(frozen=True)
class TrainConfig:
    """One training run; every field decides the policy it learns."""

    families: tuple[str, ...] = ("star", "polygon", "indoor", "maps", "crowd")
    """World families of the training episodes (a mix: one drawn per episode)."""
    levels: tuple[str, ...] = ("sensor", "map")
    task: str = "navigation"
    """"navigation" or "chauffeur" (the evader of Experiment 2's game)."""
    steps: int = 2_000_000
    """Environment steps of training."""
    seed: int = 0
    """Seed of the network, the optimiser and the episodes' order (the episodes themselves
    are those of the training seed, copi.rl.TRAINING_SEED)."""
    envs: int = 8
    """Environments stepped together (a vectorised environment in this process)."""
    learning_rate: float = 1e-3
    """With ``log_std`` -1, the setting chosen among five on validation seed 1
    (``studies/rl_train_all.py --tune``; SB3's defaults are 3e-4 and 0)."""
    n_steps: int = 256
    """Steps per environment between updates."""
    batch_size: int = 256
    n_epochs: int = 10
    gamma: float = 0.99
    ent_coef: float = 0.0
    log_std: float = -1.0
    """The policy's initial log standard deviation of its actions (exploration noise)."""
    net: tuple[int, ...] = (64, 64)
    """Hidden layers of the actor (and of the critic)."""
    reward: Reward = field(default_factory=Reward)
    max_steps: int = 500

    def __post_init__(self) -> None:
        for f in self.families:
            check_family(f)
        if self.task not in ("navigation", "chauffeur"):
            raise InvalidArgumentError(f"task must be navigation or chauffeur; got {self.task!r}")
        for key in ("steps", "envs", "n_steps", "batch_size", "n_epochs", "max_steps"):
            v = getattr(self, key)
            if isinstance(v, bool) or int(v) != v or v < 1:
                raise InvalidArgumentError(f"{key} must be a positive int; got {v!r}")
        if self.steps > 10**9:
            raise InvalidArgumentError(f"steps must be at most 1,000,000,000; got {self.steps:,}")
        if not 1 <= self.envs <= 256:
            raise InvalidArgumentError(f"envs must be in 1 .. 256; got {self.envs}")
        for key in ("learning_rate", "gamma", "ent_coef"):
            v = getattr(self, key)
            if not (isinstance(v, int | float) and math.isfinite(v) and 0 <= v <= 1):
                raise InvalidArgumentError(f"{key} must be a number in [0, 1]; got {v!r}")
        if not (isinstance(self.log_std, int | float) and -5 <= self.log_std <= 2):
            raise InvalidArgumentError(f"log_std must be a number in [-5, 2]; got {self.log_std!r}")
        if not self.net or not all(isinstance(h, int) and 1 <= h <= 1024 for h in self.net):
            raise InvalidArgumentError(f"net must be 1 to 6 layer widths in 1 .. 1024; got "
                                       f"{self.net!r}")  # fmt: skip

    def identity(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["net"] = list(self.net)
        return d


def export_policy(model: Any, n_rays: int = 32, max_range: float = 10.0,
                  info: dict[str, Any] | None = None) -> PolicyWeights:  # fmt: skip
    """The actor of a Stable-Baselines3 PPO ``MlpPolicy`` (tanh) as numpy weights: the
    policy network's linear layers, then the action network."""
    import torch

    policy = model.policy
    layers = []
    for module in [*policy.mlp_extractor.policy_net, policy.action_net]:
        if isinstance(module, torch.nn.Linear):
            w = module.weight.detach().cpu().numpy().astype(np.float64)
            b = module.bias.detach().cpu().numpy().astype(np.float64)
            layers.append((w, b))
        elif not isinstance(module, torch.nn.Tanh):
            raise InvalidArgumentError(f"cannot export a {type(module).__name__} layer (tanh "
                                       "MLPs only)")  # fmt: skip
    return PolicyWeights(tuple(layers), n_rays, max_range, info or {})


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
        except Exception:
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
    command: str = "",
) -> dict[str, Any]:
    """Train PPO as ``config`` says and write the exported policy to ``output`` (and
    ``output`` with ``.json`` and ``.png``: the learning curve). With ``checkpoints``, the
    model is saved there every ``validate_every`` steps (weights and optimiser state as
    torch tensors, loaded with ``weights_only``: no pickle), and a rerun resumes from the
    last one. Returns the run's summary (steps, seconds, steps per second, curve)."""
    _need_rl()
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.vec_env import DummyVecEnv

    torch.set_num_threads(1)
    out = Path(output)
    curve_path = out.with_suffix(".json")
    figure_path = out.with_suffix(".png")

    def make(i: int) -> Callable[[], LocalPolicyEnv]:
        def env() -> LocalPolicyEnv:
            e = LocalPolicyEnv(config.families, levels=config.levels, task=config.task,
                               reward=config.reward, max_steps=config.max_steps)  # fmt: skip
            e.reset(seed=config.seed * 1000 + i)
            return e

        return env

    vec = DummyVecEnv([make(i) for i in range(config.envs)])
    vec.seed(config.seed)
    model = PPO(
        "MlpPolicy", vec, learning_rate=config.learning_rate, n_steps=config.n_steps,
        batch_size=config.batch_size, n_epochs=config.n_epochs, gamma=config.gamma,
        ent_coef=config.ent_coef, seed=config.seed, device="cpu", verbose=0,
        policy_kwargs={"net_arch": {"pi": list(config.net), "vf": list(config.net)},
                       "activation_fn": torch.nn.Tanh, "log_std_init": config.log_std},
    )  # fmt: skip
    curve: list[dict[str, float]] = []
    elapsed0 = 0.0
    ckpt = None if checkpoints is None else Path(checkpoints)
    if ckpt is not None:
        ckpt.mkdir(parents=True, exist_ok=True)
        state = ckpt / "last.pt"
        meta = ckpt / "last.json"
        if state.is_file() and meta.is_file():
            saved = json.loads(meta.read_text())
            # the same run: every setting but the budget (a run resumes to more steps)
            same = {k: v for k, v in json.loads(json.dumps(config.identity())).items()
                    if k != "steps"}  # fmt: skip
            if {k: v for k, v in dict(saved.get("config") or {}).items() if k != "steps"} != same:
                raise InvalidArgumentError(
                    f"{ckpt} holds checkpoints of another training run; use another directory"
                )
            params = torch.load(state, weights_only=True, map_location="cpu")
            model.set_parameters(params, exact_match=True)
            model.num_timesteps = int(saved["steps"])
            curve = list(saved["curve"])
            elapsed0 = float(saved["seconds"])

    t0 = time.perf_counter()

    def snapshot() -> PolicyWeights:
        return export_policy(model, info={"algorithm": "PPO", **config.identity()})

    class Watch(BaseCallback):  # type: ignore[misc]
        def __init__(self) -> None:
            super().__init__()
            self.next = (model.num_timesteps // validate_every + 1) * validate_every

        def _on_step(self) -> bool:
            if progress is not None:
                progress(self.num_timesteps, config.steps)
            if self.num_timesteps >= self.next:
                self.next += validate_every
                record()
            return True

    def record() -> None:
        seconds = elapsed0 + time.perf_counter() - t0
        curve.append({"steps": int(model.num_timesteps), "seconds": round(seconds, 1),
                      "success": validation_success(snapshot(), config,
                                                    validation_episodes)})  # fmt: skip
        if ckpt is not None:
            torch.save(model.get_parameters(), ckpt / "last.pt.tmp")
            os.replace(ckpt / "last.pt.tmp", ckpt / "last.pt")
            write_text(ckpt / "last.json", json.dumps(
                {"config": config.identity(), "steps": int(model.num_timesteps),
                 "curve": curve, "seconds": seconds}), "json")  # fmt: skip

    left = config.steps - model.num_timesteps
    if left > 0:
        model.learn(total_timesteps=left, callback=Watch(), reset_num_timesteps=False,
                    progress_bar=False)  # fmt: skip
    if not curve or curve[-1]["steps"] < model.num_timesteps:
        record()
    seconds = elapsed0 + time.perf_counter() - t0
    summary = {
        "steps": int(model.num_timesteps),
        "seconds": round(seconds, 1),
        "steps_per_second": round(model.num_timesteps / max(seconds, 1e-9), 1),
        "curve": curve,
        "config": config.identity(),
        "command": command,
    }
    policy = export_policy(model, info={"algorithm": "PPO (Stable-Baselines3)",
                                        "steps_per_second": summary["steps_per_second"],
                                        "seconds": summary["seconds"], "command": command,
                                        **config.identity()})  # fmt: skip
    save_policy(policy, out)
    write_text(curve_path, json.dumps(summary, indent=1) + "\n", "json")
    _curve_figure(curve, figure_path, title=out.stem)
    return summary


def _curve_figure(curve: list[dict[str, float]], path: Path, *, title: str) -> None:
    fig = new_figure(5.0, 3.4)
    ax = fig.add_subplot()
    ax.plot([c["steps"] for c in curve], [100 * c["success"] for c in curve], marker="o", ms=3)
    ax.set_xlabel("environment steps")
    ax.set_ylabel("validation success (%)")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    finish_figure(fig, path)
