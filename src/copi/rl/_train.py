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

from copi._files import regular_file, write_text
from copi.baselines import MAX_LAYERS, MAX_WIDTH, PolicyWeights, PPOAgent, save_policy
from copi.envs.local_policy import LocalPolicyEnv, Reward
from copi.errors import CopiError, Interrupted, InvalidArgumentError
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


MAX_SEED = 2**32 - 1


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
        if isinstance(self.seed, bool) or not (isinstance(self.seed, int)
                                               and 0 <= self.seed <= MAX_SEED):
            raise InvalidArgumentError(f"seed must be an int in 0 .. {MAX_SEED:,} (the range "
                                       f"of the generators PPO seeds); got {self.seed!r}")
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
        most = MAX_LAYERS - 1  # the action layer is the policy file's last
        if not (1 <= len(self.net) <= most) or not all(
            isinstance(h, int) and not isinstance(h, bool) and 1 <= h <= MAX_WIDTH
            for h in self.net
        ):
            raise InvalidArgumentError(f"net must be 1 to {most} layer widths in 1 .. "
                                       f"{MAX_WIDTH}; got {self.net!r}")  # fmt: skip
        if not self.families or not self.levels:
            raise InvalidArgumentError("families and levels must each name at least one; got "
                                       f"families {self.families!r}, levels {self.levels!r}")

    @property
    def rollout(self) -> int:
        """Environment steps between two updates: PPO trains in whole rollouts."""
        return self.envs * self.n_steps

    @property
    def planned_steps(self) -> int:
        """The steps a run takes: ``steps`` rounded up to whole rollouts."""
        return -(-self.steps // self.rollout) * self.rollout

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
    resumed: Callable[[int], None] | None = None,
    command: str = "",
) -> dict[str, Any]:
    """Train PPO as ``config`` says and write the exported policy to ``output`` (and
    ``output`` with ``.json`` and ``.png``: the learning curve). With ``checkpoints``, the
    model is saved there every ``validate_every`` steps (weights and optimiser state as
    torch tensors, loaded with ``weights_only``: no pickle), and a rerun resumes from the
    last one (``resumed`` is told the steps it resumes at). ``progress(done, total)`` counts
    to :attr:`TrainConfig.planned_steps`. Returns the run's summary (steps, seconds, steps
    per second, curve)."""
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
        saved = _read_checkpoint(ckpt, config)
        if saved is not None:
            elapsed0 = _restore(model, vec, saved)
            curve = list(saved["meta"]["curve"])
            if resumed is not None:
                resumed(int(model.num_timesteps))
    if progress is not None:
        progress(int(model.num_timesteps), config.planned_steps)

    t0 = time.perf_counter()

    def snapshot() -> PolicyWeights:
        return export_policy(model, info={"algorithm": "PPO", **config.identity()})

    class Watch(BaseCallback):  # type: ignore[misc]
        """Progress at every step; validation (and a checkpoint) between rollouts, where
        the rollout buffer is empty, so that a resumed run goes on exactly as it would
        have."""

        def __init__(self) -> None:
            super().__init__()
            self.next = (model.num_timesteps // validate_every + 1) * validate_every

        def _on_step(self) -> bool:
            if progress is not None:
                progress(self.num_timesteps, config.planned_steps)
            return True

        def _on_rollout_start(self) -> None:
            if model.num_timesteps >= self.next:
                self.next = (model.num_timesteps // validate_every + 1) * validate_every
                record()

    def record() -> None:
        seconds = elapsed0 + time.perf_counter() - t0
        curve.append({"steps": int(model.num_timesteps), "seconds": round(seconds, 1),
                      "success": validation_success(snapshot(), config,
                                                    validation_episodes)})  # fmt: skip
        if ckpt is not None:
            _write_checkpoint(ckpt, model, vec, config, curve, seconds)

    left = config.steps - model.num_timesteps
    if left > 0:
        try:
            model.learn(total_timesteps=left, callback=Watch(), reset_num_timesteps=False,
                        progress_bar=False)  # fmt: skip
        except KeyboardInterrupt:
            done = f"{int(curve[-1]['steps']):,} steps checkpointed in {ckpt}; rerun the same " \
                "command to resume" if ckpt is not None and curve else (
                    "nothing saved (give --checkpoints DIR to resume an interrupted run)")
            raise Interrupted(done) from None
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


# -- checkpoints: what resumes a run exactly as it would have gone on --------------------


def _write_checkpoint(ckpt: Path, model: Any, vec: Any, config: TrainConfig,
                      curve: list[dict[str, float]], seconds: float) -> None:  # fmt: skip
    """Everything the run's future depends on, between two rollouts: the weights and the
    optimiser's state, every random generator (torch's, numpy's, Python's), and each
    environment's state (:meth:`LocalPolicyEnv.state`), as tensors (``last.pt``, read
    with ``weights_only``) and JSON (``last.json``); nothing pickled."""
    import random

    import torch

    envs = [e.state() for e in vec.envs]
    tensors = {
        "params": model.get_parameters(),
        "torch_rng": torch.get_rng_state(),
        "last_obs": torch.from_numpy(np.asarray(model._last_obs, dtype=np.float32).copy()),
        "episode_starts": torch.from_numpy(np.asarray(model._last_episode_starts,
                                                      dtype=np.float32).copy()),  # fmt: skip
        **{f"actions{i}": torch.from_numpy(s["actions"]) for i, s in enumerate(envs)},
    }
    kind, key, pos, has_gauss, cached = np.random.get_state()
    meta = {
        "config": config.identity(), "steps": int(model.num_timesteps),
        "updates": int(model._n_updates), "curve": curve, "seconds": seconds,
        "numpy_rng": [kind, np.asarray(key).tolist(), int(pos), int(has_gauss), float(cached)],
        "python_rng": json.loads(json.dumps(random.getstate())),
        "envs": [{"drawn_from": s["drawn_from"], "ended": s["ended"]} for s in envs],
    }
    torch.save(tensors, ckpt / "last.pt.tmp")
    os.replace(ckpt / "last.pt.tmp", ckpt / "last.pt")
    write_text(ckpt / "last.json", json.dumps(meta), "json")


def _bad(ckpt: Path, what: str) -> InvalidArgumentError:
    return InvalidArgumentError(f"{ckpt}: not a checkpoint of this training run ({what}); "
                                "use another --checkpoints directory")  # fmt: skip


def _read_checkpoint(ckpt: Path, config: TrainConfig) -> dict[str, Any] | None:
    """The checkpoint in ``ckpt`` of this run (None when there is none), every part
    checked: one clear line for a file that is not one, or of another run."""
    import torch

    state, meta_path = ckpt / "last.pt", ckpt / "last.json"
    if not state.exists() and not meta_path.exists():
        return None
    for path in (state, meta_path):
        regular_file(path, "checkpoint file", InvalidArgumentError)
    if meta_path.stat().st_size > 1 << 26 or state.stat().st_size > 1 << 31:
        raise _bad(ckpt, "a file larger than a checkpoint holds")
    try:
        meta = json.loads(meta_path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise _bad(ckpt, f"last.json is not JSON: {exc}") from None
    if not isinstance(meta, dict):
        raise _bad(ckpt, "last.json is not an object")
    same = {k: v for k, v in json.loads(json.dumps(config.identity())).items() if k != "steps"}
    saved = meta.get("config")
    if not isinstance(saved, dict) or {k: v for k, v in saved.items() if k != "steps"} != same:
        raise InvalidArgumentError(
            f"{ckpt} holds checkpoints of another training run; use another directory"
        )
    steps = meta.get("steps")
    if not (isinstance(steps, int) and not isinstance(steps, bool)
            and 0 <= steps <= config.steps + config.envs * config.n_steps):  # fmt: skip
        raise _bad(ckpt, f"it claims {steps!r} steps done, of a run of {config.steps:,}")
    curve = meta.get("curve")
    if not (isinstance(curve, list) and curve and all(
        isinstance(c, dict) and all(isinstance(c.get(k), int | float) and not
                                    isinstance(c.get(k), bool) and math.isfinite(c[k])
                                    for k in ("steps", "seconds", "success"))
        for c in curve) and curve[-1]["steps"] == steps):  # fmt: skip
        raise _bad(ckpt, "its learning curve is missing or does not end at its steps")
    seconds = meta.get("seconds")
    if not (isinstance(seconds, int | float) and math.isfinite(seconds) and seconds >= 0):
        raise _bad(ckpt, f"its wall time is {seconds!r}")
    envs = meta.get("envs")
    if not (isinstance(envs, list) and len(envs) == config.envs):
        raise _bad(ckpt, "it holds another number of environments")
    try:
        tensors = torch.load(state, weights_only=True, map_location="cpu")
    except Exception as exc:  # torch raises many kinds for a file that is not one
        raise _bad(ckpt, f"last.pt cannot be read: {type(exc).__name__}") from None
    need = {"params", "torch_rng", "last_obs", "episode_starts",
            *(f"actions{i}" for i in range(config.envs))}  # fmt: skip
    if not isinstance(tensors, dict) or not need <= set(tensors):
        raise _bad(ckpt, "last.pt lacks parts of a checkpoint")
    def finite(value: Any, name: str) -> None:
        if isinstance(value, dict):
            for k, v in value.items():
                finite(v, f"{name}.{k}")
        elif isinstance(value, list | tuple):
            for k, v in enumerate(value):
                finite(v, f"{name}[{k}]")
        elif isinstance(value, torch.Tensor) and value.is_floating_point() and \
                not bool(torch.isfinite(value).all()):  # fmt: skip
            raise _bad(ckpt, f"{name} holds NaN or infinity")

    finite(tensors, "last.pt")
    return {"meta": meta, "tensors": tensors}


def _restore(model: Any, vec: Any, saved: dict[str, Any]) -> float:
    """The model, the random generators and the environments as ``saved``; returns the
    wall time already spent."""
    import random

    import torch

    meta, tensors, ckpt = saved["meta"], saved["tensors"], "the checkpoint"
    try:
        model.set_parameters(tensors["params"], exact_match=True)
        obs = np.stack([
            env.restore({"drawn_from": meta["envs"][i]["drawn_from"],
                         "actions": tensors[f"actions{i}"].numpy(),
                         "ended": meta["envs"][i].get("ended")})
            for i, env in enumerate(vec.envs)
        ])  # fmt: skip
        kind, key, pos, has_gauss, cached = meta["numpy_rng"]
        np.random.set_state((kind, np.asarray(key, dtype=np.uint32), pos, has_gauss, cached))
        version, inner, gauss = meta["python_rng"]
        random.setstate((version, tuple(inner), gauss))
        torch.set_rng_state(tensors["torch_rng"])
    except Exception as exc:  # a part of another shape or kind than the run's
        first = " ".join(str(exc).split())[:160]
        raise InvalidArgumentError(f"{ckpt} does not fit this run ({type(exc).__name__}: "
                                   f"{first}); use another --checkpoints directory") from None
    model._last_obs = tensors["last_obs"].numpy().copy()
    if not np.array_equal(obs, model._last_obs):
        raise InvalidArgumentError(f"{ckpt}: its environments do not replay to the state it "
                                   "recorded; use another --checkpoints directory")  # fmt: skip
    model._last_episode_starts = tensors["episode_starts"].numpy().astype(bool)
    model.num_timesteps = int(meta["steps"])
    model._n_updates = int(meta.get("updates", 0))
    return float(meta["seconds"])
